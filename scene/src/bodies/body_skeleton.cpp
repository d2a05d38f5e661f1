#include "bodies/body_skeleton.hpp"

#include <sflsh/body/body_model.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <fstream>

namespace sflsh::scene::detail {

std::vector<double> carried_mass(const model::BodyLayer& layer) {
  const std::array<int, body::kNumJoints>& parents = layer.model->parents;
  std::vector<double> mass(body::kNumJoints, 0.0);
  for (int i = 0; i < layer.trajectory->num_nodes(); ++i)
    for (const auto& [joint, weight] : layer.trajectory->node_weights(i))
      mass[static_cast<std::size_t>(joint)] += layer.problem.mass[i] * weight;
  for (int k = body::kNumJoints - 1; k > 0; --k)  // children come after their parents
    mass[static_cast<std::size_t>(parents[static_cast<std::size_t>(k)])] += mass[static_cast<std::size_t>(k)];
  return mass;
}

reduced::JointTrackingOptions joint_tracking_options(const BodySpec& spec, const model::BodyLayer& layer) {
  reduced::JointTrackingOptions o;
  o.frequency = spec.joint_frequency;
  o.damping_ratio = spec.joint_damping_ratio;
  o.limit = spec.joint_limit;
  const std::vector<double> mass = carried_mass(layer);
  std::vector<int> joints;
  std::string skipped;
  if (spec.all_joints) {
    for (int k = 1; k < body::kNumJoints; ++k) {
      const double m = mass[static_cast<std::size_t>(k)];
      if (m >= kMinCarriedShare * mass[0]) {
        joints.push_back(k);
      } else if (m > 0.0) {
        skipped += fmt::format("{}{} {:.2f} kg", skipped.empty() ? "" : ", ",
                               body::kJointNames[static_cast<std::size_t>(k)], m);
      }
    }
  } else {
    for (const std::string& name : spec.tracked_joints) {
      const int j = body::joint_index(name);
      if (mass[static_cast<std::size_t>(j)] > 0.0)
        joints.push_back(j);
      else
        skipped += fmt::format("{}{} (carries nothing of the layer)", skipped.empty() ? "" : ", ", name);
    }
    std::sort(joints.begin(), joints.end());
    joints.erase(std::unique(joints.begin(), joints.end()), joints.end());
  }
  std::string tracked;
  for (int j : joints)
    tracked += fmt::format("{}{} {:.2f} kg", tracked.empty() ? "" : ", ",
                           body::kJointNames[static_cast<std::size_t>(j)], mass[static_cast<std::size_t>(j)]);
  logger()->info("scene: body '{}' tracks its root ({:.2f} kg) and {} joint(s){}{}{}", spec.name, mass[0],
                 joints.size(), tracked.empty() ? "" : ": " + tracked,
                 skipped.empty()
                     ? ""
                     : fmt::format("; not tracked (under {:.0f} % of the layer's mass): ", 100.0 * kMinCarriedShare),
                 skipped);
  if (joints.empty()) return o;  // the root alone
  o.setup.parents.assign(layer.model->parents.begin(), layer.model->parents.end());
  o.setup.joints = joints;
  o.setup.node_weights.reserve(static_cast<std::size_t>(layer.trajectory->num_nodes()));
  for (int i = 0; i < layer.trajectory->num_nodes(); ++i)
    o.setup.node_weights.push_back(layer.trajectory->node_weights(i));
  const auto value_of = [](const std::map<std::string, double>& table, int joint) {
    const auto it = table.find(body::kJointNames[static_cast<std::size_t>(joint)]);
    return it == table.end() ? 0.0 : it->second;
  };
  for (int j : joints) {
    o.stiffness.push_back(value_of(spec.joint_stiffness, j));
    o.damping.push_back(value_of(spec.joint_damping, j));
    o.limits.push_back(value_of(spec.joint_limits, j));
  }
  // c_j(t) = M_j(t) (J_j, 1) with J_j regressed from the shaped template, as the root's pivot.
  const body::JointPositions rest_joints = body::regress_joints(*layer.model, layer.shaped);
  o.centres = [curve = layer.curve, rest_joints, joints](double t, std::vector<Eigen::Vector3d>& centres) {
    model::JointTransforms m;
    curve->transforms(t, m);
    centres.resize(joints.size());
    for (std::size_t k = 0; k < joints.size(); ++k) {
      const auto j = static_cast<std::size_t>(joints[k]);
      centres[k] = m[j].leftCols<3>() * rest_joints.row(static_cast<Eigen::Index>(j)).transpose() + m[j].col(3);
    }
  };
  return o;
}

std::vector<reduced::Matrix34d> surface_deviation_maps(const reduced::ReducedSolver& solver,
                                                       const model::BodyLayer& layer) {
  const reduced::DeviationFrame frame = solver.deviation_frame();
  std::vector<reduced::Matrix34d> maps;
  maps.reserve(layer.vertex_weights.size());
  for (const auto& weights : layer.vertex_weights)
    maps.push_back(frame.map_blend(solver.skeleton().bone_blend(weights)));
  return maps;
}

std::vector<reduced::Matrix34d> node_deviation_maps(const reduced::ReducedSolver& solver,
                                                    const model::BodyLayer& layer) {
  const reduced::DeviationFrame frame = solver.deviation_frame();
  std::vector<reduced::Matrix34d> maps;
  maps.reserve(static_cast<std::size_t>(layer.problem.num_nodes()));
  for (int i = 0; i < layer.problem.num_nodes(); ++i) maps.push_back(frame.map_blend(frame.blend(i)));
  return maps;
}

void write_deviation_csv(const std::filesystem::path& path, const reduced::SkeletonDeviation& skeleton,
                         const std::vector<std::pair<double, Eigen::VectorXd>>& history) {
  std::ofstream out(path);
  require(static_cast<bool>(out), "{}: cannot write", path.string());
  out << "t_s,root_theta_x_rad,root_theta_y_rad,root_theta_z_rad,root_tau_x_m,root_tau_y_m,root_tau_z_m";
  for (int joint : skeleton.tracked())
    for (const char* axis : {"x", "y", "z"})
      out << ',' << body::kJointNames[static_cast<std::size_t>(joint)] << "_phi_" << axis << "_rad";
  out << '\n';
  for (const auto& [t, r] : history) {
    require(r.size() == skeleton.size(), "{}: a deviation of {} coordinates for {}", path.string(), r.size(),
            skeleton.size());
    out << fmt::format("{:.9g}", t);
    for (Eigen::Index k = 0; k < r.size(); ++k) out << fmt::format(",{:.9g}", r[k]);
    out << '\n';
  }
  require(static_cast<bool>(out), "{}: write failed", path.string());
}

meshing::RowMatrixX3d apply_maps(const std::vector<reduced::Matrix34d>& maps, const meshing::RowMatrixX3d& points) {
  require(maps.size() == static_cast<std::size_t>(points.rows()), "scene: {} deviation maps for {} points", maps.size(),
          points.rows());
  meshing::RowMatrixX3d out(points.rows(), 3);
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const reduced::Matrix34d& M = maps[static_cast<std::size_t>(i)];
    out.row(i) = (M.leftCols<3>() * points.row(i).transpose() + M.col(3)).transpose();
  }
  return out;
}

}  // namespace sflsh::scene::detail
