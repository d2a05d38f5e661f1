#include "commands.hpp"

#include <sflsh/core/log.hpp>
#include <sflsh/fullspace/petsc_session.hpp>

#include <mpi.h>

#include <iostream>

namespace sflsh::app {

void with_petsc(const Invocation& invocation, const std::function<void(int rank, int size)>& body) {
  fullspace::PetscSession session(invocation.petsc_options);
  const int rank = session.rank();
  const int size = session.size();
  if (rank != 0) logger()->set_level(spdlog::level::warn);
  try {
    body(rank, size);
  } catch (const std::exception& e) {
    if (size > 1) {
      std::cerr << "sflsh: error (rank " << rank << "): " << e.what() << std::endl;
      MPI_Abort(MPI_COMM_WORLD, 1);
    }
    throw;
  }
  for (const auto& unused : session.unused_options()) logger()->warn("PETSc option {} was not used", unused);
}

void add_body_option(CLI::App& cmd, SubjectOptions& options) {
  cmd.add_option("--body", options.body_path,
                 "Body model .npz in SMPL layout (default: the open body, data/open_body.npz)");
}

void add_subject_options(CLI::App& cmd, SubjectOptions& options) {
  auto* subject =
      cmd.add_option("--subject", options.subject, "Named subject (data/subjects.toml, data/open_body_subjects.toml)");
  auto* betas = cmd.add_option("--betas", options.betas, "Shape β: up to 10 numbers, e.g. \"1.5 -0.3 0 …\"");
  subject->excludes(betas);
  betas->excludes(subject);
}

Eigen::MatrixXd dominant_joint(const body::BodyModel& model) {
  Eigen::MatrixXd labels(model.num_vertices(), 1);
  for (Eigen::Index i = 0; i < model.num_vertices(); ++i) {
    Eigen::Index k = 0;
    model.weights.row(i).maxCoeff(&k);
    labels(i, 0) = static_cast<double>(k);
  }
  return labels;
}

}  // namespace sflsh::app
