#pragma once
// The fuzzing harness: runs the sflsh executable on one mutated input as a separate process (so that a
// crash or a hang is observed, not suffered) and classifies what happened against the project's rules
// for bad input: exit 0, or exit 1 (2 for a command line that cannot be used) with exactly one line
// `sflsh: error: …` naming the input file, no
// crash, no hang, and nothing left behind (no staging folder, no temporary file, no output folder from a
// failed run).
#include <filesystem>
#include <string>
#include <vector>

namespace sflsh::testing::fuzz {

/// What one run did, worst first.
enum class Verdict { crash, hang, leftover, unclear, refused, accepted };
const char* verdict_name(Verdict v);

struct Case {
  std::string kind;             ///< input kind, e.g. "scene TOML"
  std::string mutation;         ///< what the mutator did, e.g. "line 7: value → nan"
  std::filesystem::path input;  ///< the mutated file the message must name
  std::string arguments;        ///< sflsh arguments (without the executable)
  std::filesystem::path out;    ///< the run's --out folder (must not exist after a refusal); empty if none
};

struct Outcome {
  Case c;
  Verdict verdict = Verdict::accepted;
  int exit_code = 0;
  double seconds = 0.0;
  std::string detail;  ///< the error line, or why the verdict is what it is
};

/// Random cases per input kind: $SFLSH_FUZZ_CASES, default 10 (fuzz.many_cases sets 80).
int cases_per_kind();

/// Seconds after which a run counts as a hang (SIGTERM, then SIGKILL 5 s later).
constexpr double kHangSeconds = 90.0;

/// Runs one case in `workdir` (the folder holding the input and the output folder) and classifies it.
Outcome run_case(const Case& c, const std::filesystem::path& workdir);

/// Runs, counts and prints one table row per kind; returns the outcomes that break a rule.
struct Tally {
  std::vector<Outcome> outcomes;
  void add(Outcome o) { outcomes.push_back(std::move(o)); }
  std::vector<Outcome> failures() const;
  /// One line per case: verdict, seconds, mutation, message (what a reader of the test log needs).
  std::string cases() const;
  /// Markdown table: kind | runs | crashes | hangs | leftovers | unclear | refused | accepted.
  std::string table() const;
};

/// Entries under `dir` whose name marks an unfinished write (`.staging-`, `.tmp-`).
std::vector<std::filesystem::path> leftovers_in(const std::filesystem::path& dir);

}  // namespace sflsh::testing::fuzz
