// Retargeting the template layer to a shape and thickness (docs/architecture.md §3).
#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/meshing/retarget.hpp>
#include <sflsh/meshing/untangle.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

namespace sflsh::meshing {
namespace {

std::vector<char> boundary_flags(const LayerMesh& mesh) {
  std::vector<char> fixed(mesh.anchor.size(), 0);
  for (std::size_t i = 0; i < mesh.anchor.size(); ++i) fixed[i] = mesh.anchor[i].valid() ? 1 : 0;
  return fixed;
}

}  // namespace

Retargeter::Retargeter(const body::BodyModel& model, const LayerMesh& mesh, double stiffening)
    : model_(model), mesh_(mesh), interpolator_(mesh.nodes, mesh.tets, boundary_flags(mesh), stiffening) {
  require(model.num_vertices() == static_cast<Eigen::Index>(mesh.region_surface.local_of.size()),
          "retarget: the body model '{}' has {} vertices but the layer mesh was built for {} ('{}')", model.name,
          model.num_vertices(), mesh.region_surface.local_of.size(), mesh.body_name);
  depth_ = depth_field();
  tets_of_.resize(static_cast<std::size_t>(mesh.num_nodes()));
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e)
    for (int c = 0; c < 4; ++c) tets_of_[static_cast<std::size_t>(mesh.tets(e, c))].push_back(static_cast<int>(e));
  const LayerGeometry geometry = layer_geometry(model, mesh.region_surface, mesh.correspondence, body::Betas::Zero(),
                                                mesh.template_thickness_field());
  const Eigen::MatrixXd coordinates = interpolator_.extend(layer_coordinates(geometry));
  residual_ = mesh.nodes - coordinates.leftCols<3>() - coordinates.rightCols<3>().cwiseProduct(depth_.replicate(1, 3));
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (mesh.anchor[static_cast<std::size_t>(i)].valid()) residual_.row(i).setZero();  // round-off only
}

Eigen::MatrixXd Retargeter::layer_coordinates(const LayerGeometry& geometry) const {
  Eigen::MatrixXd values = Eigen::MatrixXd::Zero(mesh_.num_nodes(), 6);
  for (int i = 0; i < mesh_.num_nodes(); ++i) {
    const auto& anchor = mesh_.anchor[static_cast<std::size_t>(i)];
    if (!anchor.valid()) continue;
    for (int k = 0; k < 3; ++k) {
      const int v = anchor.vertex[k];
      const double w = anchor.weight(k);
      values.block<1, 3>(i, 0) += w * geometry.skin.row(v);
      values.block<1, 3>(i, 3) += w * geometry.thickness(v) * (geometry.skeleton.row(v) - geometry.skin.row(v));
    }
  }
  return values;
}

RetargetedLayer Retargeter::retarget(const body::Betas& beta, double uniform_thickness) const {
  return retarget(beta, Eigen::VectorXd::Constant(mesh_.region_surface.num_vertices(), uniform_thickness));
}

ShapedLayer Retargeter::shape(const body::Betas& beta) const {
  require(beta.allFinite(), "retarget: β has non-finite entries");
  const LayerGeometry geometry =
      layer_geometry(model_, mesh_.region_surface, mesh_.correspondence, beta, mesh_.template_thickness_field());
  ShapedLayer shaped;
  shaped.beta = beta;
  shaped.skin = geometry.skin;
  shaped.skeleton = geometry.skeleton;
  // S of the anchors carried inside; the extension is linear and column by column, so E[S] alone equals the
  // first three columns of the extension of (S, C) bit for bit.
  shaped.skin_extension = interpolator_.extend(layer_coordinates(geometry).leftCols<3>());
  return shaped;
}

Eigen::MatrixXd Retargeter::column_coordinates(const LayerGeometry& geometry) const {
  return layer_coordinates(geometry).rightCols<3>();
}

RowMatrixX3d Retargeter::node_derivative(const ShapedLayer& shaped, const Eigen::VectorXd& dthickness) const {
  require(shaped.skin.rows() == mesh_.region_surface.num_vertices() && dthickness.size() == shaped.skin.rows() &&
              dthickness.allFinite(),
          "retarget: a thickness change needs {} finite values, got {}", mesh_.region_surface.num_vertices(),
          dthickness.size());
  LayerGeometry change;
  change.skin = shaped.skin;
  change.skeleton = shaped.skeleton;
  change.thickness = dthickness;
  // dx = δ ⊙ E[dC] inside (E[S] and r do not depend on h) …
  RowMatrixX3d dx = interpolator_.extend(column_coordinates(change)).cwiseProduct(depth_.replicate(1, 3));
  for (int i = 0; i < mesh_.num_nodes(); ++i) {  // … and Σ_k w_k depth dh_k (c_k − s_k) on the boundary
    const auto& anchor = mesh_.anchor[static_cast<std::size_t>(i)];
    if (!anchor.valid()) continue;
    Eigen::RowVector3d d = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const double w = anchor.weight(k);
      if (w == 0.0) continue;
      const int v = anchor.vertex[k];
      d += w * anchor.depth * dthickness(v) * (shaped.skeleton.row(v) - shaped.skin.row(v));
    }
    dx.row(i) = d;
  }
  return dx;
}

RetargetedLayer Retargeter::retarget(const body::Betas& beta, const Eigen::VectorXd& thickness) const {
  return retarget(shape(beta), thickness, RetargetCheck::report);
}

