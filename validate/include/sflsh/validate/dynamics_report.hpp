#pragma once
// Output of the dynamics metric: the neutral-pose surface with σ fields for ParaView, a per-vertex table,
// and the summary scalars for summary.json. Every file is written atomically.
#include <sflsh/validate/dynamics_metrics.hpp>

#include <nlohmann/json.hpp>

#include <filesystem>

namespace sflsh::validate {

/// The shaped template surface (n×3 points, the body's faces) as VTK PolyData with point data `sigma`,
/// `sigma_normal`, `sigma_tangent` [mm] (one value per body vertex) and `soft_region` (0/1).
void write_dynamics_vtp(const std::filesystem::path& path, const RowMatrixX3d& shaped, const body::RowMatrixX3i& faces,
                        const DynamicsResult& result);

/// CSV: vertex,sigma_mm,sigma_normal_mm,sigma_tangent_mm,soft — one row per body vertex.
void write_dynamics_csv(const std::filesystem::path& path, const DynamicsResult& result);

/// The summary scalars in mm: sigma_mean_soft_mm, sigma_mean_all_mm, sigma_normal_mean_soft_mm,
/// sigma_tangent_mean_soft_mm, sigma_max_mm, soft_vertices, frames.
nlohmann::json dynamics_summary(const DynamicsResult& result);

}  // namespace sflsh::validate
