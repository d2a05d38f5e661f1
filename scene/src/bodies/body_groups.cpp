// Bodies that can touch each other in a step (body_groups.hpp).
#include "bodies/body_groups.hpp"

#include <boost/pending/disjoint_sets.hpp>

namespace sflsh::scene::detail {

std::vector<std::vector<std::size_t>> connected_components(std::size_t n,
                                                           const std::vector<std::array<std::size_t, 2>>& links) {
  boost::disjoint_sets_with_storage<> sets(n);
  for (std::size_t i = 0; i < n; ++i) sets.make_set(i);
  for (const auto& [a, b] : links) sets.union_set(a, b);
  std::vector<std::vector<std::size_t>> components;
  std::vector<std::size_t> component_of_root(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t r = sets.find_set(i);
    if (component_of_root[r] == n) {
      component_of_root[r] = components.size();
      components.emplace_back();
    }
    components[component_of_root[r]].push_back(i);
  }
  return components;
}

std::vector<std::vector<std::size_t>> contact_groups(const std::vector<BodyReach>& bodies, double reach) {
  const std::size_t n = bodies.size();
  std::vector<std::array<std::size_t, 2>> links;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      if (bodies[i].box.empty() || bodies[j].box.empty()) continue;
      if (bodies[i].box.distance(bodies[j].box) > reach + bodies[i].pad + bodies[j].pad) continue;
      links.push_back({i, j});
    }
  return connected_components(n, links);
}

}  // namespace sflsh::scene::detail
