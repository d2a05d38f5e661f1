#pragma once
// PETSc (and through it MPI) for the lifetime of one command. PETSc keeps its own process-wide state;
// this object is the one place that starts and stops it, so library code never calls PetscInitialize.
#include <mpi.h>

#include <string>
#include <vector>

namespace sflsh::fullspace {

/// Splits a command line into the project's own arguments and PETSc options: a token that starts with a
/// single dash followed by one of PETSc's option families (snes_, ksp_, pc_, mat_, vec_, log_, sub_, mg_,
/// options_file, info, malloc_, on_error_) is a PETSc option; the token after it is its value unless it
/// starts with '-' and is not a number. argv[0] stays in `own`.
struct SplitArguments {
  std::vector<std::string> own;
  std::vector<std::string> petsc;
};
SplitArguments split_petsc_arguments(int argc, const char* const* argv);

class PetscSession {
 public:
  /// Initializes PETSc with `options` (tokens as on a PETSc command line) and an optional options file.
  /// When PETSc is already initialized (nested use) the options are inserted and nothing else happens.
  explicit PetscSession(const std::vector<std::string>& options = {}, const std::string& options_file = "");
  ~PetscSession();
  PetscSession(const PetscSession&) = delete;
  PetscSession& operator=(const PetscSession&) = delete;

  MPI_Comm comm() const { return MPI_COMM_WORLD; }
  int rank() const;
  int size() const;
  /// Options given that no PETSc object used (PetscOptionsLeft), for a warning at the end of a run.
  std::vector<std::string> unused_options() const;

 private:
  bool owns_ = false;
};

/// True when PETSc has been initialized in this process.
bool petsc_initialized();

}  // namespace sflsh::fullspace
