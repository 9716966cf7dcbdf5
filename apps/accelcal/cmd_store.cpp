// accelcal store add|get|list: a directory of calibrations by unit and date with an index.
//   STORE/index.json                     every calibration: unit, date, file, SHA-256, verdict,
//                                        and its change against the unit's calibration before it
//   STORE/units/ID/DATE_SHA.json         the calibration files, as they were given
// A calibration added is compared with the unit's latest one of an earlier or the same date
// (calibration_change.hpp). Adding is locked (flock on STORE/.lock), every file is checked before
// anything is written, the files are written before the index, and the index is replaced whole.
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>

#include <fcntl.h>

#include "accelcal/calibration_change.hpp"
#include "accelcal/calibration_file.hpp"
#include "accelcal/json_text.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/sha256.hpp"
#include "cli_common.hpp"
#include "commands.hpp"
#include "output.hpp"

namespace accelcal::cli {
namespace {

using Json = nlohmann::ordered_json;

struct Entry {
  std::string unit, date, file, sha256, verdict, source;
  Json change;  // null for a unit's first calibration
};

void MakeDirectory(const std::string& path) {
  if (::mkdir(path.c_str(), 0777) != 0 && errno != EEXIST) {
    throw OutputError(path + ": cannot create the directory: " + std::strerror(errno));
  }
  if (!IsDirectory(path)) throw OutputError(path + ": exists and is not a directory");
}

std::string IndexPath(const std::string& store) { return store + "/index.json"; }

// The index, or none when the store is new; InputError for one that is not a store's.
std::vector<Entry> ReadIndex(const std::string& store) {
  const std::string path = IndexPath(store);
  if (::access(path.c_str(), F_OK) != 0) return {};
  std::vector<Entry> entries;
  try {
    const Json doc = Json::parse(ReadFileToString(path, kMaxSmallFileBytes));
    if (doc.at("format") != "accelcal-store" || doc.at("version") != 1) {
      throw InputError(path, 0, "not an accelcal store's index (format accelcal-store, version 1)");
    }
    for (const Json& e : doc.at("entries")) {
      entries.push_back({e.at("unit").get<std::string>(), e.at("date").get<std::string>(),
                         e.at("file").get<std::string>(), e.at("sha256").get<std::string>(),
                         e.at("verdict").get<std::string>(), e.at("source").get<std::string>(),
                         e.at("change")});
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, 0, std::string("not an accelcal store's index: ") + e.what());
  }
  return entries;
}

std::string IndexText(const std::vector<Entry>& entries) {
  Json doc;
  doc["format"] = "accelcal-store";
  doc["version"] = 1;
  Json& list = doc["entries"] = Json::array();
  for (const Entry& e : entries) {
    list.push_back({{"unit", e.unit},
                    {"date", e.date},
                    {"file", e.file},
                    {"sha256", e.sha256},
                    {"verdict", e.verdict},
                    {"source", e.source},
                    {"change", e.change}});
  }
  return JsonText(doc);
}

// Today's date in UTC, YYYY-MM-DD.
std::string Today() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[16];
  std::strftime(text, sizeof text, "%Y-%m-%d", &utc);
  return text;
}

// The store's lock, held while it lives.
class StoreLock {
 public:
  explicit StoreLock(const std::string& store) {
    const std::string path = store + "/.lock";
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0666);
    if (fd_ < 0 || ::flock(fd_, LOCK_EX) != 0) {
      throw OutputError(path + ": cannot lock the store: " + std::strerror(errno));
    }
  }
  ~StoreLock() { ::close(fd_); }
  StoreLock(const StoreLock&) = delete;
  StoreLock& operator=(const StoreLock&) = delete;

 private:
  int fd_ = -1;
};

struct Candidate {
  std::string unit, source, text, date;
  LoadedCalibration cal;
};

