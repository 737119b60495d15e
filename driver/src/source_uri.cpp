#include "naneye/driver/source_uri.hpp"
#include "naneye/base/enum_table.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>

namespace naneye::driver {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string percent_decode(std::string_view s, std::string_view whole) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '%') {
      out += s[i];
      continue;
    }
    const int hi = i + 2 < s.size() ? hex_digit(s[i + 1]) : -1;
    const int lo = i + 2 < s.size() ? hex_digit(s[i + 2]) : -1;
    if (hi < 0 || lo < 0)
      throw SourceError("bad percent escape in '" + std::string(whole) +
                        "': expected %XX with two hex digits");
    out += static_cast<char>(hi * 16 + lo);
    i += 2;
  }
  return out;
}

[[noreturn]] void bad_value(const SourceUri& uri, std::string_view name, std::string_view value,
                            std::string_view accepted) {
  throw SourceError(uri.scheme + "://: parameter '" + std::string(name) + "' has a bad value '" +
                    std::string(value) + "'; accepted: " + std::string(accepted));
}

template <class T>
std::optional<T> parse_int(std::string_view s, int base = 10) {
  if (base == 16 && (s.starts_with("0x") || s.starts_with("0X"))) s.remove_prefix(2);
  T v{};
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v, base);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size() || s.empty()) return std::nullopt;
  return v;
}

std::optional<double> parse_double(const std::string& s) {
  if (s.empty()) return std::nullopt;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

bool parse_bool(const SourceUri& uri, std::string_view name, const std::string& v) {
  if (v == "1" || v == "true" || v == "yes" || v == "on") return true;
  if (v == "0" || v == "false" || v == "no" || v == "off") return false;
  bad_value(uri, name, v, "0 or 1");
}

std::vector<std::string_view> with_stream(std::initializer_list<std::string_view> own) {
  std::vector<std::string_view> v(own);
  v.insert(v.end(), kStreamParams.begin(), kStreamParams.end());
  return v;
}

void allow(const SourceUri& uri, const std::vector<std::string_view>& accepted) {
  for (const auto& [name, value] : uri.params) {
    if (std::find(accepted.begin(), accepted.end(), name) != accepted.end()) continue;
    std::string list;
    for (auto a : accepted) list += (list.empty() ? "" : ", ") + std::string(a);
    throw SourceError(uri.scheme + "://: unknown parameter '" + name + "'; accepted: " + list);
  }
}

}  // namespace

std::optional<std::string> SourceUri::param(std::string_view name) const {
  std::optional<std::string> v;
  for (const auto& [k, value] : params)
    if (k == name) v = value;  // the last one wins
  return v;
}

void SourceUri::allow_only(std::initializer_list<std::string_view> accepted) const {
  allow(*this, std::vector<std::string_view>(accepted));
}

SourceUri parse_uri(std::string_view text) {
  SourceUri u;
  u.text = std::string(text);
  if (text.empty()) throw SourceError("empty source URI: expected usb://, v4l2://, file:// or a file path");
  const auto sep = text.find("://");
  std::string_view rest;
  if (sep == std::string_view::npos) {
    u.scheme = "file";
    u.target = std::string(text);  // a plain path is taken literally (no query, no escapes)
    return u;
  }
  u.scheme = lower(text.substr(0, sep));
  if (u.scheme.empty() || !std::all_of(u.scheme.begin(), u.scheme.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '+' || c == '-' || c == '.';
      }))
    throw SourceError("bad URI scheme in '" + std::string(text) + "'");
  rest = text.substr(sep + 3);
  const auto q = rest.find('?');
  u.target = percent_decode(rest.substr(0, q), text);
  if (q != std::string_view::npos) {
    std::string_view query = rest.substr(q + 1);
    while (!query.empty()) {
      const auto amp = query.find('&');
      const std::string_view item = query.substr(0, amp);
      if (!item.empty()) {
        const auto eq = item.find('=');
        std::string name = percent_decode(item.substr(0, eq), text);
        std::string value = eq == std::string_view::npos ? "" : percent_decode(item.substr(eq + 1), text);
        if (name.empty()) throw SourceError("empty parameter name in '" + std::string(text) + "'");
        u.params.emplace_back(std::move(name), std::move(value));
      }
      if (amp == std::string_view::npos) break;
      query.remove_prefix(amp + 1);
    }
  }
  return u;
}

namespace {
// `color=`: "bayer" is an alias of "grbg".
constexpr base::EnumTable<ColorMode, 3> kColorNames{
    {{ColorMode::mono, "mono"}, {ColorMode::bayer_grbg, "grbg"}, {ColorMode::bayer_grbg, "bayer"}}};
constexpr base::EnumTable<FileUri::Speed, 2> kSpeedNames{
    {{FileUri::Speed::realtime, "realtime"}, {FileUri::Speed::max, "max"}}};
}  // namespace

StreamSettings parse_stream_params(const SourceUri& uri, StreamSettings s) {
  if (auto v = uri.param("color")) {
    if (const auto c = base::enum_parse(kColorNames, *v))
      s.parser.color = *c;
    else
      bad_value(uri, "color", *v, base::enum_names(kColorNames));
  }
  if (auto v = uri.param("tolerance_ms")) {
    const auto ms = parse_double(*v);
    if (!ms || *ms <= 0 || *ms > 1000) bad_value(uri, "tolerance_ms", *v, "milliseconds, > 0 and <= 1000");
    s.pairer.tolerance_ns = static_cast<std::int64_t>(*ms * 1e6);
  }
  if (auto v = uri.param("reference")) {
    if (*v == "check") {
      s.parser.reference.enabled = true;
      s.parser.reference.reject = false;
    } else if (*v == "reject") {
      s.parser.reference.enabled = true;
      s.parser.reference.reject = true;
    } else if (*v == "off") {
      s.parser.reference.enabled = false;
    } else {
      bad_value(uri, "reference", *v, "check, reject, off");
    }
  }
  return s;
}

