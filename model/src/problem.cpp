#include "deterministic_reduce.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/model/kinematics.hpp>
#include <sflsh/model/problem.hpp>

#include <Eigen/Geometry>
#include <tbb/blocked_range.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace sflsh::model {

void Dirichlet::add(int node, unsigned axis_mask, int drive_index) {
  require(node >= 0, "Dirichlet: negative node index {}", node);
  require(axis_mask != 0 && axis_mask < 8u, "Dirichlet: axis mask {} is not a non-empty subset of xyz", axis_mask);
  require(drive_index >= -1 && drive_index < static_cast<int>(drives.size()),
          "Dirichlet: drive index {} out of range (have {} drives)", drive_index, drives.size());
  for (int axis = 0; axis < 3; ++axis) {
    if ((axis_mask & (1u << axis)) == 0) continue;
    const int d = 3 * node + axis;
    bool found = false;
    for (std::size_t k = 0; k < dof.size(); ++k) {
      if (dof[k] != d) continue;
      found = true;
      require(drive[k] == drive_index, "Dirichlet: component {} of node {} is prescribed twice with different values",
              "xyz"[axis], node);
    }
    if (!found) {
      dof.push_back(d);
      drive.push_back(drive_index);
    }
  }
}

void Dirichlet::finalize() {
  require(dof.size() == drive.size(), "Dirichlet: {} dofs but {} drive entries", dof.size(), drive.size());
  std::vector<std::size_t> order(dof.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return dof[a] < dof[b]; });
  std::vector<int> sorted_dof(dof.size()), sorted_drive(dof.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    sorted_dof[k] = dof[order[k]];
    sorted_drive[k] = drive[order[k]];
  }
  for (std::size_t k = 1; k < sorted_dof.size(); ++k) {
    require(sorted_dof[k] != sorted_dof[k - 1], "Dirichlet: dof {} constrained twice", sorted_dof[k]);
  }
  for (int id : sorted_drive) {
    require(id >= -1 && id < static_cast<int>(drives.size()), "Dirichlet: drive index {} out of range", id);
    if (id >= 0)
      require(static_cast<bool>(drives[id].value) && static_cast<bool>(drives[id].rate),
              "Dirichlet: drive {} has no value or rate function", id);
  }
  dof = std::move(sorted_dof);
  drive = std::move(sorted_drive);
}

Eigen::VectorXd Dirichlet::values(double t) const {
  std::vector<double> drive_value(drives.size());
  for (std::size_t k = 0; k < drives.size(); ++k) drive_value[k] = drives[k].value(t);
  Eigen::VectorXd u(dof.size());
  for (std::size_t k = 0; k < dof.size(); ++k)
    u[static_cast<Eigen::Index>(k)] = drive[k] < 0 ? 0.0 : drive_value[drive[k]];
  require(u.allFinite(), "Dirichlet: a prescribed displacement is not finite at t = {}", t);
  return u;
}

Eigen::VectorXd Dirichlet::rates(double t) const {
  std::vector<double> drive_rate(drives.size());
  for (std::size_t k = 0; k < drives.size(); ++k) drive_rate[k] = drives[k].rate(t);
  Eigen::VectorXd r(dof.size());
  for (std::size_t k = 0; k < dof.size(); ++k)
    r[static_cast<Eigen::Index>(k)] = drive[k] < 0 ? 0.0 : drive_rate[drive[k]];
  require(r.allFinite(), "Dirichlet: a prescribed velocity is not finite at t = {}", t);
  return r;
}

std::vector<char> Dirichlet::mask(int num_nodes) const {
  std::vector<char> m(static_cast<std::size_t>(3 * num_nodes), 0);
  for (int d : dof) m[static_cast<std::size_t>(d)] = 1;
  return m;
}

void NodeTrajectory::evaluate_nodes(double t, const std::vector<int>& nodes, NodeFrame& frame) const {
  NodeFrame all;
  evaluate(t, all);
  frame.A.resize(nodes.size());
  frame.d.resize(static_cast<Eigen::Index>(nodes.size()), 3);
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    frame.A[k] = all.A[static_cast<std::size_t>(nodes[k])];
    frame.d.row(static_cast<Eigen::Index>(k)) = all.d.row(nodes[k]);
  }
}

