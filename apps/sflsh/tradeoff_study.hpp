#pragma once
// sflsh tradeoff's study (tradeoff_study.cpp): one case run by a reference and a hierarchy of full-space and reduced
// configurations, each scored against the reference (docs/tradeoff.md); cmd_tradeoff.cpp parses the options and
// presets into TradeoffOptions.
#include "commands.hpp"
#include "layer_setup.hpp"

#include <string>
#include <vector>

namespace sflsh::app {

struct TradeoffOptions {
  std::string preset = "quick";
  SubjectOptions subject;
  std::string motion = "shake_hips";
  int frames = 8;
  double fps = 30.0;
  /// quick: Newmark with consistent masses at 1/960 s on the coarse mesh (second order and undamped: at that step
  /// its own time error is far below every row's; SUNDIALS at rtol 1e-6 costs ~93 s per 1/30 s frame there);
  /// full: the same on the default mesh at 1/480 s, checked against a finer step and a finer mesh.
  std::string reference = "newmark";          ///< sundials | backward_euler | bdf2 | newmark
  std::string reference_mass = "consistent";  ///< lumped | consistent
  std::string reference_mesh = "coarse";
  int reference_substeps = 32;      ///< stepping references only
  double rtol = 1e-6, atol = 1e-9;  ///< SUNDIALS reference
  /// How converged the reference is: "time" reruns it at twice the substeps, "space" on the next finer mesh, over
  /// the first reference_check_frames frames; the RMS difference is reported (summary.json "reference_checks").
  std::vector<std::string> reference_checks;
  int reference_check_frames = 8;
  std::vector<std::string> meshes = {"coarse"};
  std::vector<int> substeps = {1, 2, 4, 8};
  std::vector<std::string> integrators = {"backward_euler", "bdf2", "newmark"};
  std::vector<std::string> masses = {"lumped", "consistent"};
  std::vector<std::string> reduced_meshes = {"coarse"};
  std::vector<int> handles = {30, 86};
  std::vector<int> cubature = {200, 400};
  std::vector<int> reduced_substeps = {1, 4};
  double budget_mm = 0.0, budget_relative = 0.0;  ///< 0: not given
  LayerSettings layer;
  ReducedSettings reduced;
  std::string out;
};

/// Runs the study of `opt` and writes its run folder (tradeoff.csv/.md/.png, summary.json); one process only.
void run_tradeoff(const TradeoffOptions& opt, const Invocation& invocation, int rank, int size);

}  // namespace sflsh::app
