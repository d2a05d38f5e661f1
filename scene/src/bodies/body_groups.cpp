// Bodies that can touch each other in a step (body_groups.hpp).
#include "bodies/body_groups.hpp"

#include <numeric>

namespace sflsh::scene::detail {

std::vector<std::vector<std::size_t>> contact_groups(const std::vector<BodyReach>& bodies, double reach) {
  const std::size_t n = bodies.size();
  std::vector<std::size_t> parent(n);
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  auto root = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      if (bodies[i].box.empty() || bodies[j].box.empty()) continue;
      if (bodies[i].box.distance(bodies[j].box) > reach + bodies[i].pad + bodies[j].pad) continue;
      const std::size_t a = root(i), b = root(j);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  std::vector<std::vector<std::size_t>> groups;
  std::vector<std::size_t> group_of_root(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t r = root(i);
    if (group_of_root[r] == n) {
      group_of_root[r] = groups.size();
      groups.emplace_back();
    }
    groups[group_of_root[r]].push_back(i);
  }
  return groups;
}

}  // namespace sflsh::scene::detail
