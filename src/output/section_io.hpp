#pragma once
// A sensor's section of the calibration file described once: a description is a function
// template `Describe(Io& io, Sensor& s)` that names each key, its type and the in-memory field it
// maps to, in the file's order. Walked with a SectionWriter it builds the section; walked with a
// SectionReader it fills the in-memory form from one, checking each key as the reader always has
// (its type, finiteness, shape), with errors naming the file and the key's path. Python pickles
// the same section (as CBOR), so writing, reading and pickling cannot drift apart.
//
// `Need::kRequired` keys must be present when read; every other key may be absent (a file written
// before the key existed), which leaves the field at its default, NaN for a number that may be
// null. A description branches on fields read before (the model) to state what follows.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "accelcal/names.hpp"
#include "accelcal/types.hpp"
#include "output/json_reader.hpp"

namespace accelcal::internal {

enum class Need { kOptional, kRequired };

// "a, b, c" (NameList) as "\"a\", \"b\" or \"c\"", as the messages spell choices.
inline std::string QuotedChoices(const std::string& list) {
  std::string out;
  std::size_t at = 0;
  while (at <= list.size()) {
    const std::size_t end = std::min(list.find(", ", at), list.size());
    if (!out.empty()) out += end == list.size() ? " or " : ", ";
    out += "\"" + list.substr(at, end - at) + "\"";
    at = end + 2;
  }
  return out;
}

class SectionWriter {
 public:
  static constexpr bool kReading = false;
  explicit SectionWriter(ordered_json* doc) : doc_(*doc) {}

  void Text(const char* key, std::string& v, Need = Need::kOptional) { doc_[key] = v; }
  template <typename E>
  void Choice(const char* key, E& v, Need = Need::kOptional) {
    doc_[key] = std::string(Name(v));
  }
  void Number(const char* key, double& v, Need = Need::kOptional) { doc_[key] = v; }
  // A number that may not exist: NaN (or none) written as null.
  void MaybeNumber(const char* key, double& v) {
    doc_[key] = std::isfinite(v) ? ordered_json(v) : ordered_json(nullptr);
  }
  void MaybeNumber(const char* key, std::optional<double>& v) {
    doc_[key] = v && std::isfinite(*v) ? ordered_json(*v) : ordered_json(nullptr);
  }
  void Count(const char* key, std::size_t& v, Need = Need::kOptional) { doc_[key] = v; }
  // A position's number in the file (1, 2, ...), 0-based in memory.
  void PositionNumber(const char* key, std::size_t& v, Need = Need::kOptional) {
    doc_[key] = v + 1;
  }
  void Whole(const char* key, int& v) { doc_[key] = v; }
  void Flag(const char* key, bool& v, Need = Need::kOptional) { doc_[key] = v; }
  void Vector(const char* key, Vec3& v, Need = Need::kOptional) { doc_[key] = Json(v); }
  void Matrix(const char* key, Mat33& v, Need = Need::kOptional) { doc_[key] = Json(v); }
  void Numbers(const char* key, std::vector<double>& v) { doc_[key] = v; }
  void Vectors(const char* key, std::vector<Vec3>& v, Need = Need::kOptional) {
    ordered_json list = ordered_json::array();
    for (const Vec3& x : v) list.push_back(Json(x));
    doc_[key] = list;
  }
  void Interval(const char* key, std::pair<double, double>& v, Need = Need::kOptional) {
    doc_[key] = {v.first, v.second};
  }
  // `covariance`: that of n parameters (`what`), null when empty (the parameters are taken as
  // exact); read: symmetric, its diagonal not negative.
  void Covariance(Eigen::MatrixXd& v, std::size_t /*n*/, const std::string& /*what*/) {
    doc_["covariance"] = v.size() > 0 ? Json(v) : ordered_json(nullptr);
  }
  // Written for people (or for other tools) from the fields; not read back.
  template <typename Make>
  void Derived(const char* key, Make&& make) {
    doc_[key] = make();
  }
  // Written as null; read: must be null or absent.
  void Null(const char* key, const char* /*why*/) { doc_[key] = nullptr; }
  template <typename Fields>
  void Object(const char* key, Fields&& fields, Need = Need::kOptional) {
    ordered_json sub = ordered_json::object();
    SectionWriter inner(&sub);
    fields(inner);
    doc_[key] = std::move(sub);
  }
  // An object that may not exist: `present` says whether it does; written as null when not (or
  // left out, `null_when_absent` false).
  template <typename Fields>
  void MaybeObject(const char* key, bool& present, Fields&& fields, bool null_when_absent = true) {
    if (present) {
      Object(key, std::forward<Fields>(fields));
    } else if (null_when_absent) {
      doc_[key] = nullptr;
    }
  }
  // A list of objects, each described by fields(io, element, index).
  template <typename T, typename Fields>
  void List(const char* key, std::vector<T>& v, Fields&& fields) {
    ordered_json list = ordered_json::array();
    for (std::size_t i = 0; i < v.size(); ++i) {
      ordered_json sub = ordered_json::object();
      SectionWriter inner(&sub);
      fields(inner, v[i], i);
      list.push_back(std::move(sub));
    }
    doc_[key] = std::move(list);
  }
  static ordered_json Json(const Vec3& v) { return ordered_json::array({v(0), v(1), v(2)}); }
  static ordered_json Json(const Mat33& m) { return Json(Eigen::MatrixXd(m)); }
  static ordered_json Json(const Eigen::MatrixXd& m) {
    ordered_json rows = ordered_json::array();
    for (Eigen::Index i = 0; i < m.rows(); ++i) {
      ordered_json row = ordered_json::array();
      for (Eigen::Index j = 0; j < m.cols(); ++j) row.push_back(m(i, j));
      rows.push_back(std::move(row));
    }
    return rows;
  }

