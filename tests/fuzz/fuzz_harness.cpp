// The fuzzing harness (fuzz_harness.hpp).
#include "fuzz_harness.hpp"

#include <sflsh/core/scoped_seconds.hpp>

#include <fmt/format.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

namespace sflsh::testing::fuzz {

namespace fs = std::filesystem;

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::crash:
      return "crash";
    case Verdict::hang:
      return "hang";
    case Verdict::leftover:
      return "leftover";
    case Verdict::unclear:
      return "unclear message";
    case Verdict::refused:
      return "refused";
    case Verdict::accepted:
      return "accepted";
  }
  return "?";
}

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

}  // namespace

int cases_per_kind() {
  const char* v = std::getenv("SFLSH_FUZZ_CASES");
  return v ? std::max(1, std::atoi(v)) : 10;
}

std::vector<fs::path> leftovers_in(const fs::path& dir) {
  std::vector<fs::path> found;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return found;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.find(".staging-") != std::string::npos || name.find(".tmp-") != std::string::npos)
      found.push_back(it->path());
  }
  return found;
}

Outcome run_case(const Case& c, const fs::path& workdir) {
  Outcome o;
  o.c = c;
  const fs::path out_file = workdir / "fuzz.stdout";
  const fs::path err_file = workdir / "fuzz.stderr";
  // `timeout` sends SIGTERM first: the run's own cleanup must then remove its staging folder.
  const std::string command = fmt::format("cd '{}' && timeout -k 5 {} {} {} >'{}' 2>'{}'", workdir.string(),
                                          kHangSeconds, SFLSH_CLI, c.arguments, out_file.string(), err_file.string());
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system(command.c_str());
  o.seconds = sflsh::seconds_since(start);
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  const std::string err = slurp(err_file);
  std::error_code ec;
  fs::remove(out_file, ec);
  fs::remove(err_file, ec);

  std::vector<std::string> error_lines;
  for (const std::string& line : lines_of(err)) {
    if (line.rfind("sflsh: error", 0) == 0 || line.find("terminate called") != std::string::npos ||
        line.find("PETSC ERROR") != std::string::npos)
      error_lines.push_back(line);
  }
  const auto leftovers = leftovers_in(workdir);

  if (o.exit_code == 124 || o.exit_code == 128 + 9) {
    o.verdict = Verdict::hang;
    o.detail = fmt::format("killed after {:.0f} s", o.seconds);
  } else if (o.exit_code != 0 && o.exit_code != 1 && o.exit_code != 2) {  // 1: refused input, 2: unusable command line
    o.verdict = Verdict::crash;
    o.detail = fmt::format("exit {}: {}", o.exit_code, error_lines.empty() ? err.substr(0, 300) : error_lines.front());
  } else if (!leftovers.empty()) {
    o.verdict = Verdict::leftover;
    o.detail = "left " + leftovers.front().string();
  } else if (o.exit_code != 0 && !c.out.empty() && fs::exists(c.out)) {
    o.verdict = Verdict::leftover;
    o.detail = "a refused run left its output folder " + c.out.string();
  } else if (o.exit_code == 0) {
    o.verdict = Verdict::accepted;
  } else {
    const std::string name = c.input.filename().string();
    const std::string line = error_lines.empty() ? std::string() : error_lines.front();
    if (error_lines.size() != 1) {
      o.verdict = Verdict::unclear;
      o.detail = fmt::format("{} error lines: {}", error_lines.size(), err.substr(0, 300));
    } else if (line.find(name) == std::string::npos) {
      o.verdict = Verdict::unclear;
      o.detail = "does not name " + name + ": " + line;
    } else if (line.find("bad_alloc") != std::string::npos || line.find("std::") != std::string::npos) {
      o.verdict = Verdict::unclear;
      o.detail = "internal exception: " + line;
    } else {
      o.verdict = Verdict::refused;
      o.detail = line;
    }
  }
  // The next case starts from a clean folder: no output of this one may be mistaken for its own.
  if (!c.out.empty()) fs::remove_all(c.out, ec);
  for (const fs::path& p : leftovers) fs::remove_all(p, ec);
  return o;
}

std::vector<Outcome> Tally::failures() const {
  std::vector<Outcome> bad;
  for (const Outcome& o : outcomes)
    if (o.verdict != Verdict::refused && o.verdict != Verdict::accepted) bad.push_back(o);
  return bad;
}

std::string Tally::cases() const {
  std::string s;
  for (const Outcome& o : outcomes)
    s += fmt::format("  {:<15} {:6.1f} s  {}  →  {}\n", verdict_name(o.verdict), o.seconds, o.c.mutation,
                     o.detail.substr(0, 160));
  return s;
}

std::string Tally::table() const {
  struct Row {
    int runs = 0, crash = 0, hang = 0, leftover = 0, unclear = 0, refused = 0, accepted = 0;
    double seconds = 0.0;
  };
  std::map<std::string, Row> rows;
  for (const Outcome& o : outcomes) {
    Row& r = rows[o.c.kind];
    ++r.runs;
    r.seconds += o.seconds;
    switch (o.verdict) {
      case Verdict::crash:
        ++r.crash;
        break;
      case Verdict::hang:
        ++r.hang;
        break;
      case Verdict::leftover:
        ++r.leftover;
        break;
      case Verdict::unclear:
        ++r.unclear;
        break;
      case Verdict::refused:
        ++r.refused;
        break;
      case Verdict::accepted:
        ++r.accepted;
        break;
    }
  }
  std::string s =
      "| input kind | runs | crashes | hangs | leftovers | unclear messages | refused (one clear line) | accepted | "
      "seconds |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [kind, r] : rows)
    s += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {:.1f} |\n", kind, r.runs, r.crash, r.hang, r.leftover,
                     r.unclear, r.refused, r.accepted, r.seconds);
  return s;
}

}  // namespace sflsh::testing::fuzz
