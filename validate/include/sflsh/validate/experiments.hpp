#pragma once
// The paper's experiments (SFLSH §6, Table 2, Figures 3–8) on synthetic ground truth: independent
// per-subject fits ("optimal targets"), leave-one-out cross-validation with the λ sweep (Fig. 5), full
// optimizations with L² and the local regularizer, generalization to test subjects, the covariance of
// fitted parameters per control point (Fig. 7) and — what the paper could not measure — the error of the
// recovered parameters against the true ones. `sflsh validate` is a thin front end.
#include <sflsh/meshing/layer_mesh.hpp>
#include <sflsh/reduced/lambda_choice.hpp>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace sflsh::validate {

// λ is chosen by the rules shared with `sflsh shapefit` (reduced/lambda_choice.hpp).
using reduced::choose_lambda;
using reduced::lambda_rule_name;
using reduced::LambdaChoice;
using reduced::LambdaRule;
using reduced::LambdaScore;
using reduced::mean_of_finite;
using reduced::parse_lambda_rule;
using reduced::standard_error_of_mean;

struct ValidateConfig {
  std::string preset = "quick";
  meshing::SizePreset mesh = meshing::SizePreset::coarse;
  int point_handles = 30;
  int cubature = -1;                        ///< −1: auto
  std::vector<std::string> train_subjects;  ///< fit on these
  std::vector<std::string> test_subjects;   ///< generalization
  std::vector<std::string> train_motions{"one_leg_jump", "running_on_spot", "shake_hips"};
  std::vector<std::string> test_motions{"jiggle_on_toes", "shake_shoulders"};
  int frames = 0;  ///< per clip; 0 = the motions' default length
  std::vector<int> stages{1, 12, 24, 84};
  int iterations = 8;       ///< per stage: the safety net; a stage normally stops on a convergence test (docs/fit.md)
  double loss_rtol = 1e-3;  ///< a stage converges when 2 accepted iterations lower its loss by ≤ this (relative)
  std::vector<double> lambdas{0.01, 0.1, 1.0};  ///< cross-validation sweep (Fig. 5), both regularizers
  /// Own grids per regularizer ("l2", "ours"; `--lambdas-l2`, `--lambdas-ours`): the two penalize different
  /// directions by different amounts, so one grid rarely brackets both minima. Empty: `lambdas`.
  std::map<std::string, std::vector<double>> lambdas_of;
  /// The grid of regularizer `tag`, ascending as given.
  const std::vector<double>& lambdas_for(const std::string& tag) const;
  bool cross_validation = true;
  /// At most this many λs added to each regularizer's grid, half a decade beyond its end, while the cross-validation
  /// error is least at that end (the sweep has not found its minimum; reduced/lambda_choice.hpp). 0: the grid as
  /// given; a one-λ grid is never extended.
  int lambda_extensions = 0;
  /// How λ is chosen from the sweep: the largest within one standard error of the least error (default), or the
  /// least error (the paper's; lambda_choice.hpp).
  LambdaRule lambda_rule = LambdaRule::one_standard_error;
  /// Leave-one-out λ sweep as a continuation: per (regularizer, left-out subject) the largest λ is fitted through
  /// every stage, each smaller λ only at the last stage from the previous λ's result (docs/fit.md).
  bool lambda_warm_start = true;
  /// Trust-region iterations of each warm-started fit of the continuation (0: `iterations`).
  int warm_iterations = 0;
  /// MPI ranks split into this many groups, each running whole fits (its ranks sharing each fit's simulations);
  /// 1: every rank works on every fit (fit_chains.hpp).
  int fit_groups = 1;
  /// dσ/dq: "exact" (forward sensitivities, thickness columns through the retarget), "hybrid" (sensitivities,
  /// thickness columns by one-sided differences) or "fd" (one-sided differences of every column, the paper's).
  std::string jacobian = "exact";
  int threads = 0;             ///< 0: all
  double thickness_max = 0.0;  ///< 0: what the mesh size retargets validly
  /// DYNA files: when given, the ground truth comes from their registrations instead of the synthetic
  /// solver runs. Train subjects are the files' subject ids (all that have every train motion, or
  /// train_subjects when set); their β and per-frame poses are fitted (pose_fit.hpp) and σ* measured by
  /// dynamics_metrics on the layer's region. Test subjects (β from data/*subjects.toml) have no truth.
  std::vector<std::filesystem::path> dyna;
  std::filesystem::path body_path;          ///< body model (empty: the open body); SMPL for DYNA data
  bool preset_subjects_overridden = false;  ///< train_subjects were chosen by the user (DYNA: select those ids)
  std::filesystem::path cache_dir;          ///< template mesh cache (empty: default)
  /// The synthetic truth's material: empty for the built-in one, else a shape model file (`--truth-model`,
  /// true_material.hpp).
  std::filesystem::path truth_model;
  bool progress = true;

  /// The presets: "quick" (coarse mesh, 3 train + 2 test subjects, one train and one test motion, 40
  /// frames, N = 1 → 4, 30 handles, stages to convergence with a cap of 40 iterations) and "paper" (coarse mesh,
  /// 5 + 7 subjects, 3 + 2 motions, 60 frames, N = 1 → 12 → 24 → 84, 86 handles, 8 iterations per stage and 3 per
  /// warm fit: capped, not yet converged). Throws for an unknown name.
  static ValidateConfig from_preset(const std::string& name);
  nlohmann::json to_json() const;
};

/// Runs everything into `out_dir` (staged, committed at the end; a checkpoint per fit and a cache per
/// ground-truth case under out_dir/state let an interrupted run resume). Returns summary.json's content.
nlohmann::json run_validation(const ValidateConfig& config, const std::filesystem::path& out_dir,
                              const nlohmann::json& header);

/// `sflsh groundtruth`: only the ground truth of every (train and test subject, train and test motion) of
/// `config`, written by write_ground_truth_files (groundtruth.h5 in the DYNA layout, truth/), plus
/// summary.json with the mean σ per case. Shares the state/groundtruth cache layout with run_validation.
nlohmann::json run_ground_truth(const ValidateConfig& config, const std::filesystem::path& out_dir,
                                const nlohmann::json& header);

}  // namespace sflsh::validate
