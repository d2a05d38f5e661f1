#pragma once
// What the stability suites of both solvers share (docs/architecture.md §8): the open body on the coarse layer, a
// material with per-control-point κ, the skinned layer's kinetic energy (the energy scale the skeleton feeds
// into the tissue) and the bounded-energy check.
#include <sflsh/body/body_io.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/step_stats.hpp>

#include <gtest/gtest.h>

#include <functional>

namespace sflsh::stability {

inline const body::BodyModel& open_body() {
  static const body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  return model;
}

inline model::BodyLayerOptions coarse() {
  model::BodyLayerOptions options;
  options.size = meshing::SizePreset::coarse;
  options.cache_dir = SFLSH_TEST_CACHE;
  return options;
}

/// The default material at 12 control points with each control point's κ set by `kappa_of(i)`.
inline material::MaterialFile material_with(const std::function<material::Kappa(int)>& kappa_of) {
  meshing::LayerMeshOptions mesh_options;
  mesh_options.mesher = coarse().mesher;
  mesh_options.size = coarse().size;
  const meshing::LayerMesh mesh = meshing::cached_layer_mesh(open_body(), mesh_options, SFLSH_TEST_CACHE);
  material::MaterialFile file = material::default_material(open_body(), mesh, 12, "stability");
  file.bounds.thickness = {0.05, 0.95};
  for (std::size_t i = 0; i < file.control_points.size(); ++i)
    file.control_points[i].kappa = kappa_of(static_cast<int>(i));
  return file;
}

struct Outcome {
  double max_kinetic = 0.0;      ///< max over frames of ½ Σ m |ṗ|² [J]
  double max_elastic = 0.0;      ///< max over frames of E(x) [J]
  double skinned_kinetic = 0.0;  ///< max over frames of the kinetic energy of the purely skinned layer [J]
  double initial_elastic = 0.0;
  long failed_attempts = 0;
  long projected_retries = 0;    ///< exact-Hessian attempts repeated with the projected Hessian
  long newton_iterations = 0;    ///< summed over the run
  int max_newton_per_frame = 0;  ///< the largest Newton count of one frame
  int frames = 0;
};

/// A step's counters folded into `out` (one frame = one step here).
inline void record_step(const model::StepStats& st, Outcome& out) {
  out.failed_attempts += st.failed_attempts;
  out.projected_retries += st.projected_retries;
  out.newton_iterations += st.newton_iterations;
  out.max_newton_per_frame = std::max(out.max_newton_per_frame, st.newton_iterations);
}

/// ½ Σ m_i |d/dt (A_i x̄_i + d_i)|² at time t: the kinetic energy of the layer moving rigidly with the skin.
inline double skinned_kinetic_energy(const model::Problem& p, double t) {
  const Eigen::Map<const Eigen::VectorXd> rest(p.rest.data(), p.num_dofs());
  model::NodeFrame frame, rate;
  p.frame(t, frame, &rate);
  double kinetic = 0.0;
  for (int i = 0; i < p.num_nodes(); ++i) {
    const Eigen::Vector3d v = rate.A[static_cast<std::size_t>(i)] * rest.segment<3>(3 * i) + rate.d.row(i).transpose();
    kinetic += 0.5 * p.mass[i] * v.squaredNorm();
  }
  return kinetic;
}

/// Records one frame's state: finite, and its energies folded into `out`.
inline void record_frame(const model::Problem& p, const model::State& s, double t, std::size_t f, Outcome& out) {
  EXPECT_TRUE(s.x.allFinite() && s.w.allFinite()) << "frame " << f;
  const model::Energies e = model::energies(p, s);
  EXPECT_TRUE(std::isfinite(e.kinetic) && std::isfinite(e.elastic)) << "frame " << f;
  out.max_kinetic = std::max(out.max_kinetic, e.kinetic);
  out.max_elastic = std::max(out.max_elastic, e.elastic);
  out.skinned_kinetic = std::max(out.skinned_kinetic, skinned_kinetic_energy(p, t));
  ++out.frames;
}

/// Bounded energy: backward Euler only dissipates, so the tissue's kinetic and elastic energy stay within
/// what the skeleton's motion (whose skinned kinetic energy is the scale) and the initial state put in.
/// A factor 10 leaves room for the relative motion of tissue against bone (it is ≈ 0.1–2 in these runs);
/// an instability grows without bound and exceeds it by orders of magnitude.
inline void expect_bounded(const Outcome& o) {
  const double budget = 10.0 * o.skinned_kinetic + 2.0 * o.initial_elastic;
  EXPECT_GT(o.skinned_kinetic, 0.0);
  EXPECT_LT(o.max_kinetic, budget) << "skinned kinetic energy " << o.skinned_kinetic;
  EXPECT_LT(o.max_elastic, budget) << "skinned kinetic energy " << o.skinned_kinetic;
}

inline body::Betas beta_with(int component, double value) {
  body::Betas beta = body::Betas::Zero();
  beta[component] = value;
  return beta;
}

}  // namespace sflsh::stability