RetargetedLayer Retargeter::retarget(const ShapedLayer& shaped, const Eigen::VectorXd& thickness,
                                     RetargetCheck check) const {
  const auto start = std::chrono::steady_clock::now();
  require(
      shaped.skin_extension.rows() == mesh_.num_nodes() && shaped.skin.rows() == mesh_.region_surface.num_vertices(),
      "retarget: the shaped layer was prepared for another mesh");
  validate_thickness(thickness, mesh_.region_surface.num_vertices(), "thickness");
  const body::Betas& beta = shaped.beta;
  RetargetedLayer result;
  result.geometry.skin = shaped.skin;
  result.geometry.skeleton = shaped.skeleton;
  result.geometry.thickness = thickness;

  // Layer coordinates (S, C) from the anchors, carried inside harmonically; x = S + δ C + r.
  const int n = mesh_.num_nodes();
  const Eigen::MatrixXd columns = interpolator_.extend(column_coordinates(result.geometry));
  result.nodes = shaped.skin_extension + columns.cwiseProduct(depth_.replicate(1, 3)) + residual_;
  for (int i = 0; i < n; ++i) {  // boundary nodes exactly on their anchors (the formula above is exact up to round-off)
    const auto& anchor = mesh_.anchor[static_cast<std::size_t>(i)];
    if (anchor.valid()) result.nodes.row(i) = result.geometry.position(anchor).transpose();
  }
  bool inverted = false;  // a signed-volume pass: the full quality report below is needed once, not twice
  for (Eigen::Index e = 0; e < mesh_.tets.rows() && !inverted; ++e)
    inverted = signed_volume(result.nodes, mesh_.tets, e) <= 0.0;
  if (inverted) result.untangled_nodes = untangle(result.nodes, mesh_.tets, boundary_flags(mesh_), tets_of_);
  if (check == RetargetCheck::light && tets_valid(result.nodes, mesh_.tets)) {
    result.quality.tets = static_cast<long>(mesh_.tets.rows());
    result.quality.nodes = static_cast<long>(n);
  } else {
    result.quality = layer_quality(mesh_, result.nodes, result.geometry);
  }
  result.seconds = seconds_since(start);

  if (result.quality.inverted > 0 || result.quality.degenerate > 0) {
    const TetQuality per_tet = tet_quality(result.nodes, mesh_.tets);
    std::map<std::string, long> inverted_by_part, degenerate_by_part;
    Eigen::Index worst = 0;
    per_tet.volume.minCoeff(&worst);
    for (Eigen::Index e = 0; e < per_tet.volume.size(); ++e) {
      const std::string part = part_name(mesh_.tet_part[static_cast<std::size_t>(e)]);
      if (per_tet.volume(e) <= 0.0)
        ++inverted_by_part[part];
      else if (per_tet.degenerate[static_cast<std::size_t>(e)])
        ++degenerate_by_part[part];
    }
    const auto listed = [](const std::map<std::string, long>& by_part) {
      std::string parts;
      for (const auto& [name, count] : by_part)
        parts += fmt::format("{}{}: {}", parts.empty() ? "" : ", ", name, count);
      return parts.empty() ? std::string("none") : parts;
    };
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int c = 0; c < 4; ++c) centre += 0.25 * result.nodes.row(mesh_.tets(worst, c)).transpose();
    throw_error(
        "retarget: shape β = [{:.2f}] with h in [{:.2f}, {:.2f}] inverts {} tets ({}) and leaves {} degenerate ({}); "
        "worst tet {} ({}) at ({:.3f}, {:.3f}, {:.3f}) m",
        fmt::join(beta.data(), beta.data() + beta.size(), ", "), thickness.minCoeff(), thickness.maxCoeff(),
        result.quality.inverted, listed(inverted_by_part), result.quality.degenerate, listed(degenerate_by_part), worst,
        part_name(mesh_.tet_part[static_cast<std::size_t>(worst)]), centre(0), centre(1), centre(2));
  }
  return result;
}

Eigen::MatrixXd Retargeter::extend_surface_field(const Eigen::MatrixXd& per_region_vertex) const {
  require(per_region_vertex.rows() == mesh_.region_surface.num_vertices(),
          "surface field: {} rows, expected one per region vertex ({})", per_region_vertex.rows(),
          mesh_.region_surface.num_vertices());
  Eigen::MatrixXd values = Eigen::MatrixXd::Zero(mesh_.num_nodes(), per_region_vertex.cols());
  for (int i = 0; i < mesh_.num_nodes(); ++i) {
    const auto& anchor = mesh_.anchor[static_cast<std::size_t>(i)];
    if (!anchor.valid()) continue;
    for (int s = 0; s < 3; ++s) values.row(i) += anchor.weight(s) * per_region_vertex.row(anchor.vertex[s]);
  }
  return interpolator_.extend(values);
}

Eigen::VectorXd Retargeter::depth_field() const {
  Eigen::MatrixXd depth = Eigen::MatrixXd::Zero(mesh_.num_nodes(), 1);
  for (int i = 0; i < mesh_.num_nodes(); ++i) {
    const auto& anchor = mesh_.anchor[static_cast<std::size_t>(i)];
    if (anchor.valid()) depth(i) = anchor.depth;
  }
  return interpolator_.extend(depth).col(0);
}

}  // namespace sflsh::meshing
