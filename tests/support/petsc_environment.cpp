// PETSc (and MPI) once per test process: gtest may run many tests in one process, and MPI cannot be
// initialized twice.
#include <sflsh/fullspace/petsc_session.hpp>

#include <gtest/gtest.h>

#include <memory>

namespace {

class PetscEnvironment : public ::testing::Environment {
 public:
  void SetUp() override { session_ = std::make_unique<sflsh::fullspace::PetscSession>(); }
  void TearDown() override { session_.reset(); }

 private:
  std::unique_ptr<sflsh::fullspace::PetscSession> session_;
};

[[maybe_unused]] ::testing::Environment* const kPetscEnvironment =
    ::testing::AddGlobalTestEnvironment(new PetscEnvironment);

}  // namespace
