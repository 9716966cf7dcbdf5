// ParseYaml (yaml_document.hpp): libyaml's events folded into a tree, without recursion.
#include "io/yaml_document.hpp"

#include <yaml.h>

#include <map>
#include <memory>

#include "accelcal/error.hpp"

namespace accelcal::internal {
namespace {

// The parser and its current event, released however the parse ends.
struct Parser {
  yaml_parser_t parser;
  yaml_event_t event;
  bool has_event = false;
  Parser() {
    if (!yaml_parser_initialize(&parser)) throw std::bad_alloc();
  }
  ~Parser() {
    if (has_event) yaml_event_delete(&event);
    yaml_parser_delete(&parser);
  }
  Parser(const Parser&) = delete;
  Parser& operator=(const Parser&) = delete;
};

std::size_t LineOf(const yaml_mark_t& mark) { return mark.line + 1; }

}  // namespace

YamlDocument ParseYaml(std::string_view text, const std::string& source) {
  YamlDocument doc;
  Parser p;
  yaml_parser_set_input_string(&p.parser, reinterpret_cast<const unsigned char*>(text.data()),
                               text.size());
  const auto fail = [&](std::size_t line, const std::string& reason) -> void {
    throw InputError(source, line, reason);
  };
  const auto node = [&](YamlNode::Kind kind, std::size_t line) {
    doc.nodes_.push_back(std::make_unique<YamlNode>());
    YamlNode* n = doc.nodes_.back().get();
    n->kind = kind;
    n->line = line;
    return n;
  };
  // The open mappings and sequences, innermost last; a mapping whose key has been read waits
  // for its value.
  struct Open {
    YamlNode* node;
    bool key_read = false;
    std::map<std::string, std::size_t> keys;  // a mapping's keys and their lines
  };
  std::vector<Open> open;
  int documents = 0;
  // Places a finished scalar, or a new mapping or sequence, in its parent.
  const auto attach = [&](YamlNode* n) {
    if (open.empty()) {
      doc.root_ = n;
      return;
    }
    Open& parent = open.back();
    if (parent.node->kind == YamlNode::Kind::kSequence) {
      parent.node->items.push_back(n);
      return;
    }
    if (!parent.key_read) {
      if (n->kind != YamlNode::Kind::kScalar) {
        fail(n->line, "a key must be a plain word, not a mapping or a list");
      }
      if (const auto [at, fresh] = parent.keys.emplace(n->scalar, n->line); !fresh) {
        fail(n->line,
             "'" + n->scalar + "' given twice (first at line " + std::to_string(at->second) + ")");
      }
      parent.node->entries.push_back({n->scalar, n->line, nullptr});
      parent.key_read = true;
      return;
    }
    parent.node->entries.back().value = n;
    parent.key_read = false;
  };
  for (;;) {
    if (!yaml_parser_parse(&p.parser, &p.event)) {
      const yaml_mark_t& mark = p.parser.problem_mark;
      std::string reason = p.parser.problem ? p.parser.problem : "not YAML";
      if (p.parser.context) reason = std::string(p.parser.context) + ": " + reason;
      fail(LineOf(mark), "not valid YAML: " + reason);
    }
    p.has_event = true;
    const yaml_event_t& e = p.event;
    const std::size_t line = LineOf(e.start_mark);
    bool done = false;
    switch (e.type) {
      case YAML_DOCUMENT_START_EVENT:
        if (++documents > 1) fail(line, "a second document ('---'): give one");
        break;
      case YAML_ALIAS_EVENT:
        fail(line, "an alias ('*'): write the value out (anchors and aliases are not taken)");
        break;
      case YAML_SCALAR_EVENT: {
        if (e.data.scalar.anchor) fail(line, "an anchor ('&'): anchors are not taken");
        if (e.data.scalar.tag && !e.data.scalar.plain_implicit && !e.data.scalar.quoted_implicit) {
          fail(line, "a tag ('!'): tags are not taken");
        }
        YamlNode* n = node(YamlNode::Kind::kScalar, line);
        n->scalar.assign(reinterpret_cast<const char*>(e.data.scalar.value), e.data.scalar.length);
        n->plain = e.data.scalar.style == YAML_PLAIN_SCALAR_STYLE;
        attach(n);
        break;
      }
      case YAML_MAPPING_START_EVENT:
      case YAML_SEQUENCE_START_EVENT: {
        const bool mapping = e.type == YAML_MAPPING_START_EVENT;
        const auto& start = mapping ? e.data.mapping_start.anchor : e.data.sequence_start.anchor;
        if (start) fail(line, "an anchor ('&'): anchors are not taken");
        const bool tagged = mapping ? e.data.mapping_start.tag && !e.data.mapping_start.implicit
                                    : e.data.sequence_start.tag && !e.data.sequence_start.implicit;
        if (tagged) fail(line, "a tag ('!'): tags are not taken");
        if (static_cast<int>(open.size()) >= kMaxYamlDepth) {
          fail(line, "nested more than " + std::to_string(kMaxYamlDepth) + " deep");
        }
        YamlNode* n = node(mapping ? YamlNode::Kind::kMapping : YamlNode::Kind::kSequence, line);
        attach(n);
        open.push_back({n, false, {}});
        break;
      }
      case YAML_MAPPING_END_EVENT:
      case YAML_SEQUENCE_END_EVENT:
        open.pop_back();
        break;
      case YAML_STREAM_END_EVENT:
        done = true;
        break;
      default:  // stream and document starts and ends, no event
        break;
    }
    yaml_event_delete(&p.event);
    p.has_event = false;
    if (done) break;
  }
  if (!doc.root_) doc.root_ = node(YamlNode::Kind::kScalar, 1);  // an empty file
  return doc;
}

}  // namespace accelcal::internal
