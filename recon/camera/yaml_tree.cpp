#include "yaml_tree.hpp"

#include <yaml.h>

#include <memory>
#include <string_view>
#include <unordered_map>
#include <utility>

namespace naneye::recon::detail {
namespace {

using Parser = std::unique_ptr<yaml_parser_t, void (*)(yaml_parser_t*)>;
using Event = std::unique_ptr<yaml_event_t, void (*)(yaml_event_t*)>;

[[noreturn]] void fail(const yaml_parser_t& p) {
  std::string problem = p.problem ? p.problem : "unreadable";
  if (p.context) problem = std::string(p.context) + ": " + problem;
  throw YamlError(problem, static_cast<int>(p.problem_mark.line));
}

std::string text_of(const yaml_char_t* s) {
  return s ? reinterpret_cast<const char*>(s) : std::string();
}

// The core schema's null (YAML 1.2, 10.3.2) as yaml-cpp read it: an untagged plain scalar that is
// empty, `~` or null. `key:` with nothing after it is such an empty scalar.
bool is_null_text(std::string_view s) {
  return s.empty() || s == "~" || s == "null" || s == "Null" || s == "NULL";
}

// Builds the nodes of one document from the parser's events: each node goes into the collection
// open on top of the stack (a map's keys and values arrive alternately, so they alternate in items).
class TreeBuilder {
 public:
  explicit TreeBuilder(YamlDocument& doc) : doc_(doc) {}

  // Takes one event of the first document; false once the document has ended.
  bool take(const yaml_event_t& e) {
    const int line = static_cast<int>(e.start_mark.line);
    switch (e.type) {
      case YAML_SCALAR_EVENT: {
        const auto& s = e.data.scalar;
        std::string value(reinterpret_cast<const char*>(s.value), s.length);
        const bool plain = s.style == YAML_PLAIN_SCALAR_STYLE;
        std::string tag = s.tag ? text_of(s.tag) : plain ? "?" : "!";
        const bool null = s.tag == nullptr && plain && is_null_text(value);
        add(make(null ? YamlNode::Kind::null : YamlNode::Kind::scalar, line, std::move(tag),
                 null ? std::string() : std::move(value)),
            s.anchor);
        return true;
      }
      case YAML_SEQUENCE_START_EVENT:
        open(make(YamlNode::Kind::sequence, line, tag_or_untagged(e.data.sequence_start.tag), {}),
             e.data.sequence_start.anchor);
        return true;
      case YAML_MAPPING_START_EVENT:
        open(make(YamlNode::Kind::map, line, tag_or_untagged(e.data.mapping_start.tag), {}),
             e.data.mapping_start.anchor);
        return true;
      case YAML_SEQUENCE_END_EVENT:
      case YAML_MAPPING_END_EVENT:
        open_.pop_back();
        return true;
      case YAML_ALIAS_EVENT: {
        // libyaml leaves aliases to the composer: an alias before (or without) its anchor is ours to
        // refuse. The latest node of that name counts (an anchor may be given again).
        const std::string name = text_of(e.data.alias.anchor);
        const auto it = anchors_.find(name);
        if (it == anchors_.end()) throw YamlError("unknown anchor '" + name.substr(0, 40) + "'", line);
        add(it->second, nullptr);
        return true;
      }
      case YAML_DOCUMENT_END_EVENT:
        return false;
      default:  // stream and document starts
        return true;
    }
  }

 private:
  static std::string tag_or_untagged(const yaml_char_t* tag) { return tag ? text_of(tag) : "?"; }
  YamlNode* make(YamlNode::Kind kind, int line, std::string tag, std::string value) {
    return &doc_.nodes.emplace_back(YamlNode{kind, line, std::move(tag), std::move(value), {}});
  }
  void add(const YamlNode* n, const yaml_char_t* anchor) {
    if (anchor) anchors_[text_of(anchor)] = n;
    if (open_.empty()) {
      if (doc_.root == nullptr) doc_.root = n;
    } else {
      open_.back()->items.push_back(n);
    }
  }
  void open(YamlNode* n, const yaml_char_t* anchor) {
    add(n, anchor);
    open_.push_back(n);
  }

  YamlDocument& doc_;
  std::vector<YamlNode*> open_;  // the collections being filled, innermost last
  // By name, hashed: a file of many anchors and aliases must not cost their product.
  std::unordered_map<std::string, const YamlNode*> anchors_;
};

}  // namespace

YamlDocument parse_first_yaml_document(const std::string& text) {
  yaml_parser_t parser_state;
  if (!yaml_parser_initialize(&parser_state)) throw std::bad_alloc();
  const Parser parser(&parser_state, yaml_parser_delete);
  yaml_parser_set_input_string(parser.get(), reinterpret_cast<const unsigned char*>(text.data()),
                               text.size());

  YamlDocument doc;
  TreeBuilder builder(doc);
  bool first_done = false;
  for (;;) {
    yaml_event_t event_state;
    if (!yaml_parser_parse(parser.get(), &event_state)) fail(*parser);
    const Event event(&event_state, yaml_event_delete);
    const yaml_event_type_t type = event->type;
    if (type == YAML_STREAM_END_EVENT) break;
    if (type == YAML_DOCUMENT_START_EVENT && first_done) {
      doc.more_documents = true;
      break;
    }
    // The stream's start and the document's go to the builder too, which passes over them.
    if (!first_done && !builder.take(*event)) first_done = true;
  }
  return doc;
}

}  // namespace naneye::recon::detail
