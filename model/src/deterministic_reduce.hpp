#pragma once
// Parallel sums over tets whose result does not depend on the number of threads or on how TBB schedules them.
// A thread-local accumulator (enumerable_thread_specific) or parallel_reduce with the auto partitioner sums in an
// order that changes with the thread count and from run to run; a difference of one ulp in an energy or a
// gradient then grows through a nonlinear solve and an optimizer's accept/reject decisions. Here the range is
// cut into blocks whose size depends on the range alone (at most `max_blocks` blocks, none smaller than
// `min_grain`), each block is summed in order, and the blocks are joined in a fixed tree (TBB's
// parallel_deterministic_reduce with the simple partitioner). docs/decisions.md, "Deterministic sums".
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <utility>

namespace sflsh::model {

/// Σ over [0, count) of `body(range, acc)` (which adds the range's items to `acc` and returns it), the blocks'
/// results combined by `join(a, b)`; bit for bit the same on 1 or many threads.
template <typename Index, typename Value, typename Body, typename Join>
Value deterministic_reduce(Index count, const Value& identity, Body&& body, Join&& join, Index min_grain = 256,
                           Index max_blocks = 32) {
  if (count <= 0) return identity;
  const Index grain = std::max<Index>(min_grain, (count + max_blocks - 1) / max_blocks);
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Index>(0, count, grain), identity,
      [&](const tbb::blocked_range<Index>& range, Value acc) { return body(range, std::move(acc)); },
      [&](Value a, const Value& b) { return join(std::move(a), b); }, tbb::simple_partitioner());
}

}  // namespace sflsh::model
