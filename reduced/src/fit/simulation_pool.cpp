#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/reduced/simulation_pool.hpp>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <ctime>
#include <mutex>
#include <thread>

namespace sflsh::reduced {

SimulationPool::SimulationPool(int threads, MPI_Comm comm) {
  threads_ = threads > 0 ? threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (initialized && comm != MPI_COMM_NULL) {
    comm_ = comm;
    MPI_Comm_rank(comm_, &rank_);
    MPI_Comm_size(comm_, &size_);
  }
}

std::vector<Eigen::VectorXd> SimulationPool::run(const std::vector<const DynamicsCase*>& cases,
                                                 const std::vector<SimulationJob>& jobs,
                                                 const LayerParameterization& parameterization,
                                                 const ReducedModel& model, const ReducedOptions& options) {
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    const int c = jobs[j].case_index;
    require(c >= 0 && c < static_cast<int>(cases.size()), "simulation pool: job {} names case {} of {}", j, c,
            cases.size());
  }
  return run_tasks(
      static_cast<int>(jobs.size()),
      [&](int j) {
        return Eigen::Index{2} *
               cases[static_cast<std::size_t>(jobs[static_cast<std::size_t>(j)].case_index)]->num_region_vertices();
      },
      [&](int j) {
        const SimulationJob& job = jobs[static_cast<std::size_t>(j)];
        const CaseDynamics d =
            cases[static_cast<std::size_t>(job.case_index)]->simulate(parameterization, job.kappa, model, options);
        Eigen::VectorXd out(2 * d.sigma_normal.size());
        out << d.sigma_normal, d.sigma_tangent;
        return out;
      });
}

std::vector<Eigen::VectorXd> SimulationPool::run_tasks(int count, const std::function<Eigen::Index(int)>& length,
                                                       const std::function<Eigen::VectorXd(int)>& task) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<Eigen::Index> offset(static_cast<std::size_t>(count) + 1, 0);
  for (int j = 0; j < count; ++j)
    offset[static_cast<std::size_t>(j) + 1] = offset[static_cast<std::size_t>(j)] + length(j);
  Eigen::VectorXd buffer = Eigen::VectorXd::Zero(offset.back());
  std::vector<int> mine;
  // Job j runs on rank (first_ + j) mod size: the start rotates from batch to batch, so small batches (a fit
  // with one or two cases) do not all land on rank 0. Every rank counts the same batches.
  for (int j = 0; j < count; ++j)
    if ((first_ + j) % size_ == rank_) mine.push_back(j);
  first_ = (first_ + count) % size_;

  std::mutex mutex;
  std::string error;
  tbb::task_arena arena(threads_);
  arena.execute([&] {
    // One task per chunk (simple partitioner, grain 1): jobs last from 0.1 to several seconds, so a thread that
    // finishes early takes the next job instead of waiting for a precut half.
    tbb::parallel_for(
        tbb::blocked_range<int>(0, static_cast<int>(mine.size()), 1),
        [&](const tbb::blocked_range<int>& range) {
          for (int k = range.begin(); k < range.end(); ++k) {
            const int j = mine[static_cast<std::size_t>(k)];
            try {
              timespec cpu_start{}, cpu_end{};
              clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu_start);
              const Eigen::VectorXd r = task(j);
              clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu_end);
              {
                const std::lock_guard<std::mutex> lock(mutex);
                task_cpu_seconds_ += static_cast<double>(cpu_end.tv_sec - cpu_start.tv_sec) +
                                     1e-9 * static_cast<double>(cpu_end.tv_nsec - cpu_start.tv_nsec);
              }
              const Eigen::Index n = offset[static_cast<std::size_t>(j) + 1] - offset[static_cast<std::size_t>(j)];
              require(r.size() == n, "simulation pool: task {} returned {} values, expected {}", j, r.size(), n);
              buffer.segment(offset[static_cast<std::size_t>(j)], n) = r;
            } catch (const std::exception& e) {
              std::lock_guard<std::mutex> lock(mutex);
              if (error.empty()) error = e.what();
            }
          }
        },
        tbb::simple_partitioner());
  });
  // Errors and results reach every rank.
  int failed = error.empty() ? 0 : 1, any_failed = failed;
  if (comm_ != MPI_COMM_NULL) MPI_Allreduce(&failed, &any_failed, 1, MPI_INT, MPI_MAX, comm_);
  if (any_failed) {
    if (comm_ != MPI_COMM_NULL) {
      // The lowest failing rank's message.
      int root = failed ? rank_ : size_, lowest = size_;
      MPI_Allreduce(&root, &lowest, 1, MPI_INT, MPI_MIN, comm_);
      int n = static_cast<int>(error.size());
      MPI_Bcast(&n, 1, MPI_INT, lowest, comm_);
      error.resize(static_cast<std::size_t>(n));
      MPI_Bcast(error.data(), n, MPI_CHAR, lowest, comm_);
    }
    throw Error(error);
  }
  if (comm_ != MPI_COMM_NULL && size_ > 1) {
    constexpr Eigen::Index kChunk = 1 << 24;  // stay far below int counts
    for (Eigen::Index at = 0; at < buffer.size(); at += kChunk) {
      const int n = static_cast<int>(std::min<Eigen::Index>(kChunk, buffer.size() - at));
      MPI_Allreduce(MPI_IN_PLACE, buffer.data() + at, n, MPI_DOUBLE, MPI_SUM, comm_);
    }
  }
  std::vector<Eigen::VectorXd> out(static_cast<std::size_t>(count));
  for (int j = 0; j < count; ++j)
    out[static_cast<std::size_t>(j)] =
        buffer.segment(offset[static_cast<std::size_t>(j)],
                       offset[static_cast<std::size_t>(j) + 1] - offset[static_cast<std::size_t>(j)]);
  simulations_ += count;
  seconds_ += seconds_since(start);
  return out;
}

}  // namespace sflsh::reduced
