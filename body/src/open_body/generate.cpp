// The open body generator (the one driver of body/src/open_body/).
//
//  1. The average body (all anthropometric factors zero) is a skeleton with smooth implicit primitives
//     attached (skeleton.cpp, anatomy.cpp); CGAL meshes its zero level set and remeshes it to about
//     `target_vertices` vertices (surface_mesher.cpp). This triangulation is the topology of the model.
//  2. Skinning weights come from primitive membership, diffused on the surface (skin_weights.cpp).
//  3. `population` factor vectors z ~ N(0, C) are drawn (factors.cpp); for each, its own skeleton and
//     primitives are built and the template is carried onto its surface in correspondence: per-bone
//     affine warp, then Newton projection onto its zero level set (correspondence.cpp).
//  4. PCA over the population gives v_template (the mean) and shapedirs (√λ-scaled eigenvectors, so
//     β ~ N(0, I) spans the population, ordered by variance; shape_pca.cpp).
//  5. The joint regressor is fitted so that it reproduces every sample's skeleton (joint_regressor.cpp).
//  6. The named subjects are carried the same way and projected onto the PCA basis (subjects.cpp).
// Everything is deterministic for fixed options: the population comes from std::mt19937(seed), the
// mesher is seeded from the skeleton, and the parallel loop writes each sample to its own column.
#include "body_field.hpp"
#include "correspondence.hpp"
#include "factors.hpp"
#include "joint_regressor.hpp"
#include "mesh_topology.hpp"
#include "shape_pca.hpp"
#include "skeleton.hpp"
#include "skin_weights.hpp"
#include "subjects.hpp"
#include "surface_mesher.hpp"

#include <sflsh/body/open_body.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>

#include <tbb/parallel_for.h>

#include <chrono>

namespace sflsh::body {

OpenBodyResult generate_open_body(const OpenBodyOptions& options) {
  using namespace detail;
  require(options.population > 2 * kNumBetas, "open body: population {} must exceed {}", options.population,
          2 * kNumBetas);
  const auto start = std::chrono::steady_clock::now();
  const auto seconds = [&start]() { return seconds_since(start); };

  // 1–2. Template surface and weights.
  const Skeleton average = make_skeleton(AnthroFactors::Zero());
  const BodyField average_field = make_body_field(average);
  const TriangleSurface surface = mesh_body_surface(average_field, average, options.target_vertices);
  const Eigen::MatrixXd weights =
      skinning_weights(surface.vertices, surface.faces, surface.mirror, average_field, average);
  const Eigen::Index n = surface.vertices.rows();
  logger()->info("open body: template {} vertices, {} faces, weights done ({:.1f} s)", n, surface.faces.rows(),
                 seconds());

  // 3. Population and subjects, carried in correspondence (one column each).
  const std::vector<AnthroFactors> population = sample_population(options.population, options.seed);
  std::vector<OpenBodySubject> subjects = open_body_subject_definitions();
  std::vector<AnthroFactors> all = population;
  for (const OpenBodySubject& s : subjects) all.push_back(s.factors);
  const VertexAdjacency adjacency = vertex_adjacency(n, surface.faces);
  Eigen::MatrixXd surfaces(3 * n, static_cast<Eigen::Index>(all.size()));
  std::vector<JointArray> joints(all.size());
  tbb::parallel_for(std::size_t{0}, all.size(), [&](std::size_t k) {
    const Skeleton skeleton = make_skeleton(all[k]);
    const BodyField field = make_body_field(skeleton);
    const RowMatrixX3d carried = carry_template(surface.vertices, weights, adjacency, average, skeleton, field);
    surfaces.col(static_cast<Eigen::Index>(k)) = Eigen::Map<const Eigen::VectorXd>(carried.data(), 3 * n);
    joints[k] = skeleton.joints;
  });
  logger()->info("open body: {} population samples and {} subjects carried ({:.1f} s)", population.size(),
                 subjects.size(), seconds());

  // 4. Shape space.
  const auto samples = static_cast<Eigen::Index>(population.size());
  const ShapePca pca = shape_pca(surfaces.leftCols(samples), kNumBetas, population);

  OpenBodyResult result;
  BodyModel& model = result.model;
  model.name = "sflsh-open-body";
  model.v_template = Eigen::Map<const RowMatrixX3d>(pca.mean.data(), n, 3);
  model.faces = surface.faces;
  model.shapedirs = pca.directions;
  model.posedirs.resize(0, 0);
  model.weights = weights;
  model.parents = kJointParents;
  result.explained_variance = pca.explained;

  // 5. Joint regressor over the population.
  const std::vector<JointArray> population_joints(joints.begin(), joints.begin() + samples);
  model.joint_regressor = fit_joint_regressor(surface.vertices, surface.mirror, average_field, average,
                                              surfaces.leftCols(samples), population_joints);

  // 6. Subjects' β.
  for (std::size_t s = 0; s < subjects.size(); ++s)
    subjects[s].beta = project_to_pca(pca, surfaces.col(samples + static_cast<Eigen::Index>(s)));
  result.subjects = std::move(subjects);

  model.validate();
  logger()->info("open body: generated in {:.1f} s; explained variance of the {} components {:.4f}", seconds(),
                 kNumBetas, pca.explained.sum());
  return result;
}

}  // namespace sflsh::body
