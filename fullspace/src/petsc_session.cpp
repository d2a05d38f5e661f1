#include <sflsh/core/error.hpp>
#include <sflsh/core/interrupt_cleanup.hpp>
#include <sflsh/fullspace/petsc_session.hpp>

#include <petscsys.h>

#include <array>
#include <cstdlib>
#include <string_view>

namespace sflsh::fullspace {

namespace {

bool is_number(std::string_view s) {
  if (s.empty()) return false;
  char* end = nullptr;
  const std::string copy(s);
  std::strtod(copy.c_str(), &end);
  return end != nullptr && *end == '\0';
}

bool is_petsc_option(std::string_view token) {
  if (token.size() < 3 || token[0] != '-' || token[1] == '-') return false;
  static constexpr std::array<std::string_view, 13> kFamilies = {
      "snes_", "ksp_",         "pc_",  "mat_",    "vec_",      "log_",  "sub_",
      "mg_",   "options_file", "info", "malloc_", "on_error_", "sflsh_"};
  const std::string_view name = token.substr(1);
  for (std::string_view family : kFamilies) {
    if (name.substr(0, family.size()) == family) return true;
  }
  return false;
}

}  // namespace

SplitArguments split_petsc_arguments(int argc, const char* const* argv) {
  SplitArguments out;
  for (int i = 0; i < argc; ++i) {
    const std::string_view token = argv[i];
    if (i == 0 || !is_petsc_option(token)) {
      out.own.emplace_back(token);
      continue;
    }
    out.petsc.emplace_back(token);
    if (i + 1 < argc) {
      const std::string_view next = argv[i + 1];
      if (!next.empty() && (next[0] != '-' || is_number(next))) {
        out.petsc.emplace_back(next);
        ++i;
      }
    }
  }
  return out;
}

bool petsc_initialized() {
  PetscBool initialized = PETSC_FALSE;
  PetscInitialized(&initialized);
  return initialized == PETSC_TRUE;
}

PetscSession::PetscSession(const std::vector<std::string>& options, const std::string& options_file) {
  std::string joined;
  for (const auto& o : options) {
    if (!joined.empty()) joined += ' ';
    joined += o;
  }
  if (petsc_initialized()) {
    if (!joined.empty()) PetscOptionsInsertString(nullptr, joined.c_str());
    return;
  }
  // PETSc reads its options from argc/argv; give it exactly the PETSc tokens.
  std::vector<std::string> storage;
  storage.emplace_back("sflsh");
  for (const auto& o : options) storage.push_back(o);
  std::vector<char*> args;
  for (auto& s : storage) args.push_back(s.data());
  args.push_back(nullptr);
  int argc = static_cast<int>(storage.size());
  char** argv = args.data();
  const PetscErrorCode ierr =
      PetscInitialize(&argc, &argv, options_file.empty() ? nullptr : options_file.c_str(), nullptr);
  require(ierr == 0, "PETSc failed to initialize (error {}){}", static_cast<int>(ierr),
          options_file.empty() ? std::string() : " with options file " + options_file);
  owns_ = true;
  reinstall_interrupt_cleanup();  // PETSc's own handlers for SIGTERM/SIGHUP would leave staging folders behind
}

PetscSession::~PetscSession() {
  if (owns_) PetscFinalize();
}

int PetscSession::rank() const {
  int r = 0;
  MPI_Comm_rank(comm(), &r);
  return r;
}

int PetscSession::size() const {
  int s = 1;
  MPI_Comm_size(comm(), &s);
  return s;
}

std::vector<std::string> PetscSession::unused_options() const {
  std::vector<std::string> out;
  PetscInt count = 0;
  char** names = nullptr;
  char** values = nullptr;
  if (PetscOptionsLeftGet(nullptr, &count, &names, &values) != 0) return out;
  for (PetscInt i = 0; i < count; ++i) out.emplace_back(std::string("-") + names[i]);
  PetscOptionsLeftRestore(nullptr, &count, &names, &values);
  return out;
}

}  // namespace sflsh::fullspace
