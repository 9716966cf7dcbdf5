// ParseLimits (acceptance.hpp): a production line's limits file, YAML read by io/yaml_document,
// every key checked. Its schema is in docs/batch.md.
#include <cmath>

#include "accelcal/acceptance.hpp"
#include "accelcal/error.hpp"
#include "io/number_parser.hpp"
#include "io/yaml_document.hpp"

namespace accelcal {
namespace {

using internal::YamlNode;

class LimitsReader {
 public:
  explicit LimitsReader(const std::string& source) : source_(source) {}

  [[noreturn]] void Fail(std::size_t line, const std::string& reason) const {
    throw InputError(source_, line, reason);
  }

  const YamlNode& Mapping(const YamlNode& node, const std::string& what) const {
    if (node.kind != YamlNode::Kind::kMapping)
      Fail(node.line, what + " must be a mapping (key: value)");
    return node;
  }

  std::string Text(const YamlNode& node, const std::string& what) const {
    if (node.kind != YamlNode::Kind::kScalar || node.scalar.empty()) {
      Fail(node.line, what + " must be a word or a quoted text");
    }
    return node.scalar;
  }

  double Number(const YamlNode& node, const std::string& what) const {
    double value = 0;
    if (node.kind == YamlNode::Kind::kScalar && !node.plain) {
      Fail(node.line,
           what + " is the quoted text '" + node.scalar + "': write a number without quotes");
    }
    if (node.kind != YamlNode::Kind::kScalar || !internal::ParseNumber(node.scalar, &value) ||
        !std::isfinite(value)) {
      Fail(node.line,
           what + " must be a finite decimal number, not " +
               (node.kind == YamlNode::Kind::kScalar ? "'" + node.scalar + "'"
                                                     : std::string("a mapping or list")));
    }
    return value;
  }

  // The entries of a mapping, each key one of `known`.
  void CheckKeys(const YamlNode& node, const std::string& what,
                 std::initializer_list<const char*> known) const {
    for (const YamlNode::Entry& e : node.entries) {
      bool ok = false;
      std::string list;
      for (const char* k : known) {
        ok = ok || e.key == k;
        list += (list.empty() ? "" : ", ") + std::string(k);
      }
      if (!ok) Fail(e.line, "unknown key '" + e.key + "' in " + what + " (known: " + list + ")");
      if (!e.value) Fail(e.line, what + "." + e.key + " has no value");
    }
  }

