#pragma once
// Internal to the scene runner: a [crowd] expanded into bodies (the paper's Fig. 1): random shapes β, each
// avatar's own shape-dependent material κ(s, β) = A(s)ᵀβ + b(s) from a shape model (eq. 1), per-avatar time
// offsets of one motion, on a grid.
#include <sflsh/body/body_model.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/scene/scene_file.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace sflsh::scene::detail {

struct Crowd {
  std::vector<BodySpec> bodies;
  std::vector<material::MaterialFile> materials;  ///< per body
  std::string shape_model;                        ///< the file the materials came from
};

/// Deterministic for a seed: β_k ~ N(0, σ²) clamped to ±3, offsets uniform in [0, max_offset).
Crowd expand_crowd(const CrowdSpec& spec, const body::BodyModel& model, const std::filesystem::path& data_dir);

}  // namespace sflsh::scene::detail
