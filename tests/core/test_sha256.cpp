// SHA-256 (sha256.hpp): the test vectors of FIPS 180-4's examples, a bundled recording against
// sha256sum, and the SHA-extensions block function against the portable one on every length that
// crosses a block boundary, fed whole and in pieces.
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "accelcal/sha256.hpp"
#include "support/paths.hpp"

namespace accelcal {
namespace {

TEST(Sha256, KnownAnswers) {
  // NIST's examples (csrc.nist.gov, "SHA-256" example values): one block, two blocks, and the
  // empty message; one million 'a' (FIPS 180-2 appendix B.3).
  EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(Sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(Sha256Hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  for (const char* text : {"", "abc", "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"}) {
    EXPECT_EQ(internal::Sha256HexPortable(text), Sha256Hex(text)) << text;
  }
}

TEST(Sha256, BundledRecordingAsSha256sumHasIt) {
  std::ifstream in(std::string(ACCELCAL_DATA_DIR) + "/imutk-xsens-mti/xsens_acc.mat",
                   std::ios::binary);
  ASSERT_TRUE(in);
  std::stringstream bytes;
  bytes << in.rdbuf();
  // `sha256sum data/imutk-xsens-mti/xsens_acc.mat`
  EXPECT_EQ(Sha256Hex(bytes.str()),
            "335a234736ff4dd8741118283d5d4cd389ac54b04d00e6cd8d48ca3e532b7510");
}

std::string Hex(const std::array<std::uint8_t, 32>& digest) {
  std::string hex;
  for (const std::uint8_t b : digest) {
    static const char kDigits[] = "0123456789abcdef";
    hex += kDigits[b >> 4];
    hex += kDigits[b & 15];
  }
  return hex;
}

TEST(Sha256, BothBlockFunctionsAndAnySplitAgree) {
  // On a CPU without SHA extensions (or under valgrind, whose CPU has none) both sides are the
  // portable function and only the splits are compared; say which.
  std::printf("SHA extensions in use: %s\n", internal::Sha256UsesShaExtensions() ? "yes" : "no");
  std::mt19937 random(17);
  std::string message;
  for (int i = 0; i < 300; ++i) message += static_cast<char>(random() & 0xff);
  for (std::size_t length = 0; length <= message.size(); ++length) {
    const std::string_view part(message.data(), length);
    const std::string expected = internal::Sha256HexPortable(part);
    ASSERT_EQ(Sha256Hex(part), expected) << length;
    Sha256 pieces;  // the same bytes in pieces of 1 to 70 bytes
    for (std::size_t at = 0; at < length;) {
      const std::size_t take = std::min<std::size_t>(length - at, 1 + random() % 70);
      pieces.Update(part.data() + at, take);
      at += take;
    }
    ASSERT_EQ(Hex(pieces.Digest()), expected) << length;
  }
  Sha256 spent;
  spent.Digest();
  EXPECT_THROW(spent.Digest(), std::logic_error);
  EXPECT_THROW(spent.Update("a", 1), std::logic_error);
}

}  // namespace
}  // namespace accelcal
