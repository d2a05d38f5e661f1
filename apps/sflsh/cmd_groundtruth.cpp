// sflsh groundtruth [--preset quick|paper] --out DIR: synthetic ground truth — full-space simulations of the
// open body's train and test subjects over the motions with a hidden, smoothly shape-dependent material —
// written as DYNA-layout HDF5 (groundtruth.h5) with the true parameters beside it (truth/).
#include "commands.hpp"
#include "layer_setup.hpp"

#include <sflsh/core/log.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/meshing/layer_mesh.hpp>
#include <sflsh/validate/experiments.hpp>

namespace sflsh::app {

namespace {

struct GroundTruthOptions {
  std::string preset = "paper";
  std::string out;
  std::string mesh;
  int frames = -1;
  int threads = 0;
  std::string truth_model;
  std::vector<std::string> subjects, motions;
};

}  // namespace

void register_groundtruth_commands(CLI::App& app, const Invocation& invocation) {
  auto o = std::make_shared<GroundTruthOptions>();
  auto* cmd = app.add_subcommand(
      "groundtruth",
      "Synthetic ground truth: full-space simulations of the open body's subjects with a hidden shape-dependent "
      "material (docs/fit.md), written as groundtruth.h5 in the DYNA layout (one (V, 3, T) dataset per "
      "<subject>_<motion>) with the true parameters in truth/. Cached per case in DIR/state (resumable).");
  cmd->add_option("--preset", o->preset,
                  "Subjects, motions and frames of `sflsh validate --preset` (default paper: "
                  "5 train + 5 test subjects, 5 motions, 60 frames)")
      ->check(CLI::IsMember({"quick", "paper"}));
  cmd->add_option("--out", o->out, "Output folder")->required();
  add_mesh_option(*cmd, o->mesh, false, "preset: coarse");  // empty: the preset's
  cmd->add_option("--frames", o->frames, "Frames per motion (0 = the motions' default length)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--subjects", o->subjects,
                  "Comma-separated subject names (replaces the preset's train and test subjects)")
      ->delimiter(',');
  cmd->add_option("--motions", o->motions, "Comma-separated motion names (replaces the preset's motions)")
      ->delimiter(',');
  cmd->add_option("--threads", o->threads, "Threads per process (0 = all)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--truth-model", o->truth_model,
                  "Shape model file (TOML, as `sflsh shapefit` writes) whose κ(β) is the hidden material instead of "
                  "the built-in one: κ at its control points is the model's, carried over the layer by φ");
  cmd->callback([o, invocation] {
    with_petsc(invocation, [&](int, int) {
      validate::ValidateConfig config = validate::ValidateConfig::from_preset(o->preset);
      if (!o->mesh.empty()) config.mesh = meshing::parse_size_preset(o->mesh);
      if (o->frames >= 0) config.frames = o->frames;
      config.threads = o->threads;
      config.truth_model = o->truth_model;
      if (!o->subjects.empty()) {
        config.train_subjects = o->subjects;
        config.test_subjects.clear();
      }
      if (!o->motions.empty()) {
        config.train_motions = o->motions;
        config.test_motions.clear();
      }
      const nlohmann::json summary =
          validate::run_ground_truth(config, o->out, summary_header("groundtruth", invocation.argc, invocation.argv));
      logger()->info("groundtruth: {} cases written to {}", summary["cases"].size(), o->out);
    });
  });
}

}  // namespace sflsh::app