void Problem::validate() {
  const int n = num_nodes();
  const int m = num_tets();
  require(n > 0, "problem: no nodes");
  require(m > 0, "problem: no tets");
  require(rest.allFinite(), "problem: rest positions are not finite");
  require(tets.minCoeff() >= 0 && tets.maxCoeff() < n, "problem: tet node index out of range [0, {})", n);
  require(static_cast<int>(tet_material.size()) == m, "problem: {} tet materials for {} tets", tet_material.size(), m);
  require(tet_energy_scale.empty() || static_cast<int>(tet_energy_scale.size()) == m,
          "problem: {} tet energy scales for {} tets", tet_energy_scale.size(), m);
  for (double s : tet_energy_scale)
    require(std::isfinite(s) && s > 0.0, "problem: tet energy scale {} is not positive", s);
  if (tet_rest.empty()) {
    tet_rest.resize(static_cast<std::size_t>(m));
    for (int e = 0; e < m; ++e) {
      material::TetNodes X;
      for (int a = 0; a < 4; ++a) X.col(a) = rest.row(tets(e, a)).transpose();
      try {
        tet_rest[static_cast<std::size_t>(e)] = material::make_tet_rest(X);
      } catch (const Error& err) {
        throw_error("problem: tet {}: {}", e, err.what());
      }
    }
  }
  require(static_cast<int>(tet_rest.size()) == m, "problem: {} rest tets for {} tets", tet_rest.size(), m);
  if (mass.size() == 0) mass = Eigen::VectorXd::Zero(n);
  require(mass.size() == n, "problem: {} masses for {} nodes", mass.size(), n);
  require(mass.allFinite() && mass.minCoeff() >= 0.0, "problem: masses must be finite and non-negative");
  if (tet_mass.size() == 0 && density > 0.0) tet_mass = tet_masses(rest, tets, density);
  if (mass_kind == MassKind::consistent && dynamic()) {
    require(tet_mass.size() == m, "problem: consistent mass needs ρV per tet (a density), have {} for {} tets",
            tet_mass.size(), m);
    // The lumped masses must be the consistent matrix's row sums (gravity and the reports use them).
    Eigen::VectorXd row_sum = Eigen::VectorXd::Zero(n);
    for (int e = 0; e < m; ++e)
      for (int a = 0; a < 4; ++a) row_sum[tets(e, a)] += 0.25 * tet_mass[e];
    require((row_sum - mass).cwiseAbs().maxCoeff() <= 1e-9 * std::max(1e-300, mass.cwiseAbs().maxCoeff()),
            "problem: the lumped masses are not the row sums of the consistent mass (different density?)");
  }
  require(gravity.allFinite(), "problem: gravity is not finite");
  dirichlet.finalize();
  for (int d : dirichlet.dof) require(d < num_dofs(), "problem: constrained dof {} out of range", d);
  if (trajectory)
    require(trajectory->num_nodes() == n, "problem: trajectory has {} nodes, mesh {}", trajectory->num_nodes(), n);
  if (!dynamic()) {
    require(!dirichlet.dof.empty(), "problem: a static problem (no mass) needs prescribed components");
  }
}

Eigen::SparseMatrix<double, Eigen::RowMajor> Problem::mass_matrix() const {
  if (mass_kind == MassKind::consistent && tet_mass.size() == num_tets())
    return consistent_mass_matrix(tets, tet_mass, num_nodes());
  Eigen::SparseMatrix<double, Eigen::RowMajor> M(num_nodes(), num_nodes());
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < num_nodes(); ++i) entries.emplace_back(i, i, mass.size() ? mass[i] : 0.0);
  M.setFromTriplets(entries.begin(), entries.end());
  return M;
}

void Problem::frame(double t, NodeFrame& out, NodeFrame* rate) const {
  if (trajectory) {
    trajectory->evaluate(t, out, rate);
    return;
  }
  const auto n = static_cast<std::size_t>(num_nodes());
  out.A.assign(n, Eigen::Matrix3d::Identity());
  out.d = RowMatrixX3d::Zero(num_nodes(), 3);
  if (rate != nullptr) {
    rate->A.assign(n, Eigen::Matrix3d::Zero());
    rate->d = RowMatrixX3d::Zero(num_nodes(), 3);
  }
}

void Problem::apply_dirichlet(double t, Eigen::Ref<Eigen::VectorXd> x) const {
  const Eigen::VectorXd u = dirichlet.values(t);
  for (std::size_t k = 0; k < dirichlet.dof.size(); ++k) {
    const int d = dirichlet.dof[k];
    x[d] = rest(d / 3, d % 3) + u[static_cast<Eigen::Index>(k)];
  }
}