 private:
  const std::string& source_;
};

const YamlNode* Find(const YamlNode& mapping, const char* key) {
  for (const YamlNode::Entry& e : mapping.entries) {
    if (e.key == key) return e.value;
  }
  return nullptr;
}

}  // namespace

AcceptanceLimits ParseLimits(std::string_view text, const std::string& source) {
  const internal::YamlDocument doc = internal::ParseYaml(text, source);
  const LimitsReader r(source);
  const YamlNode& root = doc.root();
  if (root.kind == YamlNode::Kind::kScalar && root.scalar.empty()) {
    r.Fail(0, "empty: a limits file begins 'format: accelcal-limits' (see docs/batch.md)");
  }
  r.Mapping(root, "a limits file");
  r.CheckKeys(root, "the file", {"format", "version", "part", "units", "limits", "diagnosis"});
  const YamlNode* format = Find(root, "format");
  if (!format || format->kind != YamlNode::Kind::kScalar || format->scalar != "accelcal-limits") {
    r.Fail(format ? format->line : root.line,
           "not a limits file: it must say 'format: accelcal-limits' (see docs/batch.md)");
  }
  const YamlNode* version = Find(root, "version");
  if (!version) r.Fail(format->line, "no 'version: 1' (the limits schema's version)");
  if (r.Number(*version, "version") != 1) {
    r.Fail(version->line, "version " + version->scalar + ": this accelcal reads version 1");
  }
  AcceptanceLimits limits;
  limits.source = source;
  if (const YamlNode* part = Find(root, "part")) limits.part = r.Text(*part, "part");
  if (const YamlNode* units = Find(root, "units")) {
    r.CheckKeys(r.Mapping(*units, "units"), "units", {"specific_force", "raw"});
    if (const YamlNode* force = Find(*units, "specific_force")) {
      const std::optional<ForceUnit> unit =
          ForceUnitFromString(r.Text(*force, "units.specific_force"));
      if (!unit) r.Fail(force->line, "units.specific_force '" + force->scalar + "': m/s2 or g");
      limits.specific_force_unit = *unit;
    }
    if (const YamlNode* raw = Find(*units, "raw")) limits.raw_unit = r.Text(*raw, "units.raw");
  }
  if (const YamlNode* diagnosis = Find(root, "diagnosis")) {
    r.CheckKeys(r.Mapping(*diagnosis, "diagnosis"), "diagnosis", {"max_severity"});
    if (const YamlNode* severity = Find(*diagnosis, "max_severity")) {
      const std::string word = r.Text(*severity, "diagnosis.max_severity");
      for (const auto& [value, name] : EnumNames<Severity>::kTable) {
        if (word == name) limits.max_severity = value;
      }
      if (!limits.max_severity) {
        r.Fail(severity->line, "diagnosis.max_severity '" + word + "': note, warning or failure");
      }
    }
  }
  if (const YamlNode* list = Find(root, "limits")) {
    r.Mapping(*list, "limits");
    for (const YamlNode::Entry& e : list->entries) {
      Limit limit;
      limit.line = e.line;
      limit.pattern = e.key;
      const std::string sigma_suffix = ".sigma";
      if (limit.pattern.size() > sigma_suffix.size() &&
          limit.pattern.compare(limit.pattern.size() - sigma_suffix.size(), sigma_suffix.size(),
                                sigma_suffix) == 0) {
        limit.pattern.resize(limit.pattern.size() - sigma_suffix.size());
        limit.statistic = LimitStatistic::kSigma;
      }
      bool named = false, has_sigma = false;
      for (const QuantityName& q : KnownQuantityNames()) {
        if (!QuantityMatches(limit.pattern, q.name)) continue;
        named = true;
        has_sigma = has_sigma || q.has_sigma;
      }
      if (!named) {
        r.Fail(e.line, "'" + limit.pattern +
                           "' names no quantity (they are listed in "
                           "docs/batch.md, e.g. accelerometer.b_x, accelerometer.heldout_rms)");
      }
      if (limit.statistic == LimitStatistic::kSigma && !has_sigma) {
        r.Fail(e.line, "'" + e.key + "': " + limit.pattern + " has no 1 sigma to bound");
      }
      if (!e.value) r.Fail(e.line, "'" + e.key + "' has no bounds (min, max, abs_max)");
      r.CheckKeys(r.Mapping(*e.value, "'" + e.key + "'"), "'" + e.key + "'",
                  {"min", "max", "abs_max"});
      if (const YamlNode* v = Find(*e.value, "min")) limit.min = r.Number(*v, e.key + ".min");
      if (const YamlNode* v = Find(*e.value, "max")) limit.max = r.Number(*v, e.key + ".max");
      if (const YamlNode* v = Find(*e.value, "abs_max")) {
        limit.abs_max = r.Number(*v, e.key + ".abs_max");
        if (*limit.abs_max < 0) r.Fail(v->line, e.key + ".abs_max is negative");
      }
      if (!limit.min && !limit.max && !limit.abs_max) {
        r.Fail(e.line, "'" + e.key + "' has no bounds (min, max, abs_max)");
      }
      if (limit.min && limit.max && *limit.min > *limit.max) {
        r.Fail(e.line, "'" + e.key + "': min is above max, so no value can pass");
      }
      limits.limits.push_back(std::move(limit));
    }
  }
  if (limits.limits.empty() && !limits.max_severity) {
    r.Fail(root.line, "nothing to check: give limits or diagnosis.max_severity");
  }
  return limits;
}

}  // namespace accelcal
