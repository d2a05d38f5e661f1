// Mutators for the fuzzing harness (mutators.hpp).
#include "mutators.hpp"

#include <fmt/format.h>

#include <fstream>
#include <sstream>

namespace sflsh::testing::fuzz {

namespace fs = std::filesystem;

std::vector<std::uint8_t> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_bytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::trunc);
  out << text;
}

const std::vector<std::string>& hostile_values() {
  static const std::vector<std::string> values{"nan",
                                               "inf",
                                               "-inf",
                                               "-1",
                                               "0",
                                               "1e308",
                                               "-1e308",
                                               "5e-324",
                                               "1e9",
                                               "1e-12",
                                               "100000",
                                               "2147483648",
                                               "\"\"",
                                               "\"x\"",
                                               "\"../missing.file\"",
                                               "[]",
                                               "[1e308, 0.0, 0.0]",
                                               "[nan, 0.0, 0.0]",
                                               "true",
                                               "{ a = 1 }",
                                               "1979-05-27"};
  return values;
}

namespace {

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines) s += l + "\n";
  return s;
}

/// Indices of `key = value` lines (not comments, not headers).
std::vector<std::size_t> assignment_lines(const std::vector<std::string>& lines) {
  std::vector<std::size_t> found;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string& l = lines[i];
    const auto first = l.find_first_not_of(" \t");
    if (first == std::string::npos || l[first] == '#' || l[first] == '[') continue;
    if (l.find('=') != std::string::npos) found.push_back(i);
  }
  return found;
}

std::size_t pick(Random& random, std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(random); }

}  // namespace

std::string replace_toml_value(const std::string& text, const std::string& key, const std::string& value) {
  std::vector<std::string> lines = split_lines(text);
  for (std::size_t i : assignment_lines(lines)) {
    const std::string& l = lines[i];
    const auto eq = l.find('=');
    std::string name = l.substr(0, eq);
    name.erase(0, name.find_first_not_of(" \t"));
    name.erase(name.find_last_not_of(" \t") + 1);
    if (name != key) continue;
    lines[i] = l.substr(0, eq + 1) + " " + value;
    return join_lines(lines);
  }
  return {};
}

std::string mutate_toml(const std::string& text, Random& random, std::string& what) {
  std::vector<std::string> lines = split_lines(text);
  const std::vector<std::size_t> assignments = assignment_lines(lines);
  const int choice = static_cast<int>(pick(random, 10));
  if (choice <= 4 && !assignments.empty()) {  // the most telling mutation: a hostile value for a real key
    const std::size_t i = assignments[pick(random, assignments.size())];
    const std::string value = hostile_values()[pick(random, hostile_values().size())];
    const auto eq = lines[i].find('=');
    what = fmt::format("line {}: '{}' → {}", i + 1, lines[i].substr(0, eq), value);
    lines[i] = lines[i].substr(0, eq + 1) + " " + value;
    return join_lines(lines);
  }
  if (choice == 5 && !assignments.empty()) {
    const std::size_t i = assignments[pick(random, assignments.size())];
    what = fmt::format("line {} deleted: {}", i + 1, lines[i]);
    lines.erase(lines.begin() + static_cast<std::ptrdiff_t>(i));
    return join_lines(lines);
  }
  if (choice == 6 && !assignments.empty()) {
    const std::size_t i = assignments[pick(random, assignments.size())];
    what = fmt::format("line {} duplicated", i + 1);
    lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(i), lines[i]);
    return join_lines(lines);
  }
  if (choice == 7) {
    const std::size_t i = assignments.empty() ? 0 : assignments[pick(random, assignments.size())];
    what = fmt::format("unknown key before line {}", i + 1);
    const std::string unknown_key = "unknown_key_from_fuzzing = 1";  // a named string: GCC 12's -Warray-bounds
    lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(i), unknown_key);  // misfires on an inserted literal
    return join_lines(lines);
  }
  if (choice == 8 && text.size() > 1) {
    const std::size_t at = pick(random, text.size());
    what = fmt::format("truncated at byte {} of {}", at, text.size());
    return text.substr(0, at);
  }
  std::string flipped = text.empty() ? std::string("\x01") : text;
  const std::size_t at = pick(random, flipped.size());
  const char c = static_cast<char>(pick(random, 256));
  what = fmt::format("byte {} set to 0x{:02x}", at, static_cast<unsigned char>(c));
  flipped[at] = c;
  return flipped;
}

std::string mutate_tokens(const std::string& text, Random& random, std::string& what) {
  static const std::vector<std::string> tokens{"nan",        "inf",         "-1", "0",   "1e308", "99999999",
                                               "4294967297", "-2147483649", "x",  "1.5", ""};
  std::vector<std::string> lines = split_lines(text);
  if (lines.empty()) {
    what = "empty file";
    return text;
  }
  const std::size_t i = pick(random, lines.size());
  const int choice = static_cast<int>(pick(random, 8));
  if (choice <= 4) {
    std::vector<std::string> words;
    std::istringstream in(lines[i]);
    for (std::string w; in >> w;) words.push_back(w);
    if (words.empty()) words.push_back("");
    const std::size_t w = pick(random, words.size());
    const std::string token = tokens[pick(random, tokens.size())];
    what = fmt::format("line {} word {}: '{}' → '{}'", i + 1, w + 1, words[w], token);
    words[w] = token;
    std::string line;
    for (std::size_t k = 0; k < words.size(); ++k) line += (k ? " " : "") + words[k];
    lines[i] = line;
  } else if (choice == 5) {
    what = fmt::format("line {} deleted: {}", i + 1, lines[i]);
    lines.erase(lines.begin() + static_cast<std::ptrdiff_t>(i));
  } else if (choice == 6) {
    what = fmt::format("line {} duplicated", i + 1);
    lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(i), lines[i]);
  } else {
    const std::size_t at = pick(random, text.size());
    what = fmt::format("truncated at byte {} of {}", at, text.size());
    return text.substr(0, at);
  }
  return join_lines(lines);
}

std::vector<std::uint8_t> mutate_bytes(const std::vector<std::uint8_t>& bytes, Random& random, std::string& what) {
  std::vector<std::uint8_t> b = bytes;
  if (b.empty()) {
    what = "empty file";
    return b;
  }
  const int choice = static_cast<int>(pick(random, 4));
  if (choice == 0) {
    const std::size_t at = pick(random, b.size());
    what = fmt::format("truncated at byte {} of {}", at, b.size());
    b.resize(at);
  } else if (choice == 1) {
    const std::size_t flips = 1 + pick(random, 4);
    what = fmt::format("{} bytes flipped at", flips);
    for (std::size_t k = 0; k < flips; ++k) {
      const std::size_t at = pick(random, b.size());
      b[at] = static_cast<std::uint8_t>(b[at] ^ (1u + pick(random, 255)));
      what += fmt::format(" {}", at);
    }
  } else if (choice == 2) {
    const std::size_t at = pick(random, b.size());
    const std::size_t n = std::min<std::size_t>(64, b.size() - at);
    what = fmt::format("{} bytes zeroed at {}", n, at);
    std::fill(b.begin() + static_cast<std::ptrdiff_t>(at), b.begin() + static_cast<std::ptrdiff_t>(at + n), 0);
  } else {
    // A flipped byte near the start, where headers (zip local header, npy dict, HDF5 superblock) live.
    const std::size_t at = pick(random, std::min<std::size_t>(b.size(), 512));
    b[at] = static_cast<std::uint8_t>(pick(random, 256));
    what = fmt::format("header byte {} set to 0x{:02x}", at, b[at]);
  }
  return b;
}

}  // namespace sflsh::testing::fuzz