// The calibrations to add: each file given (of --unit), and the passing units of each batch
// directory given (their ids from its summary).
std::vector<Candidate> Candidates(const StoreArgs& args, int* skipped) {
  std::vector<Candidate> out;
  const auto take = [&](const std::string& unit, const std::string& path) {
    Candidate c;
    c.unit = unit;
    c.source = path;
    c.text = ReadFileToString(path, kMaxSmallFileBytes);
    c.cal = ParseCalibrationJson(c.text, path);
    c.date = !c.cal.provenance.date.empty() ? c.cal.provenance.date
             : !args.date.empty()           ? args.date
                                            : Today();
    out.push_back(std::move(c));
  };
  for (const std::string& item : args.items) {
    if (!IsDirectory(item)) {
      if (args.unit.empty()) {
        throw UsageError(item +
                         ": give its unit with --unit (a batch's directory names its units)");
      }
      take(args.unit, item);
      continue;
    }
    const std::string summary = item + "/summary.json";
    std::vector<std::pair<std::string, bool>> units;  // id, passed
    try {
      const Json doc = Json::parse(ReadFileToString(summary, kMaxSmallFileBytes));
      if (doc.at("format") != "accelcal-batch-summary") throw std::runtime_error("its format");
      for (const Json& row : doc.at("units")) {
        units.emplace_back(row.at("unit").get<std::string>(), row.at("status") == "pass");
      }
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw InputError(summary, 0, std::string("not a batch's summary: ") + e.what());
    }
    for (const auto& [unit, passed] : units) {
      if (!passed) {
        ++*skipped;
        continue;
      }
      if (!args.unit.empty() && unit != args.unit) continue;
      if (const std::string why = UnitIdProblem(unit); !why.empty()) {
        throw InputError(summary, 0, why);
      }
      take(unit, item + "/units/" + unit + "/calibration.json");
    }
  }
  return out;
}

// The comparison of `later` with `earlier` as the index records it.
Json ChangeJson(const Entry& earlier, const CalibrationChange& c) {
  const auto sensor = [](const ParameterChange& p) {
    Json j;
    j["chi2"] = p.chi2;
    j["dof"] = p.dof;
    j["p"] = p.p;
    j["noise_dof"] = p.noise_dof ? Json(*p.noise_dof) : Json();
    std::vector<std::pair<std::string, double>> z = p.z;
    std::sort(z.begin(), z.end(),
              [](const auto& a, const auto& b) { return std::abs(a.second) > std::abs(b.second); });
    Json largest = Json::array();
    for (std::size_t i = 0; i < z.size() && i < 3; ++i) {
      largest.push_back({{"parameter", z[i].first}, {"z", z[i].second}});
    }
    j["largest"] = largest;
    return j;
  };
  Json j;
  j["against"] = earlier.file;
  j["against_date"] = earlier.date;
  j["compatible"] = c.compatible;
  j["accelerometer"] = sensor(c.accelerometer);
  j["accelerometer_scale"] = sensor(c.accelerometer_scale);
  j["accelerometer_bias"] = sensor(c.accelerometer_bias);
  j["gyroscope"] = c.gyroscope ? sensor(*c.gyroscope) : Json();
  if (!c.gyroscope_note.empty()) j["note"] = c.gyroscope_note;
  return j;
}

std::string ChangeText(const Json& change) {
  if (change.is_null()) return "the unit's first calibration";
  if (change.contains("comparable") && !change["comparable"].get<bool>()) {
    return "not compared with " + change["against_date"].get<std::string>() + ": " +
           change["reason"].get<std::string>();
  }
  const Json& a = change["accelerometer"];
  std::string text = Format("%s %s (chi2 %.3g for %d parameters, p %.2g",
                            change["compatible"].get<bool>() ? "compatible with" : "CHANGED since",
                            change["against_date"].get<std::string>().c_str(),
                            a["chi2"].get<double>(), a["dof"].get<int>(), a["p"].get<double>());
  if (!change["gyroscope"].is_null()) {
    const Json& g = change["gyroscope"];
    text += Format("; gyroscope chi2 %.3g for %d, p %.2g", g["chi2"].get<double>(),
                   g["dof"].get<int>(), g["p"].get<double>());
  }
  text += ")";
  if (!change["compatible"].get<bool>()) {
    text +=
        Format("; K and k2 p %.2g, bias p %.2g", change["accelerometer_scale"]["p"].get<double>(),
               change["accelerometer_bias"]["p"].get<double>());
    text += "; largest:";
    for (const Json& l : a["largest"]) {
      text += Format(" %s %+.1f sigma", l["parameter"].get<std::string>().c_str(),
                     l["z"].get<double>());
    }
  }
  return text;
}

