#include "fit_chains.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>

#include <fmt/format.h>

#include <algorithm>

namespace sflsh::validate {

FitRunner::FitRunner(const reduced::FitContext& context, int groups, int threads) : context_(context) {
  require(context.pool != nullptr, "validate: fit runner without a simulation pool");
  require(groups >= 1, "validate: --fit-groups must be ≥ 1, got {}", groups);
  const int ranks = context.pool->ranks();
  if (groups > ranks)
    logger()->warn("validate: {} fit groups asked for {} MPI rank(s); using {}", groups, ranks, ranks);
  groups_ = std::min(groups, ranks);
  if (groups_ <= 1) return;
  int world_rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &world_rank);
  group_ = world_rank % groups_;
  MPI_Comm_split(MPI_COMM_WORLD, group_, world_rank, &group_comm_);
  group_pool_ = std::make_unique<reduced::SimulationPool>(threads, group_comm_);
  group_context_ = context_;
  group_context_.pool = group_pool_.get();
  group_context_.progress = context_.progress && group_pool_->rank() == 0;
}

FitRunner::~FitRunner() {
  group_pool_.reset();
  if (group_comm_ != MPI_COMM_NULL) MPI_Comm_free(&group_comm_);
}

long FitRunner::group_simulations() const {
  if (groups_ <= 1) return 0;
  long mine = group_pool_->rank() == 0 ? group_pool_->simulations() : 0, total = 0;
  MPI_Allreduce(&mine, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  return total;
}

std::vector<double> FitRunner::rank_task_cpu_seconds() const {
  double mine = context_.pool->task_cpu_seconds() + (group_pool_ ? group_pool_->task_cpu_seconds() : 0.0);
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized || context_.pool->ranks() <= 1) return {mine};
  std::vector<double> all(static_cast<std::size_t>(context_.pool->ranks()), 0.0);
  MPI_Gather(&mine, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  if (context_.pool->rank() != 0) all.clear();
  return all;
}

void FitRunner::run(const std::string& label, const std::vector<FitChain>& chains,
                    std::map<std::string, reduced::FitResult>& fits) const {
  auto run_chain = [&](const FitChain& chain, const reduced::FitContext& context, Progress* progress) {
    const reduced::FitResult* previous = nullptr;
    std::shared_ptr<const reduced::FitPoint> previous_point;  // only the last fit's: a few MB each
    for (const ChainFit& fit : chain) {
      reduced::FitSpec spec = fit.spec;
      if (fit.warm_from_previous && previous) {
        spec.warm_start = previous->p;
        spec.warm_start_from = previous->name;
        spec.warm_start_point = previous_point;  // its start is not simulated again
      }
      reduced::FitResult result = reduced::fit_elasticity(context, fit.targets, spec);
      previous_point = std::move(result.final_point);
      fits.insert_or_assign(fit.key, std::move(result));
      previous = &fits.at(fit.key);
      if (progress && previous->finished_earlier)
        progress->skip();
      else if (progress)
        progress->advance();
    }
  };
  std::size_t mine = 0;
  for (std::size_t c = 0; c < chains.size(); ++c)
    if (static_cast<int>(c % static_cast<std::size_t>(groups_)) == group_) mine += chains[c].size();
  const bool shown = context_.progress && context_.pool->rank() == 0;
  {
    Progress progress(groups_ > 1 ? fmt::format("{} (group 1 of {})", label, groups_) : label, mine, shown);
    for (std::size_t c = 0; c < chains.size(); ++c) {
      if (static_cast<int>(c % static_cast<std::size_t>(groups_)) != group_) continue;
      run_chain(chains[c], groups_ > 1 ? group_context_ : context_, &progress);
    }
  }
  if (groups_ <= 1) return;
  MPI_Barrier(MPI_COMM_WORLD);
  for (const FitChain& chain : chains) {
    for (const ChainFit& fit : chain)
      require(!fit.spec.checkpoint.empty(), "validate: fit {} has no checkpoint to share among fit groups",
              fit.spec.name);
    run_chain(chain, context_, nullptr);  // finished by its group: read back from the checkpoint
  }
}

}  // namespace sflsh::validate
