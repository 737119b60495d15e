// Feeds every file of a fuzz corpus to its entry point: the corpus is replayed as an ordinary test
// in every build (gcc included), so a crash once found by the fuzzer stays fixed.
//   fuzz_corpus_replay ENTRY DIR [ROUNDS]   (ENTRY: a name of fuzz_entries.hpp's kEntries)
// With ROUNDS, the corpus (read once) is fed ROUNDS times and the CPU time per input is printed:
// the same inputs before and after a change to a parser, which a fuzzing run, whose inputs follow
// the coverage of the binary, cannot give.
#include <algorithm>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "fuzz_entries.hpp"

int main(int argc, char** argv) {
  std::string names;
  for (const auto& e : naneye::fuzz::kEntries) names += (names.empty() ? "" : ", ") + std::string(e.name);
  if (argc != 3 && argc != 4) {
    std::cerr << "usage: fuzz_corpus_replay ENTRY DIR [ROUNDS]; entries: " << names << "\n";
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
  std::vector<std::vector<std::uint8_t>> inputs;
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    inputs.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const long rounds = argc == 4 ? std::stol(argv[3]) : 1;
  const std::clock_t start = std::clock();  // CPU time: a busy machine's steal is not the parser's
  for (long r = 0; r < rounds; ++r)
    for (const auto& data : inputs) entry(data.data(), data.size());
  const double cpu_s = static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC;
  std::cout << files.size() << " inputs of " << argv[2] << " replayed";
  if (argc == 4) {
    const double runs = static_cast<double>(rounds) * static_cast<double>(inputs.size());
    std::cout << " " << rounds << " times: " << 1e6 * cpu_s / runs << " us CPU per input";
  }
  std::cout << "\n";
  return 0;
}
