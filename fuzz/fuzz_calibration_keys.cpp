// libFuzzer harness: calibration files as users' tools damage them. Starts from the valid seed
// files (fuzz/corpus/calibration_file) and applies 1 to 4 mutations chosen by the input: a value
// replaced (by a hostile value of any type, a number from the input's bytes, or a string from
// them), removed, or its key duplicated (tests/support/json_mutations.hpp). Each document is read
// and, when accepted, exported in every format and rendered as a report. Accepted failures:
// InputError (bad file), DataError (a format that cannot express the calibration). Anything
// else (an uncaught nlohmann::json exception: "internal error" in the tool) is a finding.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "support/json_mutations.hpp"
#include "support/use_calibration.hpp"

namespace {

struct Seed {
  nlohmann::json doc;
  std::vector<nlohmann::json::json_pointer> places;
};

const std::vector<Seed>& Seeds() {
  static const std::vector<Seed> seeds = [] {
    std::vector<Seed> out;
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(
             std::filesystem::path(ACCELCAL_SOURCE_DIR) / "fuzz/corpus/calibration_file")) {
      files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());  // the same order on every machine
    for (const auto& path : files) {
      std::ifstream in(path, std::ios::binary);
      std::stringstream ss;
      ss << in.rdbuf();
      Seed seed;
      seed.doc = nlohmann::json::parse(ss.str());
      accelcal::test::CollectPointers(seed.doc, nlohmann::json::json_pointer(), &seed.places);
      out.push_back(std::move(seed));
    }
    return out;
  }();
  return seeds;
}

// Reads the fuzzer's bytes in order; zeros when they run out.
struct Bytes {
  const std::uint8_t* data;
  std::size_t size;
  std::uint64_t Take(int n) {
    std::uint64_t v = 0;
    for (int i = 0; i < n; ++i) {
      v = (v << 8) | (size > 0 ? *data : 0);
      if (size > 0) ++data, --size;
    }
    return v;
  }
};

nlohmann::json Value(Bytes* in) {
  const std::uint64_t kind = in->Take(1);
  static const std::vector<nlohmann::json> hostile = accelcal::test::HostileValues();
  if (kind < 160) return hostile[kind % hostile.size()];
  if (kind < 208) {  // any double the bytes spell, finite ones only (JSON has no others)
    const std::uint64_t bits = in->Take(8);
    double v;
    std::memcpy(&v, &bits, sizeof v);
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(-0.7069);
  }
  if (kind < 240) return static_cast<std::int64_t>(in->Take(8));
  std::string text;
  for (std::uint64_t n = in->Take(1) % 24; n > 0; --n) text += static_cast<char>(in->Take(1));
  nlohmann::json value = text;
  try {
    (void)value.dump();
  } catch (const nlohmann::json::exception&) {  // not UTF-8: nlohmann refuses to dump it
    return "bytes";
  }
  return value;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using accelcal::test::Mutation;
  Bytes in{data, size};
  const std::vector<Seed>& seeds = Seeds();
  const Seed& seed = seeds[in.Take(1) % seeds.size()];
  std::string text = seed.doc.dump();
  nlohmann::json doc = seed.doc;
  const int count = 1 + static_cast<int>(in.Take(1) % 4);
  for (int m = 0; m < count; ++m) {
    // Places of the seed: a mutation may remove the place of a later one (then skipped).
    const auto& at = seed.places[in.Take(2) % seed.places.size()];
    const std::uint64_t op = in.Take(1) % 8;
    const Mutation mutation = op < 6    ? Mutation::kReplace
                              : op == 6 ? Mutation::kErase
                                        : Mutation::kDuplicateKey;
    const nlohmann::json value = Value(&in);
    const std::string mutated = accelcal::test::Mutate(doc, at, mutation, value);
    if (mutated.empty()) continue;
    text = mutated;
    if (mutation == Mutation::kDuplicateKey) break;  // text only from here on
    doc = nlohmann::json::parse(text);
  }
  accelcal::test::ReadAndUseCalibration(text, "fuzz.json");
  return 0;
}
