#pragma once
// The study's fits as chains (experiments.cpp): a chain's fits run in order, a fit marked so starting from the
// previous one's result (the leave-one-out λ sweep's continuation, FitSpec::warm_start); chains do not depend on
// each other. With G fit groups the MPI ranks split into G groups (world rank mod G): group g runs the chains
// c with c mod G = g, its ranks sharing each fit's simulations (SimulationPool on the group's communicator).
// After a barrier every rank runs every chain again on the whole world: each fit is then finished in its
// checkpoint (state/fits/<fit>.json, which every rank must see: one machine, or a shared file system) and is
// read back without simulating, so every rank ends with every fit, bit for bit as its group computed it.
#include <sflsh/reduced/elasticity_fit.hpp>

#include <mpi.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace sflsh::validate {

struct ChainFit {
  std::string key;  ///< in the report's fits ("cv/ours/0.1/OPEN_TRAIN_2", …)
  reduced::FitSpec spec;
  std::vector<reduced::FitTarget> targets;
  bool warm_from_previous = false;  ///< start from the chain's previous fit (its last stage only)
};
using FitChain = std::vector<ChainFit>;

class FitRunner {
 public:
  /// `context` is the whole world's (its pool on MPI_COMM_WORLD or on this process); groups ≥ 1 (clamped to the
  /// number of ranks).
  FitRunner(const reduced::FitContext& context, int groups, int threads);
  ~FitRunner();
  FitRunner(const FitRunner&) = delete;
  FitRunner& operator=(const FitRunner&) = delete;

  int groups() const { return groups_; }
  /// Simulations the groups ran (all ranks; 0 with one group, whose fits count in the world's pool). Collective.
  long group_simulations() const;
  /// Per world rank (on rank 0; empty elsewhere): CPU seconds its threads spent in simulation tasks, the world's
  /// pool and its group's together. Collective.
  std::vector<double> rank_task_cpu_seconds() const;
  /// Runs the chains; on return `fits` holds every chain's fits on every rank.
  void run(const std::string& label, const std::vector<FitChain>& chains,
           std::map<std::string, reduced::FitResult>& fits) const;

 private:
  reduced::FitContext context_;
  int groups_ = 1;
  int group_ = 0;
  MPI_Comm group_comm_ = MPI_COMM_NULL;
  std::unique_ptr<reduced::SimulationPool> group_pool_;
  reduced::FitContext group_context_;
};

}  // namespace sflsh::validate
