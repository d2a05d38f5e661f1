// The step gradient's dependence on the rest geometry (rest_geometry_derivative.hpp has the formulas).
#include <sflsh/core/error.hpp>
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/reduced/rest_geometry_derivative.hpp>

#include <algorithm>

namespace sflsh::reduced {

namespace {

using Vector9d = Eigen::Matrix<double, 9, 1>;

/// The material with its axis turned to `axis` (unit): P_Y = Y_t^{1/4}(I − nnᵀ) + Y_n^{1/4} nnᵀ keeps its two
/// eigenvalues, read back from the current P_Y (b = nᵀP_Y n, a = (tr P_Y − b)/2).
material::OrthotropicFung with_axis(const material::OrthotropicFung& m, const Eigen::Vector3d& axis) {
  const double b = m.normal.dot(m.scaling * m.normal), a = 0.5 * (m.scaling.trace() - b);
  material::OrthotropicFung out = m;
  out.normal = axis;
  const Eigen::Matrix3d nn = axis * axis.transpose();
  out.scaling = a * (Eigen::Matrix3d::Identity() - nn) + b * nn;
  return out;
}

/// ∂vec(P)/∂n (9 × 3) at F, as the derivative along (I − nnᵀ)e_k of the normalized axis: central differences of
/// the closed-form stress over a turn of 1e-5 rad (truncation ~1e-10, round-off ~1e-11 relative).
Eigen::Matrix<double, 9, 3> stress_axis_derivative(const Eigen::Matrix3d& F, const material::OrthotropicFung& m) {
  constexpr double kTurn = 1e-5;
  Eigen::Matrix<double, 9, 3> out;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(k) - m.normal * m.normal(k);
    if (e.norm() < 1e-12) {
      out.col(k).setZero();
      continue;
    }
    const Eigen::Matrix3d plus = material::dpsi_ortho_fung_dF(F, with_axis(m, (m.normal + kTurn * e).normalized()));
    const Eigen::Matrix3d minus = material::dpsi_ortho_fung_dF(F, with_axis(m, (m.normal - kTurn * e).normalized()));
    const Eigen::Matrix3d d = (plus - minus) / (2.0 * kTurn);
    out.col(k) = Eigen::Map<const Vector9d>(d.data());
  }
  return out;
}

}  // namespace

RestGeometryDerivative::RestGeometryDerivative(const model::Problem& problem, const Subspace& subspace,
                                               const CubatureElastic& elastic, const ReducedInertia& inertia,
                                               const std::vector<meshing::RowMatrixX3d>& directions,
                                               const Eigen::VectorXd& depth, bool inertia_on)
    : problem_(problem),
      subspace_(subspace),
      elastic_(elastic),
      inertia_(inertia),
      directions_(directions),
      depth_(depth),
      columns_(static_cast<int>(directions.size())),
      inertia_on_(inertia_on) {
  require(inertia.mass_kind() == model::MassKind::lumped,
          "rest-geometry derivative: derived for a lumped mass only, the problem has a consistent one");
  require(problem.density > 0.0, "rest-geometry derivative: the problem has no density (masses ρV/4 per tet)");
  require(depth.size() == problem.num_nodes(), "rest-geometry derivative: {} depth values for {} nodes", depth.size(),
          problem.num_nodes());
  for (int id : problem.dirichlet.drive)
    require(id < 0, "rest-geometry derivative: derived for fixed attachments (x_D = X) only");
  for (const auto& d : directions)
    require(d.rows() == problem.num_nodes() && d.allFinite(),
            "rest-geometry derivative: a direction has {} rows, expected {} finite", d.rows(), problem.num_nodes());
  const int C = columns_;
  const std::vector<int>& nodes = inertia.inertia_nodes();
  const auto n = static_cast<Eigen::Index>(nodes.size());
  node_directions_.resize(3 * n, C);
  for (Eigen::Index a = 0; a < n; ++a)
    for (int j = 0; j < C; ++j)
      node_directions_.block<3, 1>(3 * a, j) = directions[static_cast<std::size_t>(j)].row(nodes[a]).transpose();

  // dm_i = ρ Σ_{e ∋ i} dV_e / 4, dV_e = V_e tr(D_m⁻¹ dD_m), over every tet (model::lumped_masses).
  Eigen::MatrixXd node_dm = Eigen::MatrixXd::Zero(problem.num_nodes(), C);
  for (int e = 0; e < problem.num_tets(); ++e) {
    const material::TetRest& rest = problem.tet_rest[static_cast<std::size_t>(e)];
    for (int j = 0; j < C; ++j) {
      const double dV = rest.volume * (rest.dm_inv * rest_shape_derivative(e, j)).trace();
      for (int k = 0; k < 4; ++k) node_dm(problem.tets(e, k), j) += problem.density * dV / 4.0;
    }
  }
  mass_derivative_.resize(inertia.num_active(), C);
  for (int a = 0; a < inertia.num_active(); ++a)
    mass_derivative_.row(a) = node_dm.row(nodes[static_cast<std::size_t>(a)]);

  // Per cubature point: dV/V, dc_s = Σ_a B_as dg_a, dn (add_points).
  volume_rate_.resize(0, C);
  dn_.resize(0, C);
  dc_.resize(0, C);
  point_offset_.assign(1, 0);
  add_points();
}