 private:
  template <typename E>
  static std::string_view Name(E v) {
    return ToString(v);
  }
  ordered_json& doc_;
};

class SectionReader {
 public:
  static constexpr bool kReading = true;
  SectionReader(const Reader& r, const ordered_json& doc) : r_(r), doc_(doc) {
    if (!doc_.is_object()) r_.Fail("a section must be an object");
  }

  void Text(const char* key, std::string& v, Need need = Need::kOptional) {
    if (Has(key, need)) v = r_.Text(doc_, key);
  }
  template <typename E>
  void Choice(const char* key, E& v, Need need = Need::kOptional) {
    if (!Has(key, need)) return;
    const std::optional<E> e =
        doc_[key].is_string() ? FromName<E>(doc_[key].get<std::string>()) : std::nullopt;
    if (!e) r_.Fail(r_.Key(key) + " must be " + QuotedChoices(NameList<E>()));
    v = *e;
  }
  void Number(const char* key, double& v, Need need = Need::kOptional) {
    if (Has(key, need)) v = r_.Number(doc_[key], r_.Key(key));
  }
  void MaybeNumber(const char* key, double& v) {
    v = IsNull(key) ? std::nan("") : r_.Number(doc_[key], r_.Key(key));
  }
  void MaybeNumber(const char* key, std::optional<double>& v) {
    v = IsNull(key) ? std::nullopt : std::optional<double>(r_.Number(doc_[key], r_.Key(key)));
  }
  void Count(const char* key, std::size_t& v, Need need = Need::kOptional) {
    if (!Has(key, need)) return;
    const ordered_json& n = doc_[key];
    if (!n.is_number_unsigned() && !(n.is_number_integer() && n.get<std::int64_t>() >= 0)) {
      r_.Fail(r_.Key(key) + " must be a whole number >= 0");
    }
    v = doc_[key].get<std::size_t>();
  }
  void PositionNumber(const char* key, std::size_t& v, Need need = Need::kOptional) {
    if (!Has(key, need)) return;
    const double n = r_.Number(doc_[key], r_.Key(key));
    if (!(n >= 1 && n == std::floor(n) && n < 1e15)) {
      r_.Fail(r_.Key(key) + " must be a position's number (1, 2, ...)");
    }
    v = static_cast<std::size_t>(n) - 1;
  }
  void Whole(const char* key, int& v) {
    if (!Has(key, Need::kOptional)) return;
    const ordered_json& n = doc_[key];
    if (!n.is_number_integer() ||
        (n.is_number_unsigned()
             ? n.get<std::uint64_t>() > INT32_MAX
             : n.get<std::int64_t>() < INT32_MIN || n.get<std::int64_t>() > INT32_MAX)) {
      r_.Fail(r_.Key(key) + " must be a whole number");
    }
    v = doc_[key].get<int>();
  }
  void Flag(const char* key, bool& v, Need need = Need::kOptional) {
    if (!Has(key, need)) return;
    if (!doc_[key].is_boolean()) r_.Fail(r_.Key(key) + " must be true or false");
    v = doc_[key].get<bool>();
  }
  void Vector(const char* key, Vec3& v, Need need = Need::kOptional) {
    if (Has(key, need)) v = r_.Vector3(doc_, key);
  }
  void Matrix(const char* key, Mat33& v, Need need = Need::kOptional) {
    if (!Has(key, need)) return;
    const std::string shape = r_.Key(key) + " must be a 3x3 array";
    const ordered_json& m = doc_[key];
    if (!m.is_array() || m.size() != 3) r_.Fail(shape);
    for (int i = 0; i < 3; ++i) {
      if (!m[i].is_array() || m[i].size() != 3) r_.Fail(shape);
      for (int j = 0; j < 3; ++j) {
        v(i, j) = r_.Number(m[i][j], r_.Key(std::string(key) + "[" + std::to_string(i) + "][" +
                                            std::to_string(j) + "]"));
      }
    }
  }
  void Numbers(const char* key, std::vector<double>& v) {
    if (!Has(key, Need::kOptional)) return;
    if (!doc_[key].is_array()) r_.Fail(r_.Key(key) + " must be an array of numbers");
    v.clear();
    for (const ordered_json& x : doc_[key]) v.push_back(r_.Number(x, r_.Key(key)));
  }
  void Vectors(const char* key, std::vector<Vec3>& v, Need need = Need::kOptional) {
    if (!Has(key, need)) return;
    const std::string shape = r_.Key(key) + " must be an array of arrays of 3 numbers";
    if (!doc_[key].is_array()) r_.Fail(shape);
    v.clear();
    for (const ordered_json& x : doc_[key]) {
      if (!x.is_array() || x.size() != 3) r_.Fail(shape);
      v.emplace_back(r_.Number(x[0], r_.Key(key)), r_.Number(x[1], r_.Key(key)),
                     r_.Number(x[2], r_.Key(key)));
    }
  }
  void Interval(const char* key, std::pair<double, double>& v, Need need = Need::kOptional) {
    if (!Has(key, need)) return;
    const ordered_json& x = doc_[key];
    if (!x.is_array() || x.size() != 2) r_.Fail(r_.Key(key) + " must be 2 numbers");
    v = {r_.Number(x[0], r_.Key(key)), r_.Number(x[1], r_.Key(key))};
  }
  void Covariance(Eigen::MatrixXd& v, std::size_t n, const std::string& what);  // in _read.cpp
  template <typename Make>
  void Derived(const char* /*key*/, Make&& /*make*/) {}
  void Null(const char* key, const char* why) {
    if (!IsNull(key)) r_.Fail(r_.Key(key) + " must be null " + why);
  }
  template <typename Fields>
  void Object(const char* key, Fields&& fields, Need need = Need::kOptional) {
    if (!Has(key, need)) return;
    SectionReader inner(r_.Inside(key), r_.Object(doc_, key));
    fields(inner);
  }
  template <typename Fields>
  void MaybeObject(const char* key, bool& present, Fields&& fields, bool = true) {
    present = !IsNull(key);
    if (present) Object(key, std::forward<Fields>(fields));
  }
  template <typename T, typename Fields>
  void List(const char* key, std::vector<T>& v, Fields&& fields) {
    if (!Has(key, Need::kOptional)) return;
    if (!doc_[key].is_array()) r_.Fail(r_.Key(key) + " must be an array");
    const Reader each = r_.Inside(std::string(key) + "[]");
    v.clear();
    for (const ordered_json& x : doc_[key]) {
      if (!x.is_object()) r_.Fail(r_.Key(key) + " must hold objects");
      SectionReader inner(each, x);
      v.emplace_back();
      fields(inner, v.back(), v.size() - 1);
    }
  }
  [[noreturn]] void Fail(const std::string& reason) const { r_.Fail(reason); }
  std::string Key(const char* key) const { return r_.Key(key); }
  const Reader& reader() const { return r_; }

 private:
  bool Has(const char* key, Need need) const {
    if (doc_.contains(key)) return true;
    if (need == Need::kRequired) r_.Fail(r_.Key(key) + " is missing");
    return false;
  }
  bool IsNull(const char* key) const { return !doc_.contains(key) || doc_[key].is_null(); }
  Reader r_;
  const ordered_json& doc_;
};

}  // namespace accelcal::internal
