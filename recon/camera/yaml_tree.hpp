#pragma once
// A YAML document as plain nodes, built in one pass of yaml-cpp's parser (its event API), for the
// calibration reader (calibration_yaml.cpp). YAML::Load's nodes cost a second parse to refuse a
// second document (yaml-cpp 0.7's LoadAll cannot be asked for two at most) and several shared
// allocations per node; these are kept in one deque and never share ownership.
// Private to recon/camera.

#include <yaml-cpp/mark.h>

#include <deque>
#include <string>
#include <vector>

namespace naneye::recon::detail {

struct YamlNode {
  enum class Kind { null, scalar, sequence, map };
  Kind kind = Kind::null;
  YAML::Mark mark;    // where the node starts (line -1: unknown)
  std::string tag;    // yaml-cpp's: "?" untagged (plain scalar), "!" a quoted scalar, else resolved
  std::string value;  // a scalar's text
  // A sequence's elements; a map's keys and values, alternating (a key given twice stays twice).
  // An alias is the node it names (shared, never copied: a node may be its own descendant).
  std::vector<const YamlNode*> items;

  bool is_null() const { return kind == Kind::null; }
  bool is_scalar() const { return kind == Kind::scalar; }
  bool is_sequence() const { return kind == Kind::sequence; }
  bool is_map() const { return kind == Kind::map; }
};

struct YamlDocument {
  // Moved, the deque hands over its storage and the nodes stay where they are; a copy's pointers
  // would point into the original.
  YamlDocument() = default;
  YamlDocument(YamlDocument&&) = default;
  YamlDocument& operator=(YamlDocument&&) = default;
  YamlDocument(const YamlDocument&) = delete;
  YamlDocument& operator=(const YamlDocument&) = delete;

  std::deque<YamlNode> nodes;      // owns every node; a deque keeps their addresses
  const YamlNode* root = nullptr;  // null: no document (or an empty one)
  bool more_documents = false;     // the text holds a second document after this one
};

// The first document of `text` and whether another follows (asking the parser for two documents at
// most: see calibration_yaml.cpp on yaml-cpp#1040). Throws YAML::Exception for invalid YAML in
// either.
YamlDocument parse_first_yaml_document(const std::string& text);

}  // namespace naneye::recon::detail
