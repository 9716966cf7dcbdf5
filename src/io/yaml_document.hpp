#pragma once
// A small YAML document (a configuration file such as batch's limits) read into a tree whose nodes
// carry their line, by libyaml's event parser (YAML 1.1). Only what a configuration needs is taken:
// mappings with scalar keys, sequences and scalars. Anchors and aliases, tags, several documents
// and a key given twice are refused, each with its line, so that a file never means something
// other than it says.

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace accelcal::internal {

struct YamlNode {
  enum class Kind { kScalar, kMapping, kSequence };
  Kind kind = Kind::kScalar;
  std::size_t line = 0;  ///< 1-based line where the node begins
  /// A scalar's text, and whether it was written plain (unquoted, so a number or a word).
  std::string scalar;
  bool plain = false;
  /// A mapping's entries in the file's order: key, the key's line, value.
  struct Entry {
    std::string key;
    std::size_t line = 0;
    YamlNode* value = nullptr;
  };
  std::vector<Entry> entries;
  std::vector<YamlNode*> items;  ///< a sequence's
};

/// The nodes of one document, owned; root() is its top node (an empty scalar for an empty file).
class YamlDocument {
 public:
  const YamlNode& root() const { return *root_; }

 private:
  friend YamlDocument ParseYaml(std::string_view text, const std::string& source);
  std::vector<std::unique_ptr<YamlNode>> nodes_;
  YamlNode* root_ = nullptr;
};

/// Nesting deeper than this is refused (no configuration needs it).
inline constexpr int kMaxYamlDepth = 32;

/// Parses `text`; throws InputError naming `source` and the line for a syntax error and for what
/// the file comment says is refused.
YamlDocument ParseYaml(std::string_view text, const std::string& source);

}  // namespace accelcal::internal
