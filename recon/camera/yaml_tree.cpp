#include "yaml_tree.hpp"

#include <yaml.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <utility>

namespace naneye::recon::detail {
namespace {

using Parser = std::unique_ptr<yaml_parser_t, void (*)(yaml_parser_t*)>;
using Event = std::unique_ptr<yaml_event_t, void (*)(yaml_event_t*)>;

YamlProblem problem_of(const yaml_parser_t& p) {
  std::string what = p.problem ? p.problem : "unreadable";
  if (p.context) what = std::string(p.context) + ": " + what;
  return YamlProblem{std::move(what), static_cast<int>(p.problem_mark.line)};
}

std::string_view view_of(const yaml_char_t* s) {
  return s ? std::string_view(reinterpret_cast<const char*>(s)) : std::string_view();
}

// The core schema's null (YAML 1.2, 10.3.2) as yaml-cpp read it: an untagged plain scalar that is
// empty, `~` or null. `key:` with nothing after it is such an empty scalar.
bool is_null_text(std::string_view s) {
  return s.empty() || s == "~" || s == "null" || s == "Null" || s == "NULL";
}

// A node while its document is read: its text and its children as places in the document's
// buffers, which grow (and move) until the end; finish() turns them into views. 32-bit places: the
// reader takes at most 1 MiB of text (calibration_yaml.hpp), which with its default tags is at most
// ~8 MiB of tags and scalars (`!!x` stands for 19 bytes).
struct Pending {
  YamlNode::Kind kind;
  char fixed_tag;  // '?' or '!' (the tag is that), else 0 and the tag is at tag_at
  int line;
  std::uint32_t tag_at, tag_size, value_at, value_size;
  std::uint32_t first_child = 0, child_count = 0;
};

// Builds the nodes of one document from the parser's events. A collection's items wait on one stack
// (a map's keys and values arrive alternately, so they alternate there) until it ends; then they go,
// together, to the document's children.
class TreeBuilder {
 public:
  // Sized once for `text_size` bytes of YAML rather than grown from nothing (each growth is an
  // allocation and a copy): the scalars' text is at most the text (escapes only shorten it; a
  // resolved tag can be longer than its shorthand, and grows the buffer then), and a node takes at
  // least two bytes (`a,`, `- `); config/calib/paper-d3.yaml, 2.3 kB, has 186 nodes.
  TreeBuilder(YamlDocument& doc, std::size_t text_size) : doc_(doc) {
    constexpr std::size_t kTypicalNodes = 256;
    const std::size_t nodes = std::min(kTypicalNodes, text_size / 2 + 1);
    doc_.text.reserve(text_size);
    pending_.reserve(nodes);
    items_.reserve(nodes);
    child_index_.reserve(nodes);
  }

  // Takes one event of the first document; false once the document has ended or on a problem.
  bool take(const yaml_event_t& e) {
    const int line = static_cast<int>(e.start_mark.line);
    switch (e.type) {
      case YAML_SCALAR_EVENT: {
        const auto& s = e.data.scalar;
        const std::string_view value(reinterpret_cast<const char*>(s.value), s.length);
        const bool plain = s.style == YAML_PLAIN_SCALAR_STYLE;
        const std::string_view tag = s.tag ? view_of(s.tag) : plain ? "?" : "!";
        const bool null = s.tag == nullptr && plain && is_null_text(value);
        add(make(null ? YamlNode::Kind::null : YamlNode::Kind::scalar, line, tag, null ? "" : value),
            s.anchor);
        return true;
      }
      case YAML_SEQUENCE_START_EVENT:
        open(make(YamlNode::Kind::sequence, line, tag_or_untagged(e.data.sequence_start.tag), ""),
             e.data.sequence_start.anchor);
        return true;
      case YAML_MAPPING_START_EVENT:
        open(make(YamlNode::Kind::map, line, tag_or_untagged(e.data.mapping_start.tag), ""),
             e.data.mapping_start.anchor);
        return true;
      case YAML_SEQUENCE_END_EVENT:
      case YAML_MAPPING_END_EVENT:
        close();
        return true;
      case YAML_ALIAS_EVENT: {
        // libyaml leaves aliases to the composer: an alias before (or without) its anchor is ours to
        // refuse. The latest node of that name counts (an anchor may be given again).
        const std::string name(view_of(e.data.alias.anchor));
        const auto it = anchors_.find(name);
        if (it == anchors_.end()) {
          problem_ = YamlProblem{"unknown anchor '" + name.substr(0, 40) + "'", line};
          return false;
        }
        add(it->second, nullptr);
        return true;
      }
      case YAML_DOCUMENT_START_EVENT:
        // A %TAG directive makes a handle stand for any prefix, which libyaml then copies into every
        // node's tag: a 1 MiB text could ask for gigabytes. FileStorage writes none.
        if (e.data.document_start.tag_directives.start != e.data.document_start.tag_directives.end) {
          problem_ = YamlProblem{"a %TAG directive (FileStorage writes none)", line};
          return false;
        }
        return true;
      case YAML_DOCUMENT_END_EVENT:
        return false;
      default:  // the stream's start
        return true;
    }
  }

