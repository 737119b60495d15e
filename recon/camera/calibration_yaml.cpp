#include "calibration_yaml.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <optional>
#include <string_view>

#include "yaml_tree.hpp"

namespace naneye::recon::detail {
namespace {

// The resolved tag of `!!opencv-matrix`, the only tagged value FileStorage writes for a cv::Mat.
constexpr std::string_view kMatrixTag = "tag:yaml.org,2002:opencv-matrix";

// OpenCV's single-channel element types, as FileStorage names them in `dt` (CV_8U ... CV_16F).
constexpr std::string_view kDepthChars = "ucwsifdh";

// Each refuse_* sets the one message a refused text gets and returns what its caller returns for
// "refused" (std::nullopt, or false).
std::nullopt_t refuse_file(Refusal& r, const std::string& file, const std::string& problem) {
  r.message = file + ": " + problem;
  return std::nullopt;
}

std::nullopt_t refuse_key(Refusal& r, const std::string& file, const std::string& key, const YamlNode& at,
                          const std::string& problem) {
  const int line = at.line;  // -1 when the parser has no position
  r.message = file + ": key '" + key + "': " + problem +
              (line >= 0 ? " (line " + std::to_string(line + 1) + ")" : "");
  return std::nullopt;
}

// ASCII only, as YAML's own names are; no copy (this runs for every number in a file).
bool same_ignoring_case(std::string_view a, std::string_view b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                    [](unsigned char x, unsigned char y) { return std::tolower(x) == std::tolower(y); });
}

// A plain (unquoted) scalar as FileStorage writes a number: decimal, `0.`, exponents, and its
// `.Nan`, `.Inf`, `-.Inf`. Locale-independent (std::from_chars), the whole text or nothing.
std::optional<double> number(const YamlNode& n) {
  if (!n.is_scalar() || n.tag != "?") return std::nullopt;  // "!" marks a quoted scalar: a string
  std::string_view s = n.value;
  if (same_ignoring_case(s, ".nan")) return std::numeric_limits<double>::quiet_NaN();
  if (same_ignoring_case(s, ".inf") || same_ignoring_case(s, "+.inf"))
    return std::numeric_limits<double>::infinity();
  if (same_ignoring_case(s, "-.inf")) return -std::numeric_limits<double>::infinity();
  if (s.size() > 1 && s[0] == '+' && s[1] != '-') s.remove_prefix(1);
  double v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || s.empty()) return std::nullopt;
  return v;
}

// A piece of the file in a message: short, since a message is logged and shown in /v1/status.
std::string excerpt(std::string_view s) {
  constexpr std::size_t kMaxChars = 40;  // enough to recognise a value, not a dump of the file
  return "'" + std::string(s.substr(0, kMaxChars)) + (s.size() > kMaxChars ? "..." : "") + "'";
}

// What OpenCV's reader stores for a float matrix's entry; beyond float's range (casting is
// undefined there) the infinity it rounds to.
double nearest_float(double v) {
  if (std::abs(v) > std::numeric_limits<float>::max() && std::isfinite(v))
    return std::copysign(std::numeric_limits<double>::infinity(), v);
  return static_cast<double>(static_cast<float>(v));
}

// The value of `name` in a map, at most once (the parser keeps a repeated key twice): the node, null
// if absent, or nullopt (refused) if given twice.
std::optional<const YamlNode*> member(Refusal& r, const std::string& file, const std::string& key,
                                      const YamlNode& map, const std::string& name) {
  const YamlNode* found = nullptr;
  for (std::size_t i = 0; i + 1 < map.items.size(); i += 2) {
    const YamlNode& k = *map.items[i];
    if (!k.is_scalar() || k.value != name) continue;
    if (found != nullptr) return refuse_key(r, file, key, k, "'" + name + "' given twice");
    found = map.items[i + 1];
  }
  return found;
}

std::optional<int> dimension(Refusal& r, const std::string& file, const std::string& key, const YamlNode& map,
                             const std::string& name) {
  const auto n = member(r, file, key, map, name);
  if (!n) return std::nullopt;
  if (!*n) return refuse_key(r, file, key, map, "a matrix needs rows, cols, dt and data: no '" + name + "'");
  const YamlNode& node = **n;
  const auto v = number(node);
  if (!v || *v != std::floor(*v) || *v < 1 || *v > static_cast<double>(std::numeric_limits<int>::max()))
    return refuse_key(r, file, key, node,
                      "'" + name + "' must be a positive integer, not " + excerpt(node.value));
  return static_cast<int>(*v);
}