Eigen::Matrix3d RestGeometryDerivative::rest_shape_derivative(int e, int j) const {
  const meshing::RowMatrixX3d& d = directions_[static_cast<std::size_t>(j)];
  Eigen::Matrix3d dDm;
  for (int k = 0; k < 3; ++k) dDm.col(k) = (d.row(problem_.tets(e, k + 1)) - d.row(problem_.tets(e, 0))).transpose();
  return dDm;
}

void RestGeometryDerivative::add_points() {
  const int C = columns_;
  const int first = static_cast<int>(point_offset_.size()) - 1, P = elastic_.num_points();
  if (first >= P) return;
  for (int p = first; p < P; ++p)
    point_offset_.push_back(point_offset_.back() + static_cast<int>(elastic_.point_functions(p).size()));
  const auto grow = [C](RowMatrix& m, Eigen::Index rows) {
    const Eigen::Index old = m.rows();
    m.conservativeResize(rows, C);
    m.bottomRows(rows - old).setZero();
  };
  grow(volume_rate_, P);
  grow(dn_, 3 * static_cast<Eigen::Index>(P));
  grow(dc_, 3 * static_cast<Eigen::Index>(point_offset_.back()));
  for (int p = first; p < P; ++p) {
    const int e = elastic_.point_tet(p);
    const material::TetRest& rest = problem_.tet_rest[static_cast<std::size_t>(e)];
    const std::span<const int> functions = elastic_.point_functions(p);
    const Eigen::Vector3d axis = problem_.tet_material[static_cast<std::size_t>(e)].normal;
    Eigen::Vector3d dd;
    for (int k = 0; k < 3; ++k) dd(k) = depth_(problem_.tets(e, k + 1)) - depth_(problem_.tets(e, 0));
    const Eigen::Vector3d gradient = rest.dm_inv.transpose() * dd;  // ∇δ (through_thickness.hpp)
    const double length = gradient.norm();
    const bool own_axis = length > 0.0 && (-gradient / length - axis).norm() < 1e-6;
    for (int j = 0; j < C; ++j) {
      const Eigen::Matrix3d M = rest.dm_inv * rest_shape_derivative(e, j);  // D_m⁻¹ dD_m
      volume_rate_(p, j) = M.trace();
      const Eigen::Matrix3d dDm_inv = -M * rest.dm_inv;
      Eigen::Matrix<double, 4, 3> dg;
      dg.bottomRows<3>() = dDm_inv;
      dg.row(0) = -dDm_inv.colwise().sum();
      const Eigen::Index first_row = 3 * static_cast<Eigen::Index>(point_offset_[static_cast<std::size_t>(p)]);
      for (int a = 0; a < 4; ++a)
        for (SparseRowMatrix::InnerIterator it(subspace_.basis, problem_.tets(e, a)); it; ++it) {
          const auto slot = std::lower_bound(functions.begin(), functions.end(), static_cast<int>(it.col()));
          dc_.block<3, 1>(first_row + 3 * (slot - functions.begin()), j) += it.value() * dg.row(a).transpose();
        }
      if (own_axis) {  // n = −∇δ/|∇δ|: dn = −(I − nnᵀ) d∇δ/|∇δ|, d∇δ = dD_m⁻ᵀ dd
        const Eigen::Vector3d dgradient = dDm_inv.transpose() * dd;
        dn_.block<3, 1>(3 * static_cast<Eigen::Index>(p), j) = -(dgradient - axis * axis.dot(dgradient)) / length;
      }
    }
  }
}

