// The sizes a Level 5 MAT-file claims, checked before libmatio reads it (mat_structure.hpp): a
// file of accelcal's writer and the same variable compressed pass and are read; a name, a
// dimension or a compressed variable claiming more than the file holds is refused, naming where,
// as are the inputs the fuzzer found (fuzz/regressions/file_log: libmatio took 4.2 GB for one).
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/mat_writer.hpp"
#include "io/mat_file.hpp"
#include "io/mat_structure.hpp"
#include "support/paths.hpp"

namespace accelcal::internal {
namespace {

std::string Write(const std::string& name, const std::string& bytes) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

// A 4 x 100 matrix "imu" (time, x, y, z per column), as simulate writes it.
std::string Matrix() {
  MatMatrixWriter writer("imu", 4, 100);
  std::string out = writer.Header();
  for (int k = 0; k < 100; ++k) {
    const double column[4] = {0.01 * k, 0.1 * k, -0.2, 9.81};
    out += writer.Column(column);
  }
  return out + writer.Finish();
}

void PutU32(std::string* bytes, std::size_t at, std::uint32_t v) {
  std::memcpy(&(*bytes)[at], &v, 4);
}

// The same file with its variable compressed (MATLAB 7's miCOMPRESSED: a zlib stream of the
// element), its inflated size `claim` bytes when given instead of the element's own.
std::string Compressed(std::uint32_t claim = 0) {
  std::string file = Matrix();
  std::string element = file.substr(128);
  if (claim != 0) PutU32(&element, 4, claim);
  uLongf n = compressBound(element.size());
  std::string z(n, '\0');
  EXPECT_EQ(compress(reinterpret_cast<Bytef*>(z.data()), &n,
                     reinterpret_cast<const Bytef*>(element.data()), element.size()),
            Z_OK);
  z.resize(n);
  std::string out = file.substr(0, 128);
  out += std::string("\x0f\x00\x00\x00", 4);
  out += std::string(4, '\0');
  PutU32(&out, 132, static_cast<std::uint32_t>(z.size()));
  return out + z;
}

TEST(MatStructure, WellFormedFilesPassAndAreRead) {
  for (const auto& [name, bytes] :
       {std::pair<std::string, std::string>{"plain.mat", Matrix()}, {"z.mat", Compressed()}}) {
    const std::string path = Write(name, bytes);
    EXPECT_EQ(CheckMatStructure(path), std::nullopt) << name;
    const MatTable t = ReadMatTable(path, "");
    EXPECT_EQ(t.rows, 100u) << name;
    EXPECT_TRUE(t.transposed) << name;
    EXPECT_EQ(t.At(99, 1), 0.1 * 99) << name;
  }
}

// From a hostile test: a variable whose name element is not text reads, through libmatio, as a
// variable named "", which it cannot find again: the refusal said "the variable  cannot be read",
// and inspect listed it as readable. Both now say why.
TEST(MatStructure, AVariableWithoutANameIsRefusedSayingSo) {
  std::string m = Matrix();
  PutU32(&m, 168, 9);  // the name element's type: doubles, not text
  const std::string path = Write("badname.mat", m);
  try {
    ReadMatTable(path, "");
    ADD_FAILURE() << "read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("has no name"), std::string::npos) << e.what();
  }
}

TEST(MatStructure, ClaimsBeyondTheFileAreRefusedWhereTheyAre) {
  // The matrix's tag (8 bytes at 128), flags (16), dimensions (16), then the name's tag at 168.
  std::string name = Matrix();
  PutU32(&name, 172, 0xffff0003u);
  std::optional<std::string> why = CheckMatStructure(Write("name.mat", name));
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("an element of 4294901763 bytes where its matrix holds"), std::string::npos)
      << *why;
  EXPECT_NE(why->find("(at byte 168)"), std::string::npos) << *why;
  // One more column claimed than the data holds.
  std::string dims = Matrix();
  PutU32(&dims, 164, 101);
  why = CheckMatStructure(Write("dims.mat", dims));
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("a matrix of 404 values whose data holds 3200 bytes of type 9"),
            std::string::npos)
      << *why;
  // The file cut inside its data.
  why = CheckMatStructure(Write("cut.mat", Matrix().substr(0, 1000)));
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("cut short"), std::string::npos) << *why;
  // A compressed variable whose element claims 10 MB it does not inflate to.
  why = CheckMatStructure(Write("claim.mat", Compressed(10u << 20)));
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("inflated"), std::string::npos) << *why;
  // A compressed variable damaged: its stream's check fails.
  std::string damaged = Compressed();
  damaged[damaged.size() - 40] ^= 0x55;
  why = CheckMatStructure(Write("damaged.mat", damaged));
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("compressed variable"), std::string::npos) << *why;
  // A compressed variable the file ends inside, said as a sentence.
  why = CheckMatStructure(Write("ends.mat", Compressed().substr(0, 200)));
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("a compressed variable whose zlib stream runs past the end of the file"),
            std::string::npos)
      << *why;
  // Through the reader: an InputError naming the file.
  try {
    ListMatVariables(Write("name.mat", name));
    ADD_FAILURE() << "read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("corrupt or cut short"), std::string::npos) << e.what();
  }
}

