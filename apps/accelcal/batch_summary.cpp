// accelcal batch's summary (batch_units.hpp): each unit's verdict against the limits, and every
// unit's row in summary.csv and summary.json.
#include <algorithm>
#include <map>

#include "accelcal/version.hpp"
#include "batch_units.hpp"
#include "cli_common.hpp"

namespace accelcal::cli::batch {
namespace {

using Json = nlohmann::ordered_json;

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

std::string WorstFinding(const LoadedCalibration& cal) {
  std::optional<Severity> worst;
  for (const Finding& f : cal.diagnostics.value_or(std::vector<Finding>())) {
    if (!worst || f.severity > *worst) worst = f.severity;
  }
  return worst ? std::string(ToString(*worst)) : "none";
}

}  // namespace

std::string Joined(const std::vector<std::string>& items, const char* separator) {
  std::string text;
  for (const std::string& s : items) text += (text.empty() ? "" : separator) + s;
  return text;
}

Summary Summarise(const BatchArgs& args, const std::optional<AcceptanceLimits>& limits,
                  const std::string& limits_sha256, std::vector<Unit>* all) {
  std::vector<Unit>& units = *all;
  Summary out;
  std::vector<std::string> columns;  // the quantities of all units, in their order of first use
  for (Unit& u : units) {
    if (!u.problem.empty()) {
      u.message = u.problem;
      continue;
    }
    if (!u.calibration) continue;
    if (limits) {
      u.acceptance = Accept(*u.calibration, *limits);
    } else {
      AcceptanceLimits none;
      none.max_severity = Severity::kFailure;  // only the calibration's own verdict
      u.acceptance = Accept(*u.calibration, none);
    }
    u.status = u.acceptance.passed ? UnitStatus::kPass : UnitStatus::kFail;
    for (const CalibrationQuantity& q : CalibrationQuantities(*u.calibration)) {
      if (std::find(columns.begin(), columns.end(), q.name) == columns.end()) {
        columns.push_back(q.name);
      }
    }
  }
  std::array<int, 3>& counts = out.counts;
  Json& doc = out.doc;
  doc["format"] = "accelcal-batch-summary";
  doc["version"] = 1;
  doc["accelcal_version"] = std::string(Version());
  if (limits) {
    Json l;
    l["file"] = args.limits;
    l["sha256"] = limits_sha256;
    if (!limits->part.empty()) l["part"] = limits->part;
    doc["limits"] = l;
  } else {
    doc["limits"] = nullptr;
  }
  doc["options"] = GivenOptionsJson(args.calibrate_options);
  Json& rows = doc["units"] = Json::array();
  std::string& csv = out.csv;
  csv = "unit,status,failed,files,verdict,worst_finding,message,sha256";
  for (const std::string& c : columns) csv += "," + c + "," + c + ".sigma";
  csv += "\n";
  for (const Unit& u : units) {
    ++counts[static_cast<int>(u.status)];
    Json row;
    row["unit"] = u.id;
    row["status"] = Name(u.status);
    row["files"] = u.files;
    // What store add checks the unit's file against: the bytes judged here.
    row["sha256"] = u.calibration ? Json(u.sha256) : Json();
    std::vector<std::string> failed;
    Json failures = Json::array();
    for (const LimitFailure& f : u.acceptance.failures) {
      failed.push_back(f.text);
      Json jf;
      jf["quantity"] = f.quantity;
      jf["value"] = f.value ? Json(*f.value) : Json();
      jf["text"] = f.text;
      if (f.line > 0) jf["line"] = f.line;
      failures.push_back(jf);
    }
    row["failed"] = failures;
    std::map<std::string, const CalibrationQuantity*> by_name;
    std::vector<CalibrationQuantity> quantities;
    if (u.calibration) {
      quantities = CalibrationQuantities(*u.calibration);
      for (const CalibrationQuantity& q : quantities) by_name[q.name] = &q;
      row["verdict"] = u.calibration->verdict;
      row["worst_finding"] = WorstFinding(*u.calibration);
      Json findings = Json::array();
      for (const Finding& f : u.calibration->diagnostics.value_or(std::vector<Finding>())) {
        findings.push_back({{"code", f.code}, {"severity", std::string(ToString(f.severity))}});
      }
      row["findings"] = findings;
      Json q = Json::object();
      for (const CalibrationQuantity& c : quantities) {
        q[c.name] = {
            {"value", c.value}, {"sigma", c.sigma ? Json(*c.sigma) : Json()}, {"unit", c.unit}};
      }
      row["quantities"] = q;
    } else {
      row["message"] = u.message;
    }
    rows.push_back(row);
    csv += CsvField(u.id) + "," + Name(u.status) + "," + CsvField(Joined(failed, "; ")) + "," +
           CsvField(Joined(u.files, ";")) + "," +
           (u.calibration ? u.calibration->verdict + "," + WorstFinding(*u.calibration) : ",") +
           "," + CsvField(u.message) + "," + (u.calibration ? u.sha256 : "");
    for (const std::string& c : columns) {
      const auto it = by_name.find(c);
      if (it == by_name.end()) {
        csv += ",,";
      } else {
        csv += "," + FormatNumber(it->second->value) + "," +
               (it->second->sigma ? FormatNumber(*it->second->sigma) : "");
      }
    }
    csv += "\n";
  }
  doc["counts"] = {
      {"units", units.size()}, {"pass", counts[0]}, {"fail", counts[1]}, {"error", counts[2]}};
  return out;
}

}  // namespace accelcal::cli::batch