UsbUri parse_usb_uri(const SourceUri& uri) {
  allow(uri, with_stream({"serial", "interface", "endpoint"}));
  UsbUri u;
  if (!uri.target.empty()) {
    const auto colon = uri.target.find(':');
    const auto vid = parse_int<std::uint16_t>(std::string_view(uri.target).substr(0, colon), 16);
    const auto pid = colon == std::string::npos
                         ? std::nullopt
                         : parse_int<std::uint16_t>(std::string_view(uri.target).substr(colon + 1), 16);
    if (!vid || !pid || colon != 4 || uri.target.size() != 9)
      throw SourceError("usb://: bad device id '" + uri.target +
                        "'; expected VID:PID in hex, e.g. usb://10f8:c487");
    u.vid = *vid;
    u.pid = *pid;
  }
  if (auto v = uri.param("serial")) {
    if (v->empty()) bad_value(uri, "serial", *v, "the board's serial number string");
    u.serial = *v;
  }
  if (auto v = uri.param("interface")) {
    const auto i = parse_int<int>(*v);
    if (!i || *i < 0 || *i > 255) bad_value(uri, "interface", *v, "an interface number 0..255");
    u.interface = *i;
  }
  if (auto v = uri.param("endpoint")) {
    const auto e = parse_int<unsigned>(*v, 16);
    if (!e || *e < 0x81 || *e > 0x8f) bad_value(uri, "endpoint", *v, "a bulk IN endpoint address 0x81..0x8f");
    u.endpoint = static_cast<std::uint8_t>(*e);
  }
  u.stream = parse_stream_params(uri);
  return u;
}

namespace {
constexpr base::EnumTable<V4l2Layout, 3> kV4l2LayoutNames{{{V4l2Layout::side_by_side, "side-by-side"},
                                                           {V4l2Layout::top_bottom, "top-bottom"},
                                                           {V4l2Layout::alternate, "alternate"}}};
}  // namespace

const char* to_string(V4l2Layout l) {
  return base::enum_name(kV4l2LayoutNames, l, "?");
}

namespace {
constexpr base::EnumTable<V4l2Format, 4> kV4l2FormatNames{{{V4l2Format::y10, "Y10"},
                                                           {V4l2Format::y16, "Y16"},
                                                           {V4l2Format::grey, "GREY"},
                                                           {V4l2Format::sgrbg10, "SGRBG10"}}};
}  // namespace

const char* to_string(V4l2Format f) {
  return base::enum_name(kV4l2FormatNames, f, "?");
}

V4l2Uri parse_v4l2_uri(const SourceUri& uri) {
  allow(uri, with_stream({"layout", "format"}));
  V4l2Uri u;
  if (!uri.target.empty()) u.device = uri.target;
  if (u.device.front() != '/')
    throw SourceError("v4l2://: bad device '" + u.device +
                      "'; expected an absolute path, e.g. v4l2:///dev/video0");
  if (auto v = uri.param("layout")) {
    if (const auto l = base::enum_parse(kV4l2LayoutNames, *v))
      u.layout = *l;
    else
      bad_value(uri, "layout", *v, base::enum_names(kV4l2LayoutNames));
  }
  if (auto v = uri.param("format")) {
    u.format = base::enum_parse(kV4l2FormatNames, *v);
    if (!u.format) bad_value(uri, "format", *v, base::enum_names(kV4l2FormatNames));
  }
  u.stream = parse_stream_params(uri);
  // A grabber may crop or process the reference pixels: checked only when the URI says they are
  // there (`reference=check` or `reject`), never assumed.
  if (!uri.param("reference")) u.stream.parser.reference.enabled = false;
  if (u.format == V4l2Format::sgrbg10 && !uri.param("color")) u.stream.parser.color = ColorMode::bayer_grbg;
  return u;
}

FileUri parse_file_uri(const SourceUri& uri) {
  allow(uri, with_stream({"speed", "loop", "chunk"}));
  FileUri f;
  f.path = uri.target;
  if (f.path.empty()) throw SourceError("file://: no path; expected file:///path/capture.raw or .neyd");
  if (auto v = uri.param("speed")) {
    if (const auto sp = base::enum_parse(kSpeedNames, *v)) {
      f.speed = *sp;
    } else {
      const auto x = parse_double(*v);
      if (!x || *x <= 0 || *x > 1000)
        bad_value(uri, "speed", *v, "realtime, max, or a factor > 0 (e.g. 2 or 0.5)");
      f.speed = FileUri::Speed::factor;
      f.factor = *x;
    }
  }
  if (auto v = uri.param("loop")) f.loop = parse_bool(uri, "loop", *v);
  if (auto v = uri.param("chunk")) {
    const auto c = parse_int<std::size_t>(*v);
    if (!c || *c < 1 || *c > (64u << 20)) bad_value(uri, "chunk", *v, "bytes per piece, 1..67108864");
    f.chunk_bytes = *c;
  }
  f.stream = parse_stream_params(uri);
  return f;
}

}  // namespace naneye::driver
