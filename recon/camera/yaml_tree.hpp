#pragma once
// A YAML document as plain nodes, built in one pass of libyaml's event parser (Debian libyaml-dev,
// the reference C implementation), for the calibration reader (calibration_yaml.cpp). Private to
// recon/camera.
//
// Why libyaml and not yaml-cpp: yaml-cpp 0.7's LoadAll never returned on a `,` outside a flow
// collection (upstream jbeder/yaml-cpp#1040), and its scanner took 330 us per fuzzed calibration
// under ASan against libyaml's 64 us (the same 2 439 texts; 145 against 5.7 us without ASan), which
// held fuzz_calib_yaml at ~1 300-3 000 exec/s.
//
// Why three flat buffers (nodes, children, text) and not a string and a vector per node: a node
// each, its text and its children were most of the reader's allocations (docs/reliability.md,
// "Fifth run"); a document now costs a handful, whatever its size.

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace naneye::recon::detail {

struct YamlNode {
  enum class Kind { null, scalar, sequence, map };
  Kind kind = Kind::null;
  int line = -1;         // 0-based line where the node starts
  std::string_view tag;  // "?" untagged (a plain scalar, or a collection), "!" a quoted scalar, else resolved
  std::string_view value;  // a scalar's text
  // A sequence's elements; a map's keys and values, alternating (a key given twice stays twice).
  // An alias is the node it names (shared, never copied: a node may be its own descendant).
  std::span<const YamlNode* const> items;

  bool is_null() const { return kind == Kind::null; }
  bool is_scalar() const { return kind == Kind::scalar; }
  bool is_sequence() const { return kind == Kind::sequence; }
  bool is_map() const { return kind == Kind::map; }
};

// Owns what its nodes point to. Moved, each vector hands over its storage and the views stay valid;
// a copy's would point into the original, so there is none.
struct YamlDocument {
  YamlDocument() = default;
  YamlDocument(YamlDocument&&) = default;
  YamlDocument& operator=(YamlDocument&&) = default;
  YamlDocument(const YamlDocument&) = delete;
  YamlDocument& operator=(const YamlDocument&) = delete;

  std::vector<YamlNode> nodes;
  std::vector<const YamlNode*> children;  // every collection's items, each collection's together
  std::vector<char> text;                 // every tag and scalar, back to back
  const YamlNode* root = nullptr;         // null: no document
  bool more_documents = false;            // a second document starts after this one
};

// Text that is not YAML: what the parser says and where (line 0-based, -1 unknown).
struct YamlProblem {
  std::string what;
  int line = -1;
};

struct YamlParse {
  YamlDocument document;
  std::optional<YamlProblem> problem;  // set: `document` is empty
};

// The first document of `text` (no NUL in it) and whether another starts after it: the parser is
// asked for the second document's start, never for its content. A problem is returned, not thrown:
// the caller throws its own error, once.
YamlParse parse_first_yaml_document(std::string_view text);

}  // namespace naneye::recon::detail
