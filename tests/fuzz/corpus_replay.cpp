// Feeds every file of a fuzz corpus to its entry point: the corpus is replayed as an ordinary test
// in every build (gcc included), so a crash once found by the fuzzer stays fixed.
//   fuzz_corpus_replay ENTRY DIR     (ENTRY: a name of fuzz_entries.hpp's kEntries)
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "fuzz_entries.hpp"

int main(int argc, char** argv) {
  std::string names;
  for (const auto& e : naneye::fuzz::kEntries) names += (names.empty() ? "" : ", ") + std::string(e.name);
  if (argc != 3) {
    std::cerr << "usage: fuzz_corpus_replay ENTRY DIR; entries: " << names << "\n";
    return 2;
  }
  naneye::fuzz::Entry entry = nullptr;
  for (const auto& e : naneye::fuzz::kEntries)
    if (e.name == argv[1]) entry = e.entry;
  if (!entry) {
    std::cerr << "unknown entry '" << argv[1] << "'; accepted: " << names << "\n";
    return 2;
  }
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(argv[2]))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  if (files.empty()) {
    std::cerr << "empty corpus " << argv[2] << "\n";
    return 1;
  }
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::vector<std::uint8_t> data(std::istreambuf_iterator<char>(in), {});
    entry(data.data(), data.size());
  }
  std::cout << files.size() << " inputs of " << argv[2] << " replayed\n";
  return 0;
}
