#pragma once
// Batches of independent reduced simulations (the fit's (1 + 3N)·M finite-difference runs, SFLSH §5),
// shared among MPI ranks (job k of a batch runs on rank (s + k) mod size, s rotating from batch to batch) and,
// within a rank, among threads (TBB).
// Every rank returns the same results: each entry is computed by exactly one rank and summed with zeros.
#include <sflsh/reduced/dynamics_case.hpp>

#include <mpi.h>

#include <functional>
#include <vector>

namespace sflsh::reduced {

struct SimulationJob {
  int case_index = 0;           ///< into the cases given to run()
  material::KappaMatrix kappa;  ///< physical control values (N × 3)
};

class SimulationPool {
 public:
  /// threads ≤ 0: all hardware threads. comm = MPI_COMM_NULL (or MPI not initialized): this process only.
  explicit SimulationPool(int threads = 0, MPI_Comm comm = MPI_COMM_WORLD);

  /// Per job the stacked dynamics [σ_n; σ_t] (2R, mm). The first failing job's error is rethrown on
  /// every rank (naming subject and motion).
  std::vector<Eigen::VectorXd> run(const std::vector<const DynamicsCase*>& cases,
                                   const std::vector<SimulationJob>& jobs,
                                   const LayerParameterization& parameterization, const ReducedModel& model,
                                   const ReducedOptions& options);

  /// The general form: task(k) for k in [0, count), each returning a vector whose length `length(k)` is known
  /// beforehand on every rank; results reach every rank. `label` names the batch in errors.
  std::vector<Eigen::VectorXd> run_tasks(int count, const std::function<Eigen::Index(int)>& length,
                                         const std::function<Eigen::VectorXd(int)>& task);

  int threads() const { return threads_; }
  int ranks() const { return size_; }
  int rank() const { return rank_; }
  long simulations() const { return simulations_; }  ///< jobs run so far (all ranks)
  double seconds() const { return seconds_; }        ///< wall time spent in run()
  /// CPU time of this rank's threads inside tasks [s]: the work this rank did, whatever the waits between batches
  /// (with more ranks than cores, Σ over ranks / max over ranks bounds the speed-up of P real cores).
  double task_cpu_seconds() const { return task_cpu_seconds_; }

 private:
  int threads_ = 1;
  MPI_Comm comm_ = MPI_COMM_NULL;
  int rank_ = 0, size_ = 1;
  long simulations_ = 0;
  double seconds_ = 0.0;
  double task_cpu_seconds_ = 0.0;
  int first_ = 0;  ///< the rank of the next batch's first job
};

}  // namespace sflsh::reduced