// A compressed uint8 matrix "imu" of `rows` x 4 zeros: `rows` x 4 bytes in a file of a thousandth
// of that (zlib's best ratio).
std::string ByteBomb(std::uint32_t rows) {
  std::string element;
  const auto put = [&](std::uint32_t v) { element.append(reinterpret_cast<const char*>(&v), 4); };
  const std::uint32_t values = rows * 4;
  put(14);  // miMATRIX
  put(16 + 16 + 8 + 8 + (values + 7) / 8 * 8);
  put(6), put(8), put(9), put(0);                        // array flags: mxUINT8_CLASS
  put(5), put(8), put(rows), put(4);                     // dimensions
  put(3u << 16 | 1), element += "imu", element += '\0';  // the name, in the small format
  put(2), put(values);                                   // miUINT8
  element.append((values + 7) / 8 * 8, '\0');
  uLongf n = compressBound(element.size());
  std::string z(n, '\0');
  EXPECT_EQ(compress2(reinterpret_cast<Bytef*>(z.data()), &n,
                      reinterpret_cast<const Bytef*>(element.data()), element.size(), 9),
            Z_OK);
  z.resize(n);
  std::string out = Matrix().substr(0, 128);
  out += std::string("\x0f\x00\x00\x00", 4);
  const auto size = static_cast<std::uint32_t>(z.size());
  out.append(reinterpret_cast<const char*>(&size), 4);
  return out + z;
}

TEST(MatStructure, ASmallFileCannotAskForMoreThanACalibrationReads) {
  // A 32 kB file of 2^25 + 4 byte values (a 1 MB one of 2^28 had taken 2.26 GB and 26 s: the
  // bytes as libmatio read them, then as doubles): refused before libmatio reads its data.
  const std::string path = Write("bomb.mat", ByteBomb((1u << 23) + 1));
  EXPECT_LT(ReadFileToString(path).size(), std::size_t{64} << 10);
  try {
    ReadMatTable(path, "");
    ADD_FAILURE() << "read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the variable imu has 8388609 x 4 values, more than "
                                         "the 33554432 accelcal reads from a MAT-file"),
              std::string::npos)
        << e.what();
  }
  // At the bound, read, each value where libmatio has it (a byte each, not a double).
  const MatTable t = ReadMatTable(Write("bound.mat", ByteBomb(1u << 23)), "");
  EXPECT_EQ(t.rows, std::size_t{1} << 23);
  EXPECT_EQ(t.columns, 4u);
  EXPECT_EQ(t.At(t.rows - 1, 3), 0.0);
}

// A compressed variable whose matrix claims `claim` bytes of doubles, its stream `zeros` zero
// bytes after the element's headers (deflated as a stream: no buffer of that size).
std::string DoubleBomb(std::uint32_t claim, std::uint64_t zeros) {
  std::string head;
  const auto put = [&](std::uint32_t v) { head.append(reinterpret_cast<const char*>(&v), 4); };
  put(14), put(48 + claim);
  put(6), put(8), put(6), put(0);  // mxDOUBLE_CLASS
  put(5), put(8), put(claim / 32), put(4);
  put(3u << 16 | 1), head += "imu", head += '\0';
  put(9), put(claim);  // miDOUBLE
  z_stream z{};
  EXPECT_EQ(deflateInit(&z, 1), Z_OK);
  std::string out;
  const std::string block(1 << 20, '\0');
  std::string buffer(1 << 20, '\0');
  const auto deflate_some = [&](const std::string& in, std::size_t n, int flush) {
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
    z.avail_in = static_cast<uInt>(n);
    do {
      z.next_out = reinterpret_cast<Bytef*>(buffer.data());
      z.avail_out = static_cast<uInt>(buffer.size());
      deflate(&z, flush);
      out.append(buffer.data(), buffer.size() - z.avail_out);
    } while (z.avail_out == 0);
  };
  deflate_some(head, head.size(), Z_NO_FLUSH);
  for (std::uint64_t left = zeros; left > 0; left -= std::min<std::uint64_t>(left, block.size())) {
    deflate_some(block, std::min<std::uint64_t>(left, block.size()), Z_NO_FLUSH);
  }
  deflate_some(block, 0, Z_FINISH);
  deflateEnd(&z);
  std::string file = Matrix().substr(0, 128);
  file += std::string("\x0f\x00\x00\x00", 4);
  const auto size = static_cast<std::uint32_t>(out.size());
  file.append(reinterpret_cast<const char*>(&size), 4);
  return file + out;
}

