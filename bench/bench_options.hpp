#pragma once
// The command line of the benchmark programs (bench/*.cpp), on CLI11 as `sflsh` itself: each program fills an
// options struct in its parse_options() and runs when parse_command_line() returns nothing. Every option shows its
// default in --help, a repeated option keeps its last value (as the hand-written parsers did), and an unknown
// option, a missing or malformed value or a failed check is refused with CLI11's message and exit status 2.
// The comma-separated lists some options take (`--sizes coarse,default,fine`, `--fps 30,60,120,240`) are split
// here, by one rule: empty entries are skipped.
#include <CLI/CLI.hpp>

#include <exception>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sflsh::bench {

/// A benchmark's options: defaults in --help, the last of a repeated option wins.
inline void use_bench_defaults(CLI::App& app) {
  app.option_defaults()->always_capture_default()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
}

/// Parses argv into the options `app` binds. Returns nothing to run, otherwise the status to exit with: 0 after
/// --help, 2 after CLI11's message on a refused command line.
inline std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return std::nullopt;
}

/// The entries of a comma-separated list, empty ones skipped.
inline std::vector<std::string> split_list(const std::string& csv) {
  std::vector<std::string> out;
  std::stringstream stream(csv);
  for (std::string item; std::getline(stream, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

/// The entries of a comma-separated list of integers (std::stoi each), empty ones skipped.
inline std::vector<int> split_ints(const std::string& csv) {
  std::vector<int> out;
  for (const std::string& item : split_list(csv)) out.push_back(std::stoi(item));
  return out;
}

/// A check that accepts what `parse(value)` accepts: the value is then refused before the benchmark starts, by the
/// parser that reads it later, with its message (with `what` for std::stoi's, which names no value); `what` is
/// also the check's name in --help.
template <class Parse>
CLI::Validator accepted_by(const std::string& what, Parse parse) {
  return CLI::Validator(
      [what, parse](std::string& value) -> std::string {
        try {
          parse(value);
          return {};
        } catch (const std::logic_error&) {  // std::stoi: invalid_argument, out_of_range
          return "'" + value + "': expected " + what;
        } catch (const std::exception& e) {
          return e.what();
        }
      },
      what);
}

/// accepted_by() for every entry of a comma-separated list (split_list()).
template <class Parse>
CLI::Validator each_accepted_by(const std::string& what, Parse parse) {
  return accepted_by(what, [parse](const std::string& list) {
    for (const std::string& item : split_list(list)) parse(item);
  });
}

/// A comma-separated list of integers, as split_ints() reads it.
inline CLI::Validator int_list() {
  return accepted_by("comma-separated integers", [](const std::string& v) { split_ints(v); });
}

}  // namespace sflsh::bench
