#pragma once
// A YAML document as plain nodes, built in one pass of libyaml's event parser (Debian libyaml-dev,
// the reference C implementation), for the calibration reader (calibration_yaml.cpp). Private to
// recon/camera.
//
// Why libyaml and not yaml-cpp: yaml-cpp 0.7's LoadAll never returned on a `,` outside a flow
// collection (upstream jbeder/yaml-cpp#1040), and its scanner took 330 us per fuzzed calibration
// under ASan against libyaml's 64 us (the same 2 439 texts; 145 against 5.7 us without ASan), which
// held fuzz_calib_yaml at ~1 300-3 000 exec/s.

#include <deque>
#include <stdexcept>
#include <string>
#include <vector>

namespace naneye::recon::detail {

struct YamlNode {
  enum class Kind { null, scalar, sequence, map };
  Kind kind = Kind::null;
  int line = -1;      // 0-based line where the node starts
  std::string tag;    // "?" untagged (a plain scalar, or a collection), "!" a quoted scalar, else resolved
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
  const YamlNode* root = nullptr;  // null: no document
  bool more_documents = false;     // a second document starts after this one
};

// Text that is not YAML: what the parser says and where (line 0-based, -1 unknown).
class YamlError : public std::runtime_error {
 public:
  YamlError(const std::string& problem, int line) : std::runtime_error(problem), line_(line) {}
  int line() const { return line_; }

 private:
  int line_;
};

// The first document of `text` (no NUL in it) and whether another starts after it: the parser is
// asked for the second document's start, never for its content. Throws YamlError.
YamlDocument parse_first_yaml_document(const std::string& text);

}  // namespace naneye::recon::detail