TEST(MatStructure, InflatingIsBoundedPerVariableAndPerFile) {
  // A 1 MB file inflating to 1 GiB, the bound before, had taken 22 s and 2.26 GB: refused when
  // its inflated bytes pass 256 MiB, saying so (not "an element is cut short").
  std::optional<std::string> why = CheckMatStructure(
      Write("1g.mat", DoubleBomb(1u << 30, (std::uint64_t{1} << 28) + (1u << 20))));
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("a compressed variable whose data inflate past 256 MiB"), std::string::npos)
      << *why;
  // Five variables of 240 MiB each, under the bound each, 1.2 GiB in all from 1.2 MB.
  const std::string one = DoubleBomb(240u << 20, 240u << 20);
  std::string five = one;
  for (int i = 0; i < 4; ++i) five += one.substr(128);
  why = CheckMatStructure(Write("five.mat", five));
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("compressed variables that inflate past 1024 MiB in all"), std::string::npos)
      << *why;
}

TEST(MatStructure, AnEmptyMatrixIsRefusedByName) {
  // Found by the fuzzer: a 262294 x 0 matrix was read as rows of nothing (the first value of an
  // empty vector).
  MatMatrixWriter writer("imu", 4, 0);
  const std::string path = Write("empty.mat", writer.Header() + writer.Finish());
  EXPECT_EQ(CheckMatStructure(path), std::nullopt);
  try {
    ReadMatTable(path, "");
    ADD_FAILURE() << "read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the variable imu is 4x0 double: it holds no values"),
              std::string::npos)
        << e.what();
  }
}

TEST(MatStructure, TheFuzzersFindingsAreRefused) {
  for (const char* name : {"dims-claim-4gb.mat", "name-claim-4gb.mat"}) {
    const std::optional<std::string> why =
        CheckMatStructure(std::string(ACCELCAL_SOURCE_DIR) + "/fuzz/regressions/file_log/" + name);
    ASSERT_TRUE(why) << name;
    EXPECT_NE(why->find("where its matrix holds"), std::string::npos) << *why;
  }
}

TEST(MatStructure, DataInTheSmallFormatHoldsWhatTheDimensionsClaim) {
  // Found by fuzz_file_schema (issue 47): a cell's double matrix of 0xdfe6a07a x 1 values whose
  // data is one byte in the small format (its value in the tag): unchecked, libmatio asked for
  // 30 GB.
  const std::optional<std::string> why = CheckMatStructure(
      std::string(ACCELCAL_SOURCE_DIR) + "/fuzz/regressions/file_log/small-data-claim-30gb.mat");
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("a matrix of 3756433530 values whose data holds 1 bytes of type 5"),
            std::string::npos)
      << *why;
}

TEST(MatStructure, TheVersionFieldNotTheTextSaysHowItIsRead) {
  // Found by the fuzzer (CI, 2026-11-28): "MATLAB 7.3" as text over a Level 5 version field.
  // libmatio read it as Level 5 while the check took it for HDF5 and let it pass, and libmatio
  // then asked for 4 GB (8 TB in another input) from its dimensions.
  const std::string dir = std::string(ACCELCAL_SOURCE_DIR) + "/fuzz/regressions/file_log/";
  const std::optional<std::string> why = CheckMatStructure(dir + "text-7.3-version-5.mat");
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("where its matrix holds"), std::string::npos) << *why;
  // A version that is neither Level 5 nor 7.3.
  std::string bytes = ReadFileToString(dir + "text-7.3-version-5.mat");
  bytes[124] = 3;
  const std::string path = Write("version-3.mat", bytes);
  EXPECT_EQ(CheckMatStructure(path).value_or(""),
            "a MAT-file of version 0x0103 (0x0100: Level 5; 0x0200: 7.3)");
}

}  // namespace
}  // namespace accelcal::internal
