#pragma once
// The part of the body skin that carries the soft-tissue layer (paper Fig. 2: torso, upper arms,
// thighs), selected from the skinning weights of the named joints with a clean boundary curve.
#include <sflsh/body/body_model.hpp>
#include <sflsh/meshing/types.hpp>

#include <string>
#include <vector>

namespace sflsh::meshing {

/// Region names accepted by select_region: "torso", "upper_arms", "thighs", "left_upper_arm",
/// "right_upper_arm", "left_thigh", "right_thigh".
const std::vector<std::string>& known_region_names();
/// The paper's region: torso, upper arms and thighs.
std::vector<std::string> default_region_names();
/// Splits "torso,upper_arms" and checks each name; throws naming an unknown one and the known ones.
std::vector<std::string> parse_region_names(const std::string& csv);
/// "torso+upper_arms+thighs": a stable key for caches and summaries.
std::string region_key(const std::vector<std::string>& names);

struct Region {
  std::vector<std::string> names;
  std::vector<int> vertices;    ///< body vertex index of each local region vertex (ascending)
  std::vector<int> local_of;    ///< body vertex → local index, or −1 outside the region
  RowMatrixX3i faces;           ///< region faces in LOCAL indices, orientation as in the body
  std::vector<int> body_faces;  ///< body face index of each region face
  std::vector<Part> part;       ///< per local vertex
  /// Boundary curves as closed loops of local vertex indices, each ordered so that it runs along the
  /// region faces' boundary edges in their orientation (a → b for a face edge a → b).
  std::vector<std::vector<int>> boundary_loops;

  int num_vertices() const { return static_cast<int>(vertices.size()); }
  int num_faces() const { return static_cast<int>(faces.rows()); }
};

/// Selects the region: per vertex the summed skinning weight of the named parts' joints, smoothed
/// over the surface, thresholded at ½ per face; then cleaned (no one-triangle teeth or notches, no
/// pinched vertices, stray islands dropped, holes filled). Throws naming the names when the
/// result is empty or not a manifold surface with boundary.
Region select_region(const body::BodyModel& model, const std::vector<std::string>& names);

}  // namespace sflsh::meshing