RestGeometryDerivative::RowMatrix RestGeometryDerivative::posed_directions() const {
  const model::NodeFrame& frame = inertia_.frame();
  RowMatrix out(node_directions_.rows(), columns_);
  for (std::size_t a = 0; a < frame.A.size(); ++a)
    out.middleRows<3>(3 * static_cast<Eigen::Index>(a)).noalias() =
        frame.A[a] * node_directions_.middleRows<3>(3 * static_cast<Eigen::Index>(a));
  return out;
}

void RestGeometryDerivative::initialize(double t0, const Eigen::VectorXd& p0, const Eigen::VectorXd& w0) {
  require(p0.size() == node_directions_.rows() && w0.size() == p0.size(),
          "rest-geometry derivative: a history of {} and {} entries for {} inertia nodes", p0.size(), w0.size(),
          node_directions_.rows() / 3);
  p_ = p0;
  w_ = w0;
  // p₀ = A(t₀)X + d(t₀) and w₀ = Ȧ(t₀)X + ḋ(t₀) at the inertia nodes (model::kinematic_velocity, fixed attachments).
  model::NodeFrame frame, rate;
  problem_.frame(t0, frame, &rate);
  const std::vector<int>& nodes = inertia_.inertia_nodes();
  dp_.resize(node_directions_.rows(), columns_);
  dw_.resize(node_directions_.rows(), columns_);
  for (std::size_t a = 0; a < nodes.size(); ++a) {
    const auto i = static_cast<std::size_t>(nodes[a]);
    const Eigen::Index row = 3 * static_cast<Eigen::Index>(a);
    dp_.middleRows<3>(row).noalias() = frame.A[i] * node_directions_.middleRows<3>(row);
    dw_.middleRows<3>(row).noalias() = rate.A[i] * node_directions_.middleRows<3>(row);
  }
}

