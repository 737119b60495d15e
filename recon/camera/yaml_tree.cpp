#include "yaml_tree.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>

#include <sstream>

namespace naneye::recon::detail {
namespace {

// Builds the nodes of one document from the parser's events: each node goes into the collection
// open on top of the stack (a map's keys and values arrive alternately, so they alternate in items).
class TreeBuilder final : public YAML::EventHandler {
 public:
  explicit TreeBuilder(YamlDocument& doc) : doc_(doc) {}

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    add(make(YamlNode::Kind::null, mark, "", {}), anchor);
  }
  void OnAlias(const YAML::Mark&, YAML::anchor_t anchor) override {
    // The parser refuses an alias it has no anchor for (ParserException "unknown anchor").
    add(anchor < anchors_.size() ? anchors_[anchor] : nullptr, YAML::NullAnchor);
  }
  void OnScalar(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                const std::string& value) override {
    add(make(YamlNode::Kind::scalar, mark, tag, value), anchor);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    open(make(YamlNode::Kind::sequence, mark, tag, {}), anchor);
  }
  void OnSequenceEnd() override { open_.pop_back(); }
  void OnMapStart(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    open(make(YamlNode::Kind::map, mark, tag, {}), anchor);
  }
  void OnMapEnd() override { open_.pop_back(); }

 private:
  YamlNode* make(YamlNode::Kind kind, const YAML::Mark& mark, const std::string& tag,
                 const std::string& value) {
    return &doc_.nodes.emplace_back(YamlNode{kind, mark, tag, value, {}});
  }
  void add(const YamlNode* n, YAML::anchor_t anchor) {
    if (n == nullptr) return;
    // Anchors are numbered from 1 in the order the parser meets them, each once.
    if (anchor != YAML::NullAnchor) {
      if (anchors_.size() <= anchor) anchors_.resize(anchor + 1, nullptr);
      anchors_[anchor] = n;
    }
    if (open_.empty()) {
      if (doc_.root == nullptr) doc_.root = n;
    } else {
      open_.back()->items.push_back(n);
    }
  }
  void open(YamlNode* n, YAML::anchor_t anchor) {
    add(n, anchor);
    open_.push_back(n);
  }

  YamlDocument& doc_;
  std::vector<YamlNode*> open_;  // the collections being filled, innermost last
  std::vector<const YamlNode*> anchors_;
};

// Takes the parser's events and keeps none: the second document is only counted.
class DiscardEvents final : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
  }
  void OnMapEnd() override {}
};

}  // namespace

YamlDocument parse_first_yaml_document(const std::string& text) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  YamlDocument doc;
  TreeBuilder builder(doc);
  if (parser.HandleNextDocument(builder)) {
    DiscardEvents discard;
    doc.more_documents = parser.HandleNextDocument(discard);
  }
  return doc;
}

}  // namespace naneye::recon::detail