// The entries' order: by unit, then date; entries of one date in the order they were added.
void SortEntries(std::vector<Entry>* entries) {
  std::stable_sort(entries->begin(), entries->end(), [](const Entry& a, const Entry& b) {
    return a.unit != b.unit ? a.unit < b.unit : a.date < b.date;
  });
}

int Add(const StoreArgs& args) {
  if (args.items.empty())
    throw UsageError("store add: give calibration files or batch directories");
  if (!args.unit.empty()) {
    if (const std::string why = UnitIdProblem(args.unit); !why.empty()) throw UsageError(why);
  }
  if (!args.date.empty()) {
    if (const auto why = CheckProvenanceDate(args.date)) throw UsageError("--date: " + *why);
  }
  // Every file is read and checked before anything is written.
  int skipped = 0;
  std::vector<Candidate> candidates = Candidates(args, &skipped);
  MakeDirectory(args.store);
  const StoreLock lock(args.store);
  std::vector<Entry> entries = ReadIndex(args.store);
  MakeDirectory(args.store + "/units");
  ChangeOptions change_options;
  if (!args.bias_repeatability.empty()) {
    const auto& q = args.bias_repeatability;
    if (q.size() != 1 && q.size() != 3) {
      throw UsageError("--bias-repeatability: one value, or x,y,z");
    }
    for (double v : q) {
      if (!(v >= 0) || !std::isfinite(v)) {
        throw UsageError("--bias-repeatability: a 1 sigma is finite and not negative");
      }
    }
    change_options.bias_repeatability =
        q.size() == 1 ? Vec3::Constant(q[0]) : Vec3(q[0], q[1], q[2]);
  }
  int added = 0, changed = 0, present = 0;
  Json report = Json::array();
  for (Candidate& c : candidates) {
    const std::string sha = Sha256Hex(c.text);
    const bool known = std::any_of(entries.begin(), entries.end(), [&](const Entry& e) {
      return e.unit == c.unit && e.sha256 == sha;
    });
    if (known) {
      ++present;
      if (!args.json) Say("%s  %s  already in the store\n", c.unit.c_str(), c.date.c_str());
      continue;
    }
    // The unit's latest calibration of an earlier or the same date.
    const Entry* earlier = nullptr;
    for (const Entry& e : entries) {
      if (e.unit == c.unit && e.date <= c.date) earlier = &e;
    }
    Entry entry;
    entry.unit = c.unit;
    entry.date = c.date;
    entry.sha256 = sha;
    entry.verdict = c.cal.verdict;
    entry.source = c.source;
    std::string day = c.date;
    std::replace(day.begin(), day.end(), ':', '-');
    entry.file = "units/" + c.unit + "/" + day + "_" + sha.substr(0, 12) + ".json";
    if (earlier != nullptr) {
      const std::string path = args.store + "/" + earlier->file;
      try {
        const LoadedCalibration before =
            ParseCalibrationJson(ReadFileToString(path, kMaxSmallFileBytes), path);
        entry.change = ChangeJson(*earlier, CompareCalibrations(before, c.cal, change_options));
      } catch (const DataError& e) {
        entry.change = {{"against", earlier->file},
                        {"against_date", earlier->date},
                        {"comparable", false},
                        {"reason", e.what()}};
      }
    }
    MakeDirectory(args.store + "/units/" + c.unit);
    WriteFileAtomically(args.store + "/" + entry.file, c.text);
    const bool was_changed = entry.change.is_object() && entry.change.contains("compatible") &&
                             !entry.change["compatible"].get<bool>();
    changed += was_changed ? 1 : 0;
    if (!args.json) {
      Say("%s  %s  added %s; %s\n", c.unit.c_str(), c.date.c_str(), entry.file.c_str(),
          ChangeText(entry.change).c_str());
    }
    report.push_back({{"unit", entry.unit}, {"file", entry.file}, {"change", entry.change}});
    entries.push_back(std::move(entry));
    SortEntries(&entries);
    ++added;
  }
  WriteFileAtomically(IndexPath(args.store), IndexText(entries));
  if (args.json) {
    WriteOut(JsonText(report));
  } else {
    Say("%d added, %d already in the store%s\n", added, present,
        skipped > 0 ? Format(", %d units that did not pass their batch left out", skipped).c_str()
                    : "");
  }
  if (changed > 0) {
    WriteErr(
        Format("accelcal: %d calibrations differ from their unit's one before beyond their "
               "covariances (p < %g)\n",
               changed, kChangeP));
    return kExitFailedChecks;
  }
  return kExitOk;
}