Eigen::MatrixXd RestGeometryDerivative::gradient_derivative(const Eigen::VectorXd& q, double dt) const {
  require(dt > 0.0 && p_.size() == node_directions_.rows(),
          "rest-geometry derivative: not initialized, or a substep of {} s", dt);
  const int C = columns_;
  RowMatrix inertial = RowMatrix::Zero(q.size(), C);  // row-major: one function's 3 × C block per scatter

  // Inertia and gravity: Σ_i b_i ⊗ A_iᵀ [m_i (dz_i − dp̃_i) + dm_i (p_i − p̃_i)]/h² − Σ_i b_i ⊗ dm_i A_iᵀ g.
  Eigen::VectorXd p;
  inertia_.posed(q, p);
  const Eigen::VectorXd p_tilde = p_ + dt * w_;  // backward Euler
  const RowMatrix dz = posed_directions();
  const double inv_h2 = 1.0 / (dt * dt);
  const model::NodeFrame& frame = inertia_.frame();
  const std::vector<double>& mass = inertia_.lumped_mass();
  const std::vector<int>& active = inertia_.active_nodes();
  Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor> y(3, C), r(3, C);
  for (std::size_t a = 0; a < active.size(); ++a) {
    const Eigen::Index row = 3 * static_cast<Eigen::Index>(a);
    const auto dm = mass_derivative_.row(static_cast<Eigen::Index>(a));
    y.noalias() = -problem_.gravity * dm;
    if (inertia_on_) {
      y.noalias() +=
          (inv_h2 * mass[a]) * (dz.middleRows<3>(row) - dp_.middleRows<3>(row) - dt * dw_.middleRows<3>(row));
      y.noalias() += (inv_h2 * (p.segment<3>(row) - p_tilde.segment<3>(row))) * dm;
    }
    r.noalias() = frame.A[a].transpose() * y;
    for (SparseRowMatrix::InnerIterator it(subspace_.basis, active[a]); it; ++it)
      inertial.middleRows<3>(3 * it.col()).noalias() += it.value() * r;
  }
  // Elasticity: Σ_c [dω P c_s + ω (∂P/∂F : dF + ∂P/∂n dn) c_s + ω P dc_s], dF = Σ_s t_s dc_sᵀ, for every
  // column at once: rows of 9 (vec(dF), vec(dP), vec of the stress, column-major entry a + 3b) × C columns.
  RowMatrix& out = inertial;
  Eigen::Matrix<double, 9, Eigen::Dynamic, Eigen::RowMajor> dF(9, C), stress(9, C);
  Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor> block(3, C);
  for (int pt = 0; pt < elastic_.num_points(); ++pt) {
    const double w = elastic_.point_weight(pt);
    if (w == 0.0) continue;
    const material::OrthotropicFung& m = problem_.tet_material[static_cast<std::size_t>(elastic_.point_tet(pt))];
    const Eigen::Matrix3d F = elastic_.point_deformation_gradient(pt, q);
    const material::OrthoFungValues values = material::eval_ortho_fung(F, m, true);
    const Eigen::Matrix<double, 9, 3> axis = stress_axis_derivative(F, m);
    const std::span<const int> functions = elastic_.point_functions(pt);
    const std::span<const Eigen::Vector3d> c = elastic_.point_vectors(pt);
    const int count = static_cast<int>(functions.size());
    const Eigen::Index first = 3 * static_cast<Eigen::Index>(point_offset_[static_cast<std::size_t>(pt)]);
    dF.setZero();  // dF(a, b) = Σ_s t_s(a) dc_s(b): rows 3b..3b+2 hold column b
    for (int s = 0; s < count; ++s) {
      const Eigen::Vector3d t = q.segment<3>(3 * functions[static_cast<std::size_t>(s)]);
      for (int b = 0; b < 3; ++b) dF.middleRows<3>(3 * b).noalias() += t * dc_.row(first + 3 * s + b);
    }
    stress.noalias() = values.dPdF * dF;
    stress.noalias() += axis * dn_.middleRows<3>(3 * static_cast<Eigen::Index>(pt));
    stress.noalias() += Eigen::Map<const Vector9d>(values.P.data()) * volume_rate_.row(pt);
    stress *= w;
    const Eigen::Matrix3d P = w * values.P;
    for (int s = 0; s < count; ++s) {
      const Eigen::Vector3d& cs = c[static_cast<std::size_t>(s)];
      block.noalias() =
          cs(0) * stress.middleRows<3>(0) + cs(1) * stress.middleRows<3>(3) + cs(2) * stress.middleRows<3>(6);
      block.noalias() += P * dc_.middleRows<3>(first + 3 * s);
      out.middleRows<3>(3 * functions[static_cast<std::size_t>(s)]) += block;
    }
  }
  return out;
}

void RestGeometryDerivative::advance(const Eigen::VectorXd& q, double dt) {
  Eigen::VectorXd p;
  inertia_.posed(q, p);
  w_ = (p - p_) / dt;  // model::advance_history, backward Euler
  p_ = std::move(p);
  RowMatrix dp = posed_directions();
  dw_ = (dp - dp_) / dt;
  dp_ = std::move(dp);
}

}  // namespace sflsh::reduced
