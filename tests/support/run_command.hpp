#pragma once
// Runs the sflsh executable in a shell and captures its exit code, stdout and stderr.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace sflsh::testing {

struct CommandResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline CommandResult run_sflsh(const std::string& args, const std::filesystem::path& scratch) {
  const auto out_file = scratch / "cmd.stdout";
  const auto err_file = scratch / "cmd.stderr";
  const std::string command =
      std::string(SFLSH_CLI) + " " + args + " >" + out_file.string() + " 2>" + err_file.string();
  const int status = std::system(command.c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  auto slurp = [](const std::filesystem::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  result.out = slurp(out_file);
  result.err = slurp(err_file);
  std::filesystem::remove(out_file);
  std::filesystem::remove(err_file);
  return result;
}

/// Whether `mpiexec` is on the PATH (tests of several MPI processes skip without it).
inline bool have_mpiexec() { return std::system("command -v mpiexec >/dev/null 2>&1") == 0; }

}  // namespace sflsh::testing
