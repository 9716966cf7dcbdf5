// Issue 16: a calibration file with `"format": -0.7069` (or a key given twice) reached `apply`
// and `export` as an uncaught exception ("internal error"). Here every value of every bundled
// seed file is replaced by a value of every type and by hostile numbers, removed, and its key
// duplicated: each result is either read (and then every export and the report work or refuse
// with DataError / InputError) or refused with InputError naming the file. A duplicated key is
// always refused. fuzz/fuzz_calibration_keys.cpp chains such mutations at random.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/export.hpp"
#include "accelcal/report.hpp"
#include "support/json_mutations.hpp"
#include "support/paths.hpp"
#include "support/use_calibration.hpp"

namespace accelcal::test {
namespace {

namespace fs = std::filesystem;
constexpr bool kSanitized = ACCELCAL_TESTS_SANITIZED;

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// "" when the text is read and used, or refused as it should be; else what went wrong.
std::string Outcome(const std::string& text, bool* read) {
  *read = false;
  LoadedCalibration cal;
  try {
    cal = ParseCalibrationJson(text, "mutated.json");
  } catch (const InputError& e) {
    if (std::string(e.what()).rfind("mutated.json", 0) != 0) {
      return std::string("an InputError not naming the file: ") + e.what();
    }
    return "";
  } catch (const std::exception& e) {
    return std::string("reading: ") + typeid(e).name() + ": " + e.what();
  }
  *read = true;
  try {
    UseCalibration(cal, text, "mutated.json");
  } catch (const std::exception& e) {
    return std::string("exporting or reporting: ") + typeid(e).name() + ": " + e.what();
  }
  return "";
}

bool InsideAMiddleElement(const nlohmann::json& doc, nlohmann::json::json_pointer at) {
  for (; !at.empty(); at = at.parent_pointer()) {
    const nlohmann::json& parent = doc.at(at.parent_pointer());
    if (!parent.is_array()) continue;
    const std::size_t i = std::stoul(at.back());
    if (i >= 1 && i + 1 < parent.size()) return true;
  }
  return false;
}

TEST(CalibrationKeys, EveryValueOfEverySeedMutatedIsReadOrRefusedByName) {
  const fs::path seeds = fs::path(ACCELCAL_SOURCE_DIR) / "fuzz/corpus/calibration_file";
  int files = 0, mutations = 0, read = 0;
  std::size_t case_index = 0;
  for (const auto& entry : fs::directory_iterator(seeds)) {
    const nlohmann::json doc = nlohmann::json::parse(ReadText(entry.path()));
    ++files;
    std::vector<nlohmann::json::json_pointer> places;
    CollectPointers(doc, nlohmann::json::json_pointer(), &places);
    for (const auto& at : places) {
      // Arrays (positions, matrix rows): the first element and the last (and what they hold)
      // stand for the rest, whose handling is the same code.
      if (InsideAMiddleElement(doc, at)) continue;
      std::vector<std::pair<Mutation, nlohmann::json>> cases = {{Mutation::kErase, nullptr}};
      for (const nlohmann::json& v : HostileValues()) {
        cases.emplace_back(Mutation::kReplace, v);
      }
      cases.emplace_back(Mutation::kDuplicateKey, 0);
      for (const auto& [mutation, value] : cases) {
        // Under the sanitizers (ten times slower) every seventh case, all places still visited.
        if (kSanitized && (case_index++ % 7) != 0) continue;
        const std::string text = Mutate(doc, at, mutation, value);
        if (text.empty()) continue;
        ++mutations;
        bool was_read = false;
        const std::string problem = Outcome(text, &was_read);
        EXPECT_EQ(problem, "") << entry.path().filename() << " " << at.to_string() << " "
                               << static_cast<int>(mutation) << " " << value.dump();
        if (mutation == Mutation::kDuplicateKey) {
          EXPECT_FALSE(was_read) << "a duplicated key was accepted: " << at.to_string();
        }
        read += was_read;
      }
    }
  }
  // Three of version 1, four of version 2 (two with a gyroscope: one with its offsets over
  // temperature, its lag and the Earth rate, records a file may lack).
  EXPECT_EQ(files, 7);
  // Most mutations of values the reader does not check (comments, figures it recomputes) are
  // still read: the test exercises the exports and the report, not only the refusals.
  EXPECT_GT(mutations, kSanitized ? 200 : 1000);
  EXPECT_GT(read, mutations / 10);
  std::printf("%d files, %d mutated documents, %d read\n", files, mutations, read);
}

// Found by fuzz_calibration_keys (fuzz/regressions/calibration_keys): an iteration count of
// -1e308 was converted to an int (undefined behaviour; the sanitizers stop there).
TEST(CalibrationKeys, AnIterationCountBeyondIntIsShownAsUnknown) {
  const fs::path seed = fs::path(ACCELCAL_SOURCE_DIR) / "fuzz/corpus/calibration_file/linear.json";
  nlohmann::json doc = nlohmann::json::parse(ReadText(seed));
  for (const nlohmann::json& count :
       {nlohmann::json(-1e308), nlohmann::json(1e300), nlohmann::json(2.5), nlohmann::json("7")}) {
    doc["solver"]["iterations"] = count;
    const std::string html =
        RenderReport({ParseCalibrationJson(doc.dump(), "x.json"), "x.json", nullptr, {}});
    EXPECT_NE(html.find("? iterations"), std::string::npos) << count;
  }
  doc["solver"]["iterations"] = 12;
  EXPECT_NE(RenderReport({ParseCalibrationJson(doc.dump(), "x.json"), "x.json", nullptr, {}})
                .find("12 iterations"),
            std::string::npos);
}

}  // namespace
}  // namespace accelcal::test
