#pragma once
// Internal to the scene runner: which bodies can touch each other in a step. Bodies in different groups
// cannot reach each other's surfaces in that step, so their contact potentials find no candidate against
// each other whichever surface they see, and the groups can step in parallel with the same result as one
// step of all bodies as one group.
#include <sflsh/scene/obstacle.hpp>

#include <array>
#include <cstddef>
#include <vector>

namespace sflsh::scene::detail {

/// Where a body can be during a step: the box of its surface at the step's start and its predicted end, and
/// how far beyond the box its contact nodes may look (its motion over the step plus twice its largest
/// elastic displacement: the nodes' skinned end leaves the elastic part out).
struct BodyReach {
  Aabb box;
  double pad = 0.0;  ///< [m]
};

/// The connected components of items 0 … n − 1 joined by `links` (union-find: boost's disjoint sets), each
/// ascending, listed in the order of their first item.
std::vector<std::vector<std::size_t>> connected_components(std::size_t n,
                                                           const std::vector<std::array<std::size_t, 2>>& links);

/// Bodies i, j are linked when box_i and box_j are at most `reach` + pad_i + pad_j apart [m]; the groups are
/// the linked components, each ascending, listed in the order of their first body.
std::vector<std::vector<std::size_t>> contact_groups(const std::vector<BodyReach>& bodies, double reach);

}  // namespace sflsh::scene::detail