// An `!!opencv-matrix`: what cv::read(FileNode, Mat) reads, single-channel (every matrix of a rig).
std::optional<cv::Mat> matrix(Refusal& r, const std::string& file, const std::string& key,
                              const YamlNode& map) {
  if (map.tag != "?" && map.tag != kMatrixTag)
    return refuse_key(r, file, key, map, "a map tagged " + excerpt(map.tag) + ": not an opencv-matrix");
  const auto rows_given = dimension(r, file, key, map, "rows");
  if (!rows_given) return std::nullopt;
  const auto cols_given = dimension(r, file, key, map, "cols");
  if (!cols_given) return std::nullopt;
  const int rows = *rows_given, cols = *cols_given;
  const auto dt_given = member(r, file, key, map, "dt");
  if (!dt_given) return std::nullopt;
  const YamlNode* dt = *dt_given;
  if (dt == nullptr) return refuse_key(r, file, key, map, "a matrix needs rows, cols, dt and data: no 'dt'");
  const std::string type(dt->is_scalar() ? dt->value : "");
  if (type.size() != 1 || kDepthChars.find(type[0]) == std::string_view::npos)
    return refuse_key(
        r, file, key, *dt,
        "dt " + excerpt(type) + " is not a single-channel OpenCV type (one of u c w s i f d h)");
  const bool integral = std::string_view("ucwsi").find(type[0]) != std::string_view::npos;
  const bool single = type[0] == 'f';
  const auto data_given = member(r, file, key, map, "data");
  if (!data_given) return std::nullopt;
  const YamlNode* data_node = *data_given;
  if (data_node == nullptr || !data_node->is_sequence())
    return refuse_key(r, file, key, map, "data is not a sequence of numbers");
  const YamlNode& data = *data_node;
  const std::size_t given = data.items.size();
  if (given != static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols))
    return refuse_key(r, file, key, data,
                      "data has " + std::to_string(given) + " values but rows x cols is " +
                          std::to_string(rows) + "x" + std::to_string(cols));
  cv::Mat m(rows, cols, CV_64F);
  std::size_t i = 0;
  for (const YamlNode* element : data.items) {
    const YamlNode& e = *element;
    const auto v = number(e);
    if (!v)
      return refuse_key(
          r, file, key, e,
          "data value " + std::to_string(i + 1) + " (" + excerpt(e.value) + ") is not a number");
    if (integral && std::isfinite(*v) && *v != std::floor(*v))
      return refuse_key(
          r, file, key, e,
          "data value " + std::to_string(i + 1) + " is not an integer, as dt '" + type + "' says");
    // A float matrix holds what OpenCV's reader makes of the text: the nearest float (FileStorage
    // writes 9 significant digits, which name one float but not its double).
    m.at<double>(static_cast<int>(i / cols), static_cast<int>(i % cols)) = single ? nearest_float(*v) : *v;
    ++i;
  }
  return m;
}

}  // namespace

std::optional<std::vector<YamlKey>> read_calibration_yaml(const std::string& file, std::string_view text,
                                                          Refusal& r) {
  if (text.size() > kMaxCalibrationBytes) return refuse_file(r, file, "larger than 1 MiB: not a calibration");
  // No text file holds a NUL; it ended OpenCV's reader in a loop (hang_nul_byte.yaml), and a
  // calibration read by another program should not depend on what each makes of one.
  if (text.find('\0') != std::string_view::npos)
    return refuse_file(r, file, "holds a NUL byte: not a YAML text file");
  // FileStorage writes `%YAML:1.0` first and reads a file as YAML only when it begins with `%YAML`
  // (version 1.x); YAML wants `%YAML 1.x`. The line is checked, then left out up to its newline,
  // so that the parser's line numbers are still the file's.
  const std::size_t eol = std::min(text.find('\n'), text.size());
  const std::string_view first = text.substr(0, eol);
  if (!first.starts_with("%YAML:1.") && !first.starts_with("%YAML 1."))
    return refuse_file(
        r, file,
        "not an OpenCV FileStorage YAML file: the first line must be %YAML:1.0, as FileStorage writes it");
  text.remove_prefix(eol);

  // One document: the parser is asked whether a second one starts (yaml-cpp 0.7's LoadAll, asked
  // for all of them, never returned on a `,` outside a flow collection: hang_yamlcpp_loadall.yaml,
  // upstream jbeder/yaml-cpp#1040; kept in the corpus).
  YamlParse parse = parse_first_yaml_document(text);
  if (const auto& p = parse.problem)
    return refuse_file(r, file,
                       (p->line >= 0 ? "line " + std::to_string(p->line + 1) + ": " : std::string()) +
                           "not valid YAML: " + p->what);
  const YamlDocument& doc = parse.document;
  if (doc.more_documents)
    return refuse_file(r, file, "holds more than one YAML document; a calibration is one");
  if (doc.root == nullptr || doc.root->is_null()) return refuse_file(r, file, "holds no keys");
  const YamlNode& root = *doc.root;
  if (!root.is_map()) return refuse_file(r, file, "not a map of keys (the top level of a FileStorage file)");

  std::vector<YamlKey> keys;
  for (std::size_t i = 0; i + 1 < root.items.size(); i += 2) {
    const YamlNode& name = *root.items[i];
    if (!name.is_scalar() || name.value.empty())
      return refuse_file(r, file, "line " + std::to_string(name.line + 1) + ": a key that is not a name");
    YamlKey k{std::string(name.value), {}, {}};
    const YamlNode& v = *root.items[i + 1];
    const auto data =
        v.is_map() ? member(r, file, k.key, v, "data") : std::optional<const YamlNode*>(nullptr);
    if (!data) return std::nullopt;
    if (*data) {
      auto m = matrix(r, file, k.key, v);
      if (!m) return std::nullopt;
      k.value = std::move(*m);
    } else if (const auto x = number(v)) {
      k.value = cv::Mat(1, 1, CV_64F, cv::Scalar(*x));
    } else {
      k.skipped = v.is_map()        ? "a map without data"
                  : v.is_sequence() ? "a sequence"
                  : v.is_null()     ? "empty"
                                    : "a string (" + excerpt(v.value) + ")";
    }
    keys.push_back(std::move(k));
  }
  return keys;
}

}  // namespace naneye::recon::detail
