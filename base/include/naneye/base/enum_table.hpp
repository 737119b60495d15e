#pragma once
// An enum's names from one table, read both ways: enum_name() for JSON, logs and messages,
// enum_parse() for settings and URIs. A table lists every value once with its name; further rows
// for a value are aliases that enum_parse() accepts and enum_name() never gives. The names must be
// string literals (enum_name() hands out their data() as a C string). Header-only, no I/O: recon
// uses it too.
//
//   constexpr base::EnumTable<Color, 2> kColorNames{{{Color::red, "red"}, {Color::blue, "blue"}}};
//   const char* to_string(Color c) { return base::enum_name(kColorNames, c); }
#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace naneye::base {

template <class E, std::size_t N>
using EnumTable = std::array<std::pair<E, std::string_view>, N>;

// The first name of `e`, or `unknown` for a value not in the table.
template <class E, std::size_t N>
constexpr const char* enum_name(const EnumTable<E, N>& table, E e, const char* unknown = "unknown") {
  for (const auto& [value, name] : table)
    if (value == e) return name.data();
  return unknown;
}

// The value named `text` (any of its names), if any.
template <class E, std::size_t N>
constexpr std::optional<E> enum_parse(const EnumTable<E, N>& table, std::string_view text) {
  for (const auto& [value, name] : table)
    if (name == text) return value;
  return std::nullopt;
}

// Every value's first name, joined ("board, scene, both"), for the message that refuses a name.
template <class E, std::size_t N>
std::string enum_names(const EnumTable<E, N>& table, std::string_view separator = ", ") {
  std::string out;
  for (std::size_t i = 0; i < N; ++i) {
    bool alias = false;
    for (std::size_t j = 0; j < i; ++j) alias |= table[j].first == table[i].first;
    if (alias) continue;
    if (!out.empty()) out += separator;
    out += table[i].second;
  }
  return out;
}

}  // namespace naneye::base
