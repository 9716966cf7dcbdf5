// A CalibrationResult's pickled state: every field of the result and of what it holds, by name,
// as CBOR (binary: each double's bits, NaN and infinities included, survive, which JSON text
// would not promise). One field list per struct (Fields) serves both directions, so that what is
// saved and what is loaded cannot drift apart; a struct that gains a field fails the size checks
// below until its list names it. The gyroscope is pickled as its section of the calibration file
// (GyroscopeToJson), the one description that also writes and reads the file.
#include <cstdint>
#include <cstring>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/sha256.hpp"
#include "accelcal/version.hpp"
#include "py_result.hpp"

namespace accelcal::python {

namespace {

namespace py = pybind11;
using Json = nlohmann::json;

// What a field list is walked with: Saver writes each field into a JSON object, Loader reads it
// back. Fields take the struct by non-const reference; Saver only reads it.
struct Saver;
struct Loader;

std::uint64_t Bits(double v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  return bits;
}
double FromBits(std::uint64_t bits) {
  double v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

template <typename T>
struct IsOptional : std::false_type {};
template <typename T>
struct IsOptional<std::optional<T>> : std::true_type {};
template <typename T>
struct IsVector : std::false_type {};
template <typename T, typename A>
struct IsVector<std::vector<T, A>> : std::true_type {};
template <typename T>
struct IsEigen : std::is_base_of<Eigen::MatrixBase<T>, T> {};

template <typename V>
void Fields(V& v, ModelParameters& p) {
  v("K", p.K)("bias", p.bias)("k2", p.k2);
}
template <typename V>
void Fields(V& v, Summary& s) {
  v("method", s.method)("initialization", s.initialization)(
      "initialization_note", s.initialization_note)("iterations", s.iterations)(
      "termination", s.termination)("termination_message", s.termination_message)(
      "initial_cost", s.initial_cost)("final_cost", s.final_cost)("time_s", s.time_s)(
      "estimator", s.estimator)("correction_rounds", s.correction_rounds);
}
template <typename V>
void Fields(V& v, OutlierFinding& o) {
  v("position", o.position)("statistic", o.statistic)("t", o.t)("threshold", o.threshold)(
      "degrees_of_freedom", o.degrees_of_freedom)("normal_residual", o.normal_residual)(
      "scatter", o.scatter)("excluded", o.excluded);
}
template <typename V>
void Fields(V& v, BiasModel& m) {
  v("kind", m.kind)("knots", m.knots);
}
template <typename V>
void Fields(V& v, BiasTimeBasis& b) {
  v("model", b.model)("t_ref_s", b.t_ref_s)("knots_s", b.knots_s);
}
template <typename V>
void Fields(V& v, BiasDrift& d) {
  v("basis", d.basis)("D", d.D)("covariance", d.covariance)("times_s", d.times_s)("random_walk",
                                                                                  d.random_walk);
}
template <typename V>
void Fields(V& v, ThermalDegrees& d) {
  v("K", d.K)("bias", d.bias)("k2", d.k2);
}
template <typename V>
void Fields(V& v, ThermalParameters& p) {
  v("t_ref_c", p.t_ref_c)("degrees", p.degrees)("coefficients", p.coefficients);
}
template <typename V>
void Fields(V& v, ThermalTerms& t) {
  v("params", t.params)("covariance", t.covariance)("temperatures_c", t.temperatures_c);
}
template <typename V>
void Fields(V& v, CalibrationResult& r) {
  v("model", r.model)("frame", r.frame)("gravity", r.gravity)("params", r.params)(
      "directions", r.directions)("residuals", r.residuals)("covariance", r.covariance)(
      "residual_sigma", r.residual_sigma)("noise_source", r.noise_source)(
      "scatter_ratio", r.scatter_ratio)("degrees_of_freedom", r.degrees_of_freedom)(
      "summary", r.summary)("drift", r.drift)("thermal", r.thermal)("crossval_rms", r.crossval_rms)(
      "crossval_errors", r.crossval_errors)("crossval_note", r.crossval_note)(
      "outliers", r.outliers)("outlier_note", r.outlier_note)("screening", r.screening);
}
template <typename V>
void Fields(V& v, ModelSelection& s) {
  v("chosen", s.chosen)("reason", s.reason)("linear", s.linear)("quadratic", s.quadratic)(
      "quadratic_error", s.quadratic_error)("k2_t", s.k2_t)("screened_with", s.screened_with)(
      "positions_used", s.positions_used)("improvement", s.improvement)(
      "improvement_se", s.improvement_se)("improvement_threshold", s.improvement_threshold)(
      "k2_t_threshold", s.k2_t_threshold);
}
template <typename V>
void Fields(V& v, StaticInterval& i) {
  v("begin", i.begin)("end", i.end)("t_begin_s", i.t_begin_s)("t_end_s", i.t_end_s)("mean", i.mean)(
      "std", i.std)("averaged", i.averaged)("temperature_c", i.temperature_c);
}
template <typename V>
void Fields(V& v, Position& p) {
  v("mean", p.mean)("samples", p.samples)("std", p.std)("interval", p.interval)("temperature_c",
                                                                                p.temperature_c);
}
template <typename V>
void Fields(V& v, Finding& f) {
  v("code", f.code)("severity", f.severity)("message", f.message)("numbers", f.numbers);
}
template <typename V>
void Fields(V& v, Diagnosis& d) {
  v("findings", d.findings);
}
template <typename V>
void Fields(V& v, SourceStream& s) {
  v("format", s.format)("topic", s.topic)("type", s.type)("instance", s.instance)(
      "device_id", s.device_id)("unit", s.unit)("corrected", s.corrected)("calibration_in_force",
                                                                          s.calibration_in_force);
}
template <typename V>
void Fields(V& v, InputRecord& i) {
  v("name", i.name)("bytes", i.bytes)("sha256", i.sha256)("stream", i.stream);
}
template <typename V>
void Fields(V& v, Provenance& p) {
  v("command", p.command)("options", p.options)("inputs", p.inputs)("date", p.date)(
      "accelcal_version", p.accelcal_version);
}
template <typename V>
void Fields(V& v, BiasModelStep& s) {
  v("simpler", s.simpler)("richer", s.richer)("error", s.error)("positions_used", s.positions_used)(
      "simpler_rms", s.simpler_rms)("richer_rms", s.richer_rms)("improvement", s.improvement)(
      "improvement_se", s.improvement_se)("improvement_threshold", s.improvement_threshold)(
      "wald", s.wald)("wald_threshold", s.wald_threshold)("wald_dof", s.wald_dof)("accepted",
                                                                                  s.accepted);
}
template <typename V>
void Fields(V& v, BiasModelSelection& b) {
  v("chosen", b.chosen)("reason", b.reason)("result", b.result)("steps", b.steps);
}
template <typename V>
void Fields(V& v, PyCalibration& c) {
  v("result", c.result)("selection", c.selection)("model_requested", c.model_requested)(
      "unit", c.unit)("positions", c.positions)("mean_sigmas", c.mean_sigmas)("source", c.source)(
      "raw_unit", c.raw_unit)("sources", c.sources)("position_source", c.position_source)(
      "bias_model_selection", c.bias_model_selection)("max_excluded", c.max_excluded)(
      "diagnosis", c.diagnosis)("provenance", c.provenance)("gyroscope", c.gyroscope);
}

// A struct that gains a field must have it in its list above: these sizes (x86-64, libstdc++)
// are those of the structs the lists were written for.
#if defined(__x86_64__) && defined(__GLIBCXX__)
static_assert(sizeof(CalibrationResult) == 760,
              "CalibrationResult changed: update its field list (py_state.cpp)");
static_assert(sizeof(Summary) == 112, "Summary changed: update its field list (py_state.cpp)");
static_assert(sizeof(OutlierFinding) == 56,
              "OutlierFinding changed: update its field list (py_state.cpp)");
static_assert(sizeof(BiasDrift) == 136, "BiasDrift changed: update its field list (py_state.cpp)");
static_assert(sizeof(ThermalTerms) == 96,
              "ThermalTerms changed: update its field list (py_state.cpp)");
static_assert(sizeof(ModelSelection) == 1688,
              "ModelSelection changed: update its field list (py_state.cpp)");
static_assert(sizeof(Position) == 192, "Position changed: update its field list (py_state.cpp)");
static_assert(sizeof(Finding) == 96, "Finding changed: update its field list (py_state.cpp)");
static_assert(sizeof(SourceStream) == 208,
              "SourceStream changed: update its field list (py_state.cpp)");
static_assert(sizeof(InputRecord) == 288,
              "InputRecord changed: update its field list (py_state.cpp)");
static_assert(sizeof(Provenance) == 136,
              "Provenance changed: update its field list (py_state.cpp)");
static_assert(sizeof(BiasModelStep) == 136,
              "BiasModelStep changed: update its field list (py_state.cpp)");
static_assert(sizeof(BiasModelSelection) == 824,
              "BiasModelSelection changed: update its field list (py_state.cpp)");
static_assert(sizeof(PyCalibration) == 5224,
              "PyCalibration changed: update its field list (py_state.cpp)");
static_assert(sizeof(StaticInterval) == 104,
              "StaticInterval changed: update its field list (py_state.cpp)");
static_assert(sizeof(BiasTimeBasis) == 40,
              "BiasTimeBasis changed: update its field list (py_state.cpp)");
static_assert(sizeof(ThermalParameters) == 48,
              "ThermalParameters changed: update its field list (py_state.cpp)");
static_assert(sizeof(Diagnosis) == 24, "Diagnosis changed: update its field list (py_state.cpp)");
#endif

struct Saver {
  Json object = Json::object();
  template <typename T>
  Saver& operator()(const char* name, T& value) {
    object[name] = Save(value);
    return *this;
  }

  template <typename T>
  static Json Save(const T& value) {
    if constexpr (std::is_enum_v<T>) {
      return static_cast<std::int64_t>(value);
    } else if constexpr (std::is_same_v<T, double>) {
      return Bits(value);  // every bit, NaN's sign and payload included
    } else if constexpr (std::is_arithmetic_v<T> || std::is_same_v<T, std::string>) {
      return value;
    } else if constexpr (std::is_same_v<T, nlohmann::ordered_json>) {
      return value.dump();  // as text: its keys' order is the file's
    } else if constexpr (std::is_same_v<T, UnitGyroscope>) {
      // As the file's section (one description writes, reads and pickles it); its text holds
      // every double exactly (17 digits), and null for the numbers that do not exist.
      return GyroscopeToJson(value, ForceUnit::kMetersPerSecond2).dump();
    } else if constexpr (IsEigen<T>::value) {
      Json j = Json::object();
      j["rows"] = value.rows();
      j["cols"] = value.cols();
      Json data = Json::array();
      for (Eigen::Index c = 0; c < value.cols(); ++c) {
        for (Eigen::Index r = 0; r < value.rows(); ++r) data.push_back(Bits(value(r, c)));
      }
      j["data"] = std::move(data);
      return j;
    } else if constexpr (IsOptional<T>::value) {
      return value ? Save(*value) : Json(nullptr);
    } else if constexpr (IsVector<T>::value) {
      Json a = Json::array();
      for (const auto& item : value) a.push_back(Save(item));
      return a;
    } else if constexpr (std::is_same_v<T, std::map<std::string, double>>) {
      Json a = Json::array();
      for (const auto& [key, number] : value) a.push_back(Json::array({key, Save(number)}));
      return a;
    } else if constexpr (std::is_same_v<T, std::pair<std::string, double>> ||
                         std::is_same_v<T, std::pair<double, double>>) {
      return Json::array({Save(value.first), Save(value.second)});
    } else {
      Saver nested;
      Fields(nested, const_cast<T&>(value));
      return std::move(nested.object);
    }
  }
};

struct Loader {
  const Json& object;
  template <typename T>
  Loader& operator()(const char* name, T& value) {
    const auto it = object.find(name);
    if (it == object.end()) throw py::value_error(std::string("field '") + name + "' missing");
    Load(*it, value);
    return *this;
  }

  template <typename T>
  static void Load(const Json& j, T& value) {
    if constexpr (std::is_enum_v<T>) {
      value = static_cast<T>(j.get<std::int64_t>());
    } else if constexpr (std::is_same_v<T, double>) {
      value = FromBits(j.get<std::uint64_t>());
    } else if constexpr (std::is_arithmetic_v<T> || std::is_same_v<T, std::string>) {
      value = j.get<T>();
    } else if constexpr (std::is_same_v<T, nlohmann::ordered_json>) {
      value = nlohmann::ordered_json::parse(j.get<std::string>());
    } else if constexpr (std::is_same_v<T, UnitGyroscope>) {
      try {
        value = GyroscopeFromJson(nlohmann::ordered_json::parse(j.get<std::string>()), "pickle");
      } catch (const InputError& e) {
        throw py::value_error(std::string("a pickled gyroscope that is not one: ") + e.what());
      } catch (const nlohmann::json::exception&) {  // its message may quote broken UTF-8
        throw py::value_error("a pickled gyroscope that is not one: its section is not JSON");
      }
    } else if constexpr (IsEigen<T>::value) {
      const auto rows = j.at("rows").get<Eigen::Index>();
      const auto cols = j.at("cols").get<Eigen::Index>();
      const Json& data = j.at("data");
      if (rows < 0 || cols < 0 || (cols > 0 && static_cast<std::size_t>(rows) > data.size()) ||
          data.size() != static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols) ||
          (T::RowsAtCompileTime != Eigen::Dynamic && rows != T::RowsAtCompileTime) ||
          (T::ColsAtCompileTime != Eigen::Dynamic && cols != T::ColsAtCompileTime)) {
        throw py::value_error("a matrix of the wrong shape");
      }
      value.resize(rows, cols);
      std::size_t i = 0;
      for (Eigen::Index c = 0; c < cols; ++c) {
        for (Eigen::Index r = 0; r < rows; ++r)
          value(r, c) = FromBits(data[i++].get<std::uint64_t>());
      }
    } else if constexpr (IsOptional<T>::value) {
      if (j.is_null()) {
        value.reset();
      } else {
        value.emplace();
        Load(j, *value);
      }
    } else if constexpr (IsVector<T>::value) {
      value.clear();
      value.resize(j.size());
      for (std::size_t i = 0; i < j.size(); ++i) Load(j[i], value[i]);
    } else if constexpr (std::is_same_v<T, std::map<std::string, double>>) {
      value.clear();
      for (const Json& item : j) Load(item.at(1), value[item.at(0).get<std::string>()]);
    } else if constexpr (std::is_same_v<T, std::pair<std::string, double>> ||
                         std::is_same_v<T, std::pair<double, double>>) {
      Load(j.at(0), value.first);
      Load(j.at(1), value.second);
    } else {
      if (!j.is_object()) throw py::value_error("a struct that is not an object");
      Loader nested{j};
      Fields(nested, value);
    }
  }
};

constexpr const char* kStateFormat = "accelcal-python-calibration-result";
// The state's bytes: this magic, the SHA-256 of the CBOR (64 hexadecimal digits), the CBOR. A
// damaged pickle (truncated, a flipped bit) fails the digest before it is parsed.
constexpr std::string_view kMagic = "accelcal-state-1:";

template <typename E>
void CheckEnum(E value, const char* what) {
  if (ToString(value).empty()) throw py::value_error(std::string("an unknown ") + what);
}

// What the result's users index by: every per-position list as long as the positions, every
// position number in range, every enum one of its values.
void Validate(const PyCalibration& c) {
  const CalibrationResult& r = c.result;
  const std::size_t m = c.positions.size();
  const auto same = [&](std::size_t n, const char* what) {
    if (n != m) throw py::value_error(std::string(what) + " not one per position");
  };
  same(r.directions.size(), "directions");
  same(r.residuals.size(), "residuals");
  if (!r.crossval_errors.empty()) same(r.crossval_errors.size(), "crossval_errors");
  if (!c.mean_sigmas.empty()) same(c.mean_sigmas.size(), "mean_sigmas");
  for (const OutlierFinding& o : r.outliers) {
    if (o.position < 0 || static_cast<std::size_t>(o.position) >= m) {
      throw py::value_error("an outlier's position out of range");
    }
    CheckEnum(o.statistic, "outlier statistic");
  }
  CheckEnum(r.model, "model");
  CheckEnum(r.frame, "frame");
  CheckEnum(r.screening, "screening policy");
  CheckEnum(r.summary.method, "method");
  CheckEnum(r.summary.initialization, "initialization");
  CheckEnum(r.summary.termination, "termination");
  CheckEnum(r.summary.estimator, "estimator");
  CheckEnum(c.unit, "unit");
  for (const Finding& f : c.diagnosis.findings) CheckEnum(f.severity, "severity");
  const Eigen::Index p = static_cast<Eigen::Index>(ParameterSlots(r.model, r.frame).size());
  if (r.covariance.size() != 0 && (r.covariance.rows() != p || r.covariance.cols() != p)) {
    throw py::value_error("a covariance of the wrong size");
  }
  if (c.selection) {
    for (const int k : c.selection->positions_used) {
      if (k < 0 || static_cast<std::size_t>(k) >= m) throw py::value_error("positions_used");
    }
  }
  if (c.gyroscope) {
    CheckEnum(c.gyroscope->model, "gyroscope model");
    CheckEnum(c.gyroscope->estimator, "gyroscope estimator");
    CheckEnum(c.gyroscope->unit, "gyroscope unit");
    for (const GyroRotation& t : c.gyroscope->rotations) {
      if (t.from >= m || t.to >= m) throw py::value_error("a turn's position out of range");
    }
  }
}

}  // namespace

std::string SaveState(const PyCalibration& c) {
  Json state = Json::object();
  state["format"] = kStateFormat;
  state["accelcal_version"] = std::string(Version());
  state["result"] = Saver::Save(c);
  const std::vector<std::uint8_t> cbor = Json::to_cbor(state);
  const std::string body(cbor.begin(), cbor.end());
  return std::string(kMagic) + Sha256Hex(body) + body;
}

PyCalibration LoadState(const std::string& bytes) {
  constexpr std::size_t kDigest = 64;
  if (bytes.size() < kMagic.size() + kDigest || bytes.compare(0, kMagic.size(), kMagic) != 0) {
    throw py::value_error("not a pickled accelcal CalibrationResult");
  }
  const std::string body = bytes.substr(kMagic.size() + kDigest);
  if (Sha256Hex(body) != bytes.substr(kMagic.size(), kDigest)) {
    throw py::value_error("a damaged pickled CalibrationResult: its SHA-256 does not match");
  }
  Json state;
  try {
    state = Json::from_cbor(body);
  } catch (const Json::exception& e) {
    throw py::value_error(std::string("not a pickled accelcal CalibrationResult: ") + e.what());
  }
  if (!state.is_object() || state.value("format", "") != kStateFormat) {
    throw py::value_error("not a pickled accelcal CalibrationResult");
  }
  const std::string version = state.value("accelcal_version", "");
  if (version != Version()) {
    throw py::value_error("a CalibrationResult pickled by accelcal " + version +
                          " cannot be read by " + std::string(Version()) +
                          ": carry results between versions as calibration files (to_json)");
  }
  PyCalibration c;
  try {
    Loader::Load(state.at("result"), c);
    Validate(c);
  } catch (const Json::exception& e) {
    throw py::value_error(std::string("a damaged pickled CalibrationResult: ") + e.what());
  } catch (const py::value_error& e) {
    throw py::value_error(std::string("a damaged pickled CalibrationResult: ") + e.what());
  }
  return c;
}

}  // namespace accelcal::python