Eigen::VectorXd lumped_masses(const RowMatrixX3d& rest, const RowMatrixX4i& tets, double density) {
  require(std::isfinite(density) && density >= 0.0, "density must be finite and non-negative, got {}", density);
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(rest.rows());
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    const Eigen::Vector3d a = rest.row(tets(e, 0)), b = rest.row(tets(e, 1)), c = rest.row(tets(e, 2)),
                          d = rest.row(tets(e, 3));
    const double volume = std::abs((b - a).dot((c - a).cross(d - a))) / 6.0;
    for (int k = 0; k < 4; ++k) mass[tets(e, k)] += density * volume / 4.0;
  }
  return mass;
}

namespace {

material::TetNodes gather(const Problem& problem, const Eigen::VectorXd& x, int e) {
  material::TetNodes nodes;
  for (int a = 0; a < 4; ++a) nodes.col(a) = x.segment<3>(3 * problem.tets(e, a));
  return nodes;
}

}  // namespace

ElasticEvaluation evaluate_elastic(const Problem& problem, const Eigen::VectorXd& x, bool with_gradient) {
  require(x.size() == problem.num_dofs(), "evaluate_elastic: state has {} entries, expected {}", x.size(),
          problem.num_dofs());
  struct Partial {
    double energy = 0.0;
    Eigen::VectorXd gradient;
  };
  const int m = problem.num_tets();
  const Eigen::Index dofs = with_gradient ? problem.num_dofs() : 0;
  Partial total = deterministic_reduce(
      m, Partial{0.0, Eigen::VectorXd::Zero(dofs)},
      [&](const tbb::blocked_range<int>& range, Partial acc) {
        for (int e = range.begin(); e < range.end(); ++e) {
          const auto se = static_cast<std::size_t>(e);
          const material::TetNodes nodes = gather(problem, x, e);
          const double scale = problem.tet_energy_scale.empty() ? 1.0 : problem.tet_energy_scale[se];
          if (with_gradient) {
            const material::TetElastic el =
                material::tet_elastic(problem.tet_rest[se], nodes, problem.tet_material[se], false);
            acc.energy += scale * el.energy;
            for (int a = 0; a < 4; ++a)
              acc.gradient.segment<3>(3 * problem.tets(e, a)) += scale * el.gradient.segment<3>(3 * a);
          } else {
            acc.energy += scale * material::tet_elastic_energy(problem.tet_rest[se], nodes, problem.tet_material[se]);
          }
        }
        return acc;
      },
      [](Partial a, const Partial& b) {
        a.energy += b.energy;
        a.gradient += b.gradient;
        return a;
      },
      512);
  ElasticEvaluation out;
  out.energy = total.energy;
  out.gradient = with_gradient ? std::move(total.gradient) : Eigen::VectorXd();
  return out;
}

RowMatrixX3d posed_positions(const NodeFrame& frame, const Eigen::VectorXd& x) {
  const auto n = static_cast<Eigen::Index>(frame.A.size());
  require(x.size() == 3 * n && frame.d.rows() == n, "posed_positions: {} maps, {} offsets, state of {}", n,
          frame.d.rows(), x.size());
  RowMatrixX3d p(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    p.row(i) = (frame.A[static_cast<std::size_t>(i)] * x.segment<3>(3 * i) + frame.d.row(i).transpose()).transpose();
  }
  return p;
}

Energies energies(const Problem& problem, const State& state) {
  Energies out;
  NodeFrame frame;
  problem.frame(state.t, frame);
  const RowMatrixX3d p = posed_positions(frame, state.x);
  for (int i = 0; i < problem.num_nodes(); ++i) {
    const double m = problem.mass[i];
    if (problem.mass_kind == MassKind::lumped) out.kinetic += 0.5 * m * state.w.segment<3>(3 * i).squaredNorm();
    out.gravity -= m * problem.gravity.dot(p.row(i).transpose());
  }
  if (problem.mass_kind == MassKind::consistent) {
    for (int e = 0; e < problem.num_tets(); ++e) {
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
          out.kinetic += 0.5 * problem.tet_mass[e] * consistent_mass_factor(a, b) *
                         state.w.segment<3>(3 * problem.tets(e, a)).dot(state.w.segment<3>(3 * problem.tets(e, b)));
    }
  }
  out.elastic = evaluate_elastic(problem, state.x, false).energy;
  return out;
}

State initial_state(const Problem& problem, double t0) {
  State s;
  s.t = t0;
  s.x = Eigen::Map<const Eigen::VectorXd>(problem.rest.data(), problem.num_dofs());
  problem.apply_dirichlet(t0, s.x);
  s.w = kinematic_velocity(problem, s.x, t0);
  return s;
}

}  // namespace sflsh::model