std::vector<Entry> UnitEntries(const std::vector<Entry>& entries, const std::string& unit,
                               const std::string& store) {
  std::vector<Entry> of_unit;
  for (const Entry& e : entries) {
    if (e.unit == unit) of_unit.push_back(e);
  }
  if (of_unit.empty()) {
    throw InputError(IndexPath(store), 0, "no calibration of unit '" + unit + "' in the store");
  }
  return of_unit;
}

int Get(const StoreArgs& args) {
  if (args.items.size() != 1) throw UsageError("store get: give one unit");
  CheckOutputs({{"-o", args.output}}, {IndexPath(args.store)});
  const std::vector<Entry> entries =
      UnitEntries(ReadIndex(args.store), args.items.front(), args.store);
  const Entry* chosen = nullptr;
  for (const Entry& e : entries) {
    // A date picks the unit's latest calibration of that day (or that exact date and time).
    if (args.date.empty() || e.date.compare(0, args.date.size(), args.date) == 0) chosen = &e;
  }
  if (chosen == nullptr) {
    std::string dates;
    for (const Entry& e : entries) dates += (dates.empty() ? "" : ", ") + e.date;
    throw InputError(IndexPath(args.store), 0,
                     "unit '" + args.items.front() + "' has no calibration of " + args.date +
                         " (it has " + dates + ")");
  }
  const std::string path = args.store + "/" + chosen->file;
  const std::string text = ReadFileToString(path, kMaxSmallFileBytes);
  if (Sha256Hex(text) != chosen->sha256) {
    throw InputError(path, 0,
                     "its SHA-256 is not the index's: the file was changed after it was "
                     "stored");
  }
  if (args.output.empty() || args.output == "-") {
    WriteOut(text);
  } else {
    WriteFileAtomically(args.output, text);
  }
  return kExitOk;
}

int List(const StoreArgs& args) {
  if (args.items.size() > 1) throw UsageError("store list: give at most one unit");
  std::vector<Entry> entries = ReadIndex(args.store);
  if (!IsDirectory(args.store)) throw InputError(args.store, 0, "no such store");
  if (!args.items.empty()) entries = UnitEntries(entries, args.items.front(), args.store);
  if (args.json) {
    WriteOut(IndexText(entries));
    return kExitOk;
  }
  if (args.items.empty()) {
    // One line per unit: its calibrations, the latest, and its change.
    for (std::size_t i = 0; i < entries.size();) {
      std::size_t j = i;
      while (j < entries.size() && entries[j].unit == entries[i].unit) ++j;
      const Entry& latest = entries[j - 1];
      Say("%-16s %3zu  latest %s  %-8s  %s\n", latest.unit.c_str(), j - i, latest.date.c_str(),
          latest.verdict.c_str(), ChangeText(latest.change).c_str());
      i = j;
    }
    return kExitOk;
  }
  for (const Entry& e : entries) {
    Say("%s  %-8s  %s  %s\n", e.date.c_str(), e.verdict.c_str(), e.file.c_str(),
        ChangeText(e.change).c_str());
  }
  return kExitOk;
}

}  // namespace

int RunStore(const StoreArgs& args) {
  if (args.action == "add") return Add(args);
  if (args.action == "get") return Get(args);
  if (args.action == "list") return List(args);
  throw UsageError("store: '" + args.action + "' is neither add, get nor list");
}

}  // namespace accelcal::cli