  std::optional<YamlProblem>& problem() { return problem_; }

  // The nodes, with views into the document's buffers, which are now their final size.
  void finish() {
    doc_.nodes.reserve(pending_.size());
    const char* text = doc_.text.data();
    for (const Pending& p : pending_) {
      const std::string_view tag = p.fixed_tag == '?'   ? "?"
                                   : p.fixed_tag == '!' ? "!"
                                                        : std::string_view(text + p.tag_at, p.tag_size);
      doc_.nodes.push_back(
          YamlNode{p.kind, p.line, tag, std::string_view(text + p.value_at, p.value_size), {}});
    }
    doc_.children.reserve(child_index_.size());
    for (const std::uint32_t i : child_index_) doc_.children.push_back(&doc_.nodes[i]);
    for (std::size_t i = 0; i < pending_.size(); ++i) {
      doc_.nodes[i].items = std::span<const YamlNode* const>(doc_.children.data() + pending_[i].first_child,
                                                             pending_[i].child_count);
    }
    if (root_) doc_.root = &doc_.nodes[*root_];
  }

 private:
  static std::string_view tag_or_untagged(const yaml_char_t* tag) { return tag ? view_of(tag) : "?"; }

  std::uint32_t keep(std::string_view s) {
    const auto at = static_cast<std::uint32_t>(doc_.text.size());
    doc_.text.insert(doc_.text.end(), s.begin(), s.end());
    return at;
  }
  // `tag` is "?", "!" or libyaml's text of a tag, which the event owns: only the latter is kept.
  std::uint32_t make(YamlNode::Kind kind, int line, std::string_view tag, std::string_view value) {
    const char fixed_tag = tag == "?" ? '?' : tag == "!" ? '!' : '\0';
    const std::uint32_t tag_at = fixed_tag ? 0 : keep(tag);
    const std::uint32_t value_at = keep(value);
    pending_.push_back(Pending{kind, fixed_tag, line, tag_at, static_cast<std::uint32_t>(tag.size()),
                               value_at, static_cast<std::uint32_t>(value.size())});
    return static_cast<std::uint32_t>(pending_.size() - 1);
  }
  void add(std::uint32_t n, const yaml_char_t* anchor) {
    if (anchor) anchors_[std::string(view_of(anchor))] = n;
    if (open_.empty()) {
      if (!root_) root_ = n;
    } else {
      items_.push_back(n);
    }
  }
  void open(std::uint32_t n, const yaml_char_t* anchor) {
    add(n, anchor);
    open_.push_back(Open{n, items_.size()});
  }
  void close() {
    const Open o = open_.back();
    open_.pop_back();
    Pending& p = pending_[o.node];
    p.first_child = static_cast<std::uint32_t>(child_index_.size());
    p.child_count = static_cast<std::uint32_t>(items_.size() - o.first_item);
    child_index_.insert(child_index_.end(), items_.begin() + static_cast<std::ptrdiff_t>(o.first_item),
                        items_.end());
    items_.resize(o.first_item);
  }

  struct Open {
    std::uint32_t node;
    std::size_t first_item;  // where its items start on items_
  };

  YamlDocument& doc_;
  std::vector<Pending> pending_;
  std::vector<Open> open_;                  // the collections being filled, innermost last
  std::vector<std::uint32_t> items_;        // their items so far, the innermost's on top
  std::vector<std::uint32_t> child_index_;  // the items of the collections that have ended
  std::optional<std::uint32_t> root_;
  std::optional<YamlProblem> problem_;
  // By name, hashed: a file of many anchors and aliases must not cost their product.
  std::unordered_map<std::string, std::uint32_t> anchors_;
};

}  // namespace

YamlParse parse_first_yaml_document(std::string_view text) {
  yaml_parser_t parser_state;
  if (!yaml_parser_initialize(&parser_state)) throw std::bad_alloc();
  const Parser parser(&parser_state, yaml_parser_delete);
  yaml_parser_set_input_string(parser.get(), reinterpret_cast<const unsigned char*>(text.data()),
                               text.size());

  YamlParse out;
  TreeBuilder builder(out.document, text.size());
  bool first_done = false;
  for (;;) {
    yaml_event_t event_state;
    if (!yaml_parser_parse(parser.get(), &event_state)) {
      out.problem = problem_of(*parser);
      break;
    }
    const Event event(&event_state, yaml_event_delete);
    const yaml_event_type_t type = event->type;
    if (type == YAML_STREAM_END_EVENT) break;
    if (type == YAML_DOCUMENT_START_EVENT && first_done) {
      out.document.more_documents = true;
      break;
    }
    // The stream's start and the document's go to the builder too, which passes over them.
    if (!first_done && !builder.take(*event)) {
      if (builder.problem()) {
        out.problem = std::move(builder.problem());
        break;
      }
      first_done = true;
    }
  }
  if (out.problem) {
    out.document = YamlDocument();
  } else {
    builder.finish();
  }
  return out;
}

}  // namespace naneye::recon::detail
