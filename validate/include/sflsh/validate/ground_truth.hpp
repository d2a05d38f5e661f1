#pragma once
// Synthetic ground truth (docs/architecture.md §5): the full-space backward-Euler solver run on a subject of the open
// body with the hidden material of true_material.hpp, recorded as the paper measures captured data —
// posed whole-body surfaces per frame (the DYNA layout) and the per-vertex dynamics σ*_n, σ*_t of the
// region's skin in the neutral pose (docs/physics.md §4) that the fits try to reproduce.
#include <sflsh/body/motion.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/layer_parameterization.hpp>
#include <sflsh/validate/true_material.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace sflsh::validate {

struct GroundTruthCase {
  std::string subject, motion;
  body::Betas beta = body::Betas::Zero();
  double fps = 60.0;
  Eigen::VectorXd sigma_normal, sigma_tangent;  ///< per region vertex [mm]
  material::KappaMatrix kappa;                  ///< the true κ per region vertex (physical)
  std::string truth;                            ///< TrueMaterial::fingerprint() of the material it ran with
  std::vector<body::RowMatrixX3d> posed;        ///< whole posed body per frame [m] (empty unless asked)
  double seconds = 0.0;
  int newton_iterations = 0;

  Eigen::VectorXd sigma() const;  ///< [σ*_n; σ*_t] (2R), the fit's target layout
  double mean_sigma() const;      ///< mean over region vertices of √(σ_n² + σ_t²) [mm]
};

struct GroundTruthOptions {
  material::ParameterBounds bounds;
  TrueMaterial truth;       ///< the hidden material (default: the built-in one)
  bool keep_frames = true;  ///< fill GroundTruthCase::posed
};

/// Runs the full-space solver (one process, PETSc on MPI_COMM_SELF) over the layer's motion with the true
/// material of `layer.beta`. `parameterization` supplies the retargeter of the layer's template.
GroundTruthCase simulate_ground_truth(const model::BodyLayer& layer, const body::Motion& motion,
                                      const std::string& subject,
                                      const reduced::LayerParameterization& parameterization,
                                      const model::BodyLayerOptions& layer_options, const GroundTruthOptions& options);

/// Per-case cache (npz: sigma_normal, sigma_tangent, kappa, beta, posed frames when kept), so that runs
/// can resume and several commands can share one ground truth. load returns false for a missing or
/// unreadable file.
void save_ground_truth_case(const std::filesystem::path& path, const GroundTruthCase& c);
bool load_ground_truth_case(const std::filesystem::path& path, GroundTruthCase& c);

}  // namespace sflsh::validate

namespace sflsh::validate {

/// Writes the synthetic ground truth as captured data would come: `<dir>/groundtruth.h5` in the DYNA layout
/// (faces, one (V, 3, T) dataset per "<subject>_<motion>", attributes fps and beta per dataset, and on the
/// file "source" = "sflsh synthetic ground truth" and the body name), and the true parameters beside it:
/// `<dir>/truth/<subject>.npz` (region_vertices, kappa per region vertex [h, Pa, Pa], beta) and
/// `<dir>/truth/true_material.json`. Files are staged in `run` (atomic). Cases need their posed frames.
void write_ground_truth_files(RunFolder& run, const body::BodyModel& model, const meshing::LayerMesh& mesh,
                              const std::vector<const GroundTruthCase*>& cases, const material::ParameterBounds& bounds,
                              const TrueMaterial& truth);

}  // namespace sflsh::validate
