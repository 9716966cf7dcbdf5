#pragma once
// accelcal batch's units (cmd_batch.cpp) and the summary of their verdicts (batch_summary.cpp).
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "accelcal/acceptance.hpp"
#include "accelcal/calibration_file.hpp"
#include "commands.hpp"

namespace accelcal::cli::batch {

enum class UnitStatus { kPass, kFail, kError };
inline const char* Name(UnitStatus s) {
  return s == UnitStatus::kPass ? "pass" : s == UnitStatus::kFail ? "fail" : "error";
}

struct Unit {
  std::string id;
  std::vector<std::string> files;
  std::string problem;  // found before calibrating (a name the pattern does not match): an error
  // Filled by the run.
  int exit_status = -1;
  bool reused = false;
  std::string message;  // an error's, from calibrate's stderr
  UnitStatus status = UnitStatus::kError;
  std::optional<LoadedCalibration> calibration;
  std::string sha256;  // of the calibration's file, the bytes judged
  Acceptance acceptance;
};

std::string Joined(const std::vector<std::string>& items, const char* separator);

// The summary of a batch: summary.csv's text, summary.json's document, and how many units passed,
// failed and could not be calibrated.
struct Summary {
  std::string csv;
  nlohmann::ordered_json doc;
  std::array<int, 3> counts{0, 0, 0};
};

// Each unit's verdict against `limits` (without them, the calibration's own), then the summary:
// every unit in id order, so the same inputs give the same bytes.
Summary Summarise(const BatchArgs& args, const std::optional<AcceptanceLimits>& limits,
                  const std::string& limits_sha256, std::vector<Unit>* units);

}  // namespace accelcal::cli::batch
