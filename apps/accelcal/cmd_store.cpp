// accelcal store add|get|list: a directory of calibrations by unit and date with an index.
//   STORE/index.json                     every calibration: unit, date, file, SHA-256, verdict,
//                                        and its change against the unit's calibration before it
//   STORE/units/ID/DATE_SHA.json         the calibration files, as they were given
// Each calibration is compared with the unit's latest comparable one before it in time
// (calibration_change.hpp); one added before others re-compares the one after it, so the index
// always says how each calibration differs from its predecessor. Adding is locked (flock on
// STORE/.lock), every file is checked before anything is written, the files are written before
// the index, and the index is replaced whole. The index is checked when read: a path that leaves
// the store or holds a control character, a bad date or SHA-256, a duplicate are refused. Below
// STORE (the directory the user names) nothing is followed: every directory, file and the index
// are opened relative to their parent without following a link (output.hpp's Directory).
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include "accelcal/calibration_change.hpp"
#include "accelcal/calibration_file.hpp"
#include "accelcal/json_text.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/sha256.hpp"
#include "cli_common.hpp"
#include "cli_options.hpp"
#include "commands.hpp"
#include "output.hpp"

namespace accelcal::cli {
namespace {

using Json = nlohmann::ordered_json;

struct Entry {
  std::string unit, date, file, sha256, verdict, source;
  Json change;         // null for a unit's first calibration
  std::string key;     // the date as a UTC instant, for ordering (DateKey)
  bool fresh = false;  // added or re-compared by this add
};

constexpr const char* kIndex = "index.json";

std::string IndexPath(const std::string& store) { return store + "/" + kIndex; }

// A stored file's bytes: `file` is an index's units/UNIT/NAME (checked by ReadIndex), each part
// opened without following a link.
std::string ReadStored(const Directory& store, const std::string& file) {
  const std::size_t first = file.find('/'), last = file.rfind('/');
  return store.Sub(file.substr(0, first), false)
      .Sub(file.substr(first + 1, last - first - 1), false)
      .Read(file.substr(last + 1), kMaxSmallFileBytes);
}

// A provenance date (CheckProvenanceDate's form) as the UTC instant "YYYY-MM-DDTHH:MM:SS", so that
// dates with other time zones order by time; a date alone is its day's start.
std::string DateKey(const std::string& date) {
  std::tm t{};
  t.tm_year = std::atoi(date.substr(0, 4).c_str()) - 1900;
  t.tm_mon = std::atoi(date.substr(5, 2).c_str()) - 1;
  t.tm_mday = std::atoi(date.substr(8, 2).c_str());
  long offset_s = 0;
  if (date.size() > 10) {
    t.tm_hour = std::atoi(date.substr(11, 2).c_str());
    t.tm_min = std::atoi(date.substr(14, 2).c_str());
    std::size_t at = 16;
    if (at < date.size() && date[at] == ':') {
      t.tm_sec = std::atoi(date.substr(at + 1, 2).c_str());
      at += 3;
    }
    if (at < date.size() && (date[at] == '+' || date[at] == '-')) {
      offset_s = (date[at] == '-' ? -1 : 1) * (std::atol(date.substr(at + 1, 2).c_str()) * 3600 +
                                               std::atol(date.substr(at + 4, 2).c_str()) * 60);
    }
  }
  const std::time_t utc = timegm(&t) - offset_s;
  std::tm out{};
  gmtime_r(&utc, &out);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &out);
  return text;
}

// The entries' order: by unit, then time; entries of one time in the order they were added.
void SortEntries(std::vector<Entry>* entries) {
  std::stable_sort(entries->begin(), entries->end(), [](const Entry& a, const Entry& b) {
    return a.unit != b.unit ? a.unit < b.unit : a.key < b.key;
  });
}

// The index, or none when the store has none yet. Every entry is checked: an index edited by hand
// or damaged is refused (InputError naming the entry) rather than read outside the store or
// half-understood.
std::vector<Entry> ReadIndex(const Directory& store) {
  const std::string path = store.Shown(kIndex);
  if (!store.Has(kIndex)) return {};
  std::vector<Entry> entries;
  Json doc;
  try {
    doc = Json::parse(store.Read(kIndex, kMaxSmallFileBytes));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, 0, std::string("not JSON: ") + e.what());
  }
  if (!doc.is_object() || doc.value("format", Json()) != "accelcal-store" ||
      doc.value("version", Json()) != 1 || !doc.contains("entries") || !doc["entries"].is_array()) {
    throw InputError(path, 0,
                     "not an accelcal store's index: it must have format accelcal-store, "
                     "version 1 and a list of entries");
  }
  std::set<std::pair<std::string, std::string>> seen;
  for (std::size_t i = 0; i < doc["entries"].size(); ++i) {
    const Json& e = doc["entries"][i];
    const auto fail = [&](const std::string& why) {
      throw InputError(path, 0, "entry " + std::to_string(i + 1) + ": " + why);
    };
    const auto text = [&](const char* key) {
      if (!e.is_object() || !e.contains(key) || !e[key].is_string()) {
        fail(std::string("'") + key + "' is missing or not a string");
      }
      return e[key].get<std::string>();
    };
    Entry entry;
    entry.unit = text("unit");
    entry.date = text("date");
    entry.file = text("file");
    entry.sha256 = text("sha256");
    entry.verdict = text("verdict");
    entry.source = text("source");
    entry.change = e.value("change", Json());
    if (const std::string why = UnitIdProblem(entry.unit); !why.empty()) fail(why);
    if (const auto why = CheckProvenanceDate(entry.date)) fail(*why);
    if (entry.sha256.size() != 64 ||
        entry.sha256.find_first_not_of("0123456789abcdef") != std::string::npos) {
      fail("'sha256' is not 64 hexadecimal digits");
    }
    // A control character (a NUL above all: the system would see the name end there, and open
    // another file) is no part of a name the store writes.
    if (std::any_of(entry.file.begin(), entry.file.end(),
                    [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; })) {
      fail("'file' " + internal::VisibleLine(entry.file) + " holds a control character");
    }
    // units/UNIT/NAME.json, NAME without a '/': never a path out of the store.
    const std::string prefix = "units/" + entry.unit + "/";
    const std::string name = entry.file.substr(std::min(entry.file.size(), prefix.size()));
    if (entry.file.compare(0, prefix.size(), prefix) != 0 || name.empty() || name[0] == '.' ||
        name.find('/') != std::string::npos) {
      fail("'file' " + entry.file + " is not units/" + entry.unit + "/NAME.json");
    }
    if (!entry.change.is_null() && !entry.change.is_object()) fail("'change' is not an object");
    if (!seen.emplace(entry.unit, entry.sha256).second) {
      fail("unit " + entry.unit + "'s calibration " + entry.sha256.substr(0, 12) + " twice");
    }
    entry.key = DateKey(entry.date);
    entries.push_back(std::move(entry));
  }
  SortEntries(&entries);
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

struct Candidate {
  std::string unit, source, text, date;
  LoadedCalibration cal;
};

// The calibrations to add: each file given (of --unit), and the passing units of each batch
// directory given (their ids from its summary; only --unit's when given). A calibration that
// failed its own checks is no unit's reference: refused.
std::vector<Candidate> Candidates(const StoreArgs& args, int* skipped) {
  std::vector<Candidate> out;
  const auto take = [&](const std::string& unit, const std::string& path, std::string text) {
    Candidate c;
    c.unit = unit;
    c.source = path;
    c.text = std::move(text);
    c.cal = ParseCalibrationJson(c.text, path);
    if (c.cal.verdict == "failed") {
      throw InputError(path, 0,
                       "the calibration failed its own checks (verdict failed): it is not "
                       "stored as the unit's reference");
    }
    c.date = !c.cal.provenance.date.empty() ? c.cal.provenance.date
             : !args.date.empty()           ? args.date
                                            : Today();
    if (!c.cal.provenance.date.empty() && !args.date.empty() && args.date != c.date) {
      Warn("%s: dated %s by its provenance; --date %s is for calibrations without one\n",
           path.c_str(), c.date.c_str(), args.date.c_str());
    }
    out.push_back(std::move(c));
  };
  bool from_batch = false;
  for (const std::string& item : args.items) {
    if (!IsDirectory(item)) {
      if (args.unit.empty()) {
        throw UsageError(item +
                         ": give its unit with --unit (a batch's directory names its units)");
      }
      take(args.unit, item, ReadFileToString(item, kMaxSmallFileBytes));
      continue;
    }
    from_batch = true;
    // The batch's directory as batch writes it: nothing below it followed through a link, and
    // not while a batch writes into it (its lock, shared; never made: store add only reads it).
    const Directory batch = Directory::Open(item, false);
    const DirectoryLock lock(batch, ".lock", false, false, false);
    if (lock.busy()) {
      throw InputError(item, 0, "a batch is writing into it: add it when the batch has finished");
    }
    const std::string summary = batch.Shown("summary.json");
    struct Row {
      std::string unit, sha256;
      bool passed;
    };
    std::vector<Row> units;
    try {
      const Json doc = Json::parse(batch.Read("summary.json", kMaxSmallFileBytes));
      if (doc.at("format") != "accelcal-batch-summary") throw std::runtime_error("its format");
      for (const Json& row : doc.at("units")) {
        const bool passed = row.at("status") == "pass";
        const Json sha = row.value("sha256", Json());
        units.push_back({row.at("unit").get<std::string>(),
                         sha.is_string() ? sha.get<std::string>() : std::string(), passed});
      }
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw InputError(summary, 0, std::string("not a batch's summary: ") + e.what());
    }
    for (const Row& row : units) {
      if (!args.unit.empty() && row.unit != args.unit) continue;
      if (!row.passed) {
        ++*skipped;
        continue;
      }
      if (const std::string why = UnitIdProblem(row.unit); !why.empty()) {
        throw InputError(summary, 0, why);
      }
      // The unit's file must be the one the batch judged: another run, or a hand, may have
      // replaced it since (a unit that passed would then store a calibration never judged).
      const Directory unit_dir = batch.Sub("units", false).Sub(row.unit, false);
      const std::string path = unit_dir.Shown("calibration.json");
      const std::string text = unit_dir.Read("calibration.json", kMaxSmallFileBytes);
      if (row.sha256.size() != 64) {
        throw InputError(summary, 0,
                         "unit " + row.unit +
                             " has no SHA-256 of its file (a summary written before summaries "
                             "carried one): run the batch again, which redoes no current "
                             "calibration");
      }
      if (Sha256Hex(text) != row.sha256) {
        throw InputError(path, 0,
                         "its SHA-256 is not the one " + summary +
                             " judged: the file was replaced after the batch (run the batch "
                             "again)");
      }
      take(row.unit, path, text);
    }
  }
  if (from_batch && !args.unit.empty() && out.empty() && *skipped == 0) {
    throw UsageError("--unit " + args.unit + ": no such unit in the batch directories given");
  }
  return out;
}

// A number for a person: %.3g, the extremes said as such.
std::string Brief(double v) {
  if (!std::isfinite(v)) return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
  return Format("%.3g", v);
}

// The comparison with `earlier` as the index records it.
Json ChangeJson(const Entry& earlier, const CalibrationChange& c, const ChangeOptions& options) {
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
  j["bias_repeatability"] =
      options.bias_repeatability
          ? Json::array({(*options.bias_repeatability)(0), (*options.bias_repeatability)(1),
                         (*options.bias_repeatability)(2)})
          : Json();
  j["notes"] = c.notes;
  return j;
}

// What the index's record of a change says, in a line. Written by this file, but read from an
// index a person may have edited: whatever is missing reads as unknown, never as a crash.
std::string ChangeText(const Json& change) {
  if (!change.is_object()) return "the unit's first calibration";
  const std::string against = change.value("against_date", std::string("?"));
  if (!change.value("comparable", true)) {
    return "not compared with " + against + ": " + change.value("reason", std::string("?"));
  }
  const auto number = [](const Json& j, const char* key) {
    return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>() : NAN;
  };
  const Json a = change.value("accelerometer", Json());
  const Json g = change.value("gyroscope", Json());
  const bool compatible = change.value("compatible", false);
  std::string text = (compatible ? "compatible with " : "CHANGED since ") + against + " (chi2 " +
                     Brief(number(a, "chi2")) + " for " + Brief(number(a, "dof")) +
                     " parameters, p " + Brief(number(a, "p"));
  if (g.is_object()) {
    text += "; gyroscope chi2 " + Brief(number(g, "chi2")) + " for " + Brief(number(g, "dof")) +
            ", p " + Brief(number(g, "p"));
  }
  text += ")";
  if (!compatible) {
    const auto largest = [&](const char* label, const Json& sensor) {
      if (!sensor.is_object() || !(number(sensor, "p") < kChangeP)) return;
      text += std::string("; ") + label + " largest:";
      for (const Json& l : sensor.value("largest", Json::array())) {
        text +=
            " " + l.value("parameter", std::string("?")) + " " + Brief(number(l, "z")) + " sigma";
      }
    };
    text += "; K and k2 p " + Brief(number(change.value("accelerometer_scale", Json()), "p")) +
            ", bias p " + Brief(number(change.value("accelerometer_bias", Json()), "p"));
    largest("accelerometer", a);
    largest("gyroscope", g);
  }
  for (const Json& note : change.value("notes", Json::array())) {
    if (note.is_string()) text += "; " + note.get<std::string>();
  }
  return text;
}

// The change of entry `i` against the unit's latest comparable calibration before it: each
// earlier one is tried in turn (one of another model, or without a covariance, is passed over,
// and said when none is comparable). A stored file whose bytes are no longer the index's is
// refused, not compared.
Json CompareWithPredecessor(const Directory& store, const std::vector<Entry>& entries,
                            std::size_t i, const LoadedCalibration& cal,
                            const ChangeOptions& options) {
  Json first_refusal;
  for (std::size_t j = i; j-- > 0 && entries[j].unit == entries[i].unit;) {
    const Entry& earlier = entries[j];
    const std::string path = store.Shown(earlier.file);
    const std::string text = ReadStored(store, earlier.file);
    if (Sha256Hex(text) != earlier.sha256) {
      throw InputError(path, 0,
                       "its SHA-256 is not the index's: the file was changed after it was stored "
                       "(restore it, or remove its entry from the index)");
    }
    try {
      return ChangeJson(
          earlier, CompareCalibrations(ParseCalibrationJson(text, path), cal, options), options);
    } catch (const DataError& e) {
      if (first_refusal.is_null()) {
        first_refusal = {{"against", earlier.file},
                         {"against_date", earlier.date},
                         {"comparable", false},
                         {"reason", e.what()}};
      }
    }
  }
  return first_refusal;
}

ChangeOptions ParseChangeOptions(const StoreArgs& args) {
  ChangeOptions options;
  if (args.bias_repeatability.empty()) return options;
  const auto& q = args.bias_repeatability;
  if (q.size() != 1 && q.size() != 3) throw UsageError("--bias-repeatability: one value, or x,y,z");
  for (double v : q) {
    if (!(v >= 0) || !std::isfinite(v)) {
      throw UsageError("--bias-repeatability: a 1 sigma is finite and not negative");
    }
  }
  options.bias_repeatability = q.size() == 1 ? Vec3::Constant(q[0]) : Vec3(q[0], q[1], q[2]);
  return options;
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
  if (!args.output.empty()) throw UsageError("store add writes into the store: -o is get's");
  const ChangeOptions options = ParseChangeOptions(args);
  // Every file is read and checked before anything is written.
  int skipped = 0;
  std::vector<Candidate> candidates = Candidates(args, &skipped);
  const Directory store = Directory::Open(args.store, true);
  // Concurrent adds wait for each other: an add takes seconds.
  const DirectoryLock lock(store, ".lock", true, true, true);
  std::vector<Entry> entries = ReadIndex(store);
  const Directory units = store.Sub("units", true);
  int present = 0;
  std::vector<std::string> lines;
  std::map<std::string, const LoadedCalibration*> new_calibrations;  // by file
  for (Candidate& c : candidates) {
    const std::string sha = Sha256Hex(c.text);
    const auto known = std::find_if(entries.begin(), entries.end(),
                                    [&](const Entry& e) { return e.sha256 == sha; });
    if (known != entries.end() && known->unit == c.unit) {
      ++present;
      lines.push_back(c.unit + "  " + c.date + "  already in the store\n");
      continue;
    }
    if (known != entries.end()) {
      Warn("%s: the same calibration is stored as unit %s's; is %s another unit's id for it?\n",
           c.source.c_str(), known->unit.c_str(), c.unit.c_str());
    }
    Entry entry;
    entry.unit = c.unit;
    entry.date = c.date;
    entry.key = DateKey(c.date);
    entry.sha256 = sha;
    entry.verdict = c.cal.verdict;
    entry.source = c.source;
    entry.fresh = true;
    std::string day = c.date;
    std::replace(day.begin(), day.end(), ':', '-');
    const std::string name = day + "_" + sha.substr(0, 12) + ".json";
    entry.file = "units/" + c.unit + "/" + name;
    const Directory unit_dir = units.Sub(c.unit, true);
    OutputFile file(unit_dir, name);
    file.Write(c.text);
    file.Commit();
    new_calibrations[entry.file] = &c.cal;
    entries.push_back(std::move(entry));
    SortEntries(&entries);
  }
  // Each new calibration against the one before it, and the one after it against it: an older
  // calibration added late sits between two that were compared with each other.
  int changed = 0, added = 0;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const bool is_new = new_calibrations.count(entries[i].file) > 0;
    const bool after_new = !is_new && i > 0 && entries[i - 1].unit == entries[i].unit &&
                           entries[i - 1].fresh && new_calibrations.count(entries[i - 1].file) > 0;
    if (!is_new && !after_new) continue;
    std::optional<LoadedCalibration> stored;
    if (!is_new) {
      const std::string path = store.Shown(entries[i].file);
      const std::string text = ReadStored(store, entries[i].file);
      if (Sha256Hex(text) != entries[i].sha256) {
        throw InputError(path, 0,
                         "its SHA-256 is not the index's: the file was changed after it "
                         "was stored");
      }
      stored = ParseCalibrationJson(text, path);
    }
    const LoadedCalibration& cal = is_new ? *new_calibrations[entries[i].file] : *stored;
    entries[i].change = CompareWithPredecessor(store, entries, i, cal, options);
    const bool was_changed =
        entries[i].change.is_object() && entries[i].change.value("compatible", true) == false;
    changed += was_changed ? 1 : 0;
    added += is_new ? 1 : 0;
    lines.push_back(entries[i].unit + "  " + entries[i].date + "  " +
                    (is_new ? "added " + entries[i].file : std::string("now")) + "; " +
                    ChangeText(entries[i].change) + "\n");
  }
  {
    OutputFile index(store, kIndex);
    index.Write(IndexText(entries));
    index.Commit();
  }
  // Said once the index holds it.
  if (args.json) {
    Json report = Json::array();
    for (const Entry& e : entries) {
      if (new_calibrations.count(e.file) > 0) {
        report.push_back({{"unit", e.unit}, {"file", e.file}, {"change", e.change}});
      }
    }
    WriteOut(JsonText(report));
  } else {
    for (const std::string& line : lines) Say("%s", line.c_str());
    Say("%d added, %d already in the store%s\n", added, present,
        skipped > 0 ? Format(", %d units that did not pass their batch left out", skipped).c_str()
                    : "");
  }
  if (changed > 0) {
    WriteErrLine(
        Format("accelcal: %d calibration%s differ%s from the unit's one before beyond the "
               "covariances (p < %g)\n",
               changed, changed == 1 ? "" : "s", changed == 1 ? "s" : "", kChangeP));
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

// The store must exist to be read.
Directory RequireStore(const std::string& store) {
  if (!IsDirectory(store)) throw InputError(store, 0, "no such store (a directory)");
  return Directory::Open(store, false);
}

// Refuses an output inside the store: it would replace a stored calibration, the index or the lock.
void RefuseOutputInStore(const std::string& output, const std::string& store) {
  if (output.empty() || output == "-") return;
  char store_real[PATH_MAX], out_dir_real[PATH_MAX];
  const std::size_t slash = output.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : output.substr(0, slash + 1);
  if (::realpath(store.c_str(), store_real) == nullptr ||
      ::realpath(dir.c_str(), out_dir_real) == nullptr) {
    return;  // the write itself will say what is wrong
  }
  const std::string s = store_real, o = out_dir_real;
  if (o == s || o.compare(0, s.size() + 1, s + "/") == 0) {
    throw UsageError("-o " + output +
                     " is inside the store: it would replace what the store "
                     "holds; write it elsewhere");
  }
}

int Get(const StoreArgs& args) {
  if (args.items.size() != 1) throw UsageError("store get: give one unit");
  if (!args.date.empty()) {
    if (const auto why = CheckProvenanceDate(args.date)) throw UsageError("--date: " + *why);
  }
  const Directory store = RequireStore(args.store);
  RefuseOutputInStore(args.output, args.store);
  CheckOutputs({{"-o", args.output}}, {IndexPath(args.store)});
  const std::vector<Entry> entries = UnitEntries(ReadIndex(store), args.items.front(), args.store);
  const Entry* chosen = nullptr;
  // A day picks the unit's latest calibration dated that day; a date and time, the one of that
  // instant (in any time zone).
  const bool day = args.date.size() == 10;
  for (const Entry& e : entries) {
    const bool match = args.date.empty() ||
                       (day ? e.date.compare(0, 10, args.date) == 0 : e.key == DateKey(args.date));
    if (match) chosen = &e;
  }
  if (chosen == nullptr) {
    std::string dates;
    for (const Entry& e : entries) dates += (dates.empty() ? "" : ", ") + e.date;
    throw InputError(IndexPath(args.store), 0,
                     "unit '" + args.items.front() + "' has no calibration of " + args.date +
                         " (it has " + dates + ")");
  }
  const std::string path = store.Shown(chosen->file);
  const std::string text = ReadStored(store, chosen->file);
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
  std::vector<Entry> entries = ReadIndex(RequireStore(args.store));
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

CommandRun SetUpStore(CLI::App* cmd) {
  auto a = std::make_shared<StoreArgs>();
  cmd->add_option("ACTION", a->action, "add, get or list")->required();
  cmd->add_option("STORE", a->store, "the store's directory (made by the first add)")
      ->required()
      ->check(kFileName);
  cmd->add_option("ITEMS", a->items,
                  "add: calibration files, or batch directories (their passing units); get: "
                  "the unit; list: a unit (default: every unit)");
  cmd->add_option("--unit", a->unit,
                  "add: the unit of the calibration files given (a batch directory names "
                  "its own; with one, only that unit is added)");
  cmd->add_option("--date", a->date,
                  "add: the date of calibrations whose provenance has none (default: today, "
                  "UTC); get: the calibration of that date (YYYY-MM-DD: its latest that day; "
                  "default: the unit's latest)");
  cmd->add_option("-o,--output", a->output, "get: write the calibration file here")
      ->check(kFileName);
  cmd->add_flag("--json", a->json, "list: the index's entries; add: what was added");
  cmd->add_option("--bias-repeatability", a->bias_repeatability,
                  "add: the accelerometer's turn-on bias repeatability (1 sigma, in the "
                  "calibrations' specific-force unit; one value or x,y,z: a MEMS part's bias "
                  "moves between power-ups by more than a calibration's covariance holds)")
      ->expected(1, 3)
      ->delimiter(',')
      ->check(kDecimal)
      ->type_name("Q[,Q,Q]");
  return [a](const CLI::App& /*parsed*/) { return RunStore(*a); };
}

}  // namespace accelcal::cli
