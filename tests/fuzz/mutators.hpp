#pragma once
// Mutators for the fuzzing harness: small, seeded, generated changes to a valid input file. Text mutators
// work on TOML line by line (hostile values, missing, duplicated and unknown keys, truncation, byte
// flips); byte mutators work on any binary file (truncation, flipped bytes, zeroed blocks). Each returns a
// one-line description of what it did, for the report.
#include <cstdint>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace sflsh::testing::fuzz {

using Random = std::mt19937_64;

std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path);
void write_bytes(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes);
std::string read_text(const std::filesystem::path& path);
void write_text(const std::filesystem::path& path, const std::string& text);

/// Values a hostile or careless user puts where a number, a string or an array belongs.
const std::vector<std::string>& hostile_values();

/// One random text mutation of a TOML document; `what` receives its description.
std::string mutate_toml(const std::string& text, Random& random, std::string& what);
/// Replaces the value of `key` (first `key = …` line) by `value`; empty when the key is absent.
std::string replace_toml_value(const std::string& text, const std::string& key, const std::string& value);

/// One random mutation of a whitespace-separated text format (OBJ, gmsh .msh): a token of a random line
/// replaced by a hostile number or word, a line deleted or duplicated, or the text truncated.
std::string mutate_tokens(const std::string& text, Random& random, std::string& what);

/// One random byte mutation; `what` receives its description.
std::vector<std::uint8_t> mutate_bytes(const std::vector<std::uint8_t>& bytes, Random& random, std::string& what);

}  // namespace sflsh::testing::fuzz
