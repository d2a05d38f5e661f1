#include <sflsh/core/error.hpp>
#include <sflsh/reduced/weights.hpp>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <array>
#include <map>

namespace sflsh::reduced {

namespace {

/// Gradients of the four linear shape functions of a tet (rows) and its volume.
void shape_gradients(const RowMatrixX3d& nodes, const RowMatrixX4i& tets, int e, Eigen::Matrix<double, 4, 3>& grad,
                     double& volume) {
  Eigen::Matrix3d dm;
  for (int a = 0; a < 3; ++a) dm.col(a) = (nodes.row(tets(e, a + 1)) - nodes.row(tets(e, 0))).transpose();
  const double det = dm.determinant();
  require(det > 0.0, "weights: tet {} is inverted or degenerate (det {:.3e})", e, det);
  volume = det / 6.0;
  const Eigen::Matrix3d inv = dm.inverse();  // rows: ∇φ_1..3
  grad.bottomRows<3>() = inv;
  grad.row(0) = -inv.colwise().sum();
}

/// Boundary faces (each with the tet it belongs to and the local index of the opposite node).
struct BoundaryFace {
  int tet;
  int opposite;  ///< local node 0..3 not on the face
};

std::vector<BoundaryFace> boundary_faces(const RowMatrixX4i& tets) {
  std::map<std::array<int, 3>, std::pair<int, int>> count;  // sorted face → (tet, opposite) or tet = −1 when shared
  for (int e = 0; e < tets.rows(); ++e) {
    for (int o = 0; o < 4; ++o) {
      std::array<int, 3> f{};
      int k = 0;
      for (int a = 0; a < 4; ++a)
        if (a != o) f[static_cast<std::size_t>(k++)] = tets(e, a);
      std::sort(f.begin(), f.end());
      auto [it, inserted] = count.try_emplace(f, e, o);
      if (!inserted) it->second.first = -1;
    }
  }
  std::vector<BoundaryFace> out;
  for (const auto& [face, value] : count)
    if (value.first >= 0) out.push_back({value.first, value.second});
  return out;
}

Eigen::VectorXd lumped_volume(const RowMatrixX3d& nodes, const RowMatrixX4i& tets) {
  Eigen::VectorXd m = Eigen::VectorXd::Zero(nodes.rows());
  Eigen::Matrix<double, 4, 3> grad;
  double volume = 0.0;
  for (int e = 0; e < tets.rows(); ++e) {
    shape_gradients(nodes, tets, e, grad, volume);
    for (int a = 0; a < 4; ++a) m[tets(e, a)] += volume / 4.0;
  }
  return m;
}

/// Solver for the constrained minimization with a fixed constrained set: factor Q_ff once.
class ConstrainedSolve {
 public:
  ConstrainedSolve(const RowMatrixX3d& nodes, const RowMatrixX4i& tets, const std::vector<int>& constrained) {
    const int n = static_cast<int>(nodes.rows());
    local_.assign(static_cast<std::size_t>(n), -1);
    is_constrained_.assign(static_cast<std::size_t>(n), 0);
    for (int v : constrained) {
      require(v >= 0 && v < n, "weights: constrained node {} out of range [0, {})", v, n);
      require(!is_constrained_[static_cast<std::size_t>(v)], "weights: node {} belongs to two handles", v);
      is_constrained_[static_cast<std::size_t>(v)] = 1;
    }
    for (int v = 0; v < n; ++v)
      if (!is_constrained_[static_cast<std::size_t>(v)]) {
        local_[static_cast<std::size_t>(v)] = static_cast<int>(free_.size());
        free_.push_back(v);
      }
    q_ = linearly_precise_biharmonic(nodes, tets);
    std::vector<Eigen::Triplet<double>> ff;
    for (int k = 0; k < q_.outerSize(); ++k)
      for (SparseMatrixd::InnerIterator it(q_, k); it; ++it) {
        const int r = local_[static_cast<std::size_t>(it.row())], c = local_[static_cast<std::size_t>(it.col())];
        if (r >= 0 && c >= 0) ff.emplace_back(r, c, it.value());
      }
    SparseMatrixd qff(static_cast<Eigen::Index>(free_.size()), static_cast<Eigen::Index>(free_.size()));
    qff.setFromTriplets(ff.begin(), ff.end());
    if (!free_.empty()) {
      ldlt_.compute(qff);
      require(ldlt_.info() == Eigen::Success,
              "weights: the biharmonic system could not be factorized (a part of the mesh touches no handle?)");
    }
  }

  /// Full solution for prescribed values `value` (per node; read only on constrained nodes).
  Eigen::VectorXd solve(const Eigen::VectorXd& value) const {
    Eigen::VectorXd out = value;
    if (free_.empty()) return out;
    // rhs_f = −Q_fc w_c
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(free_.size()));
    for (int k = 0; k < q_.outerSize(); ++k) {
      if (!is_constrained_[static_cast<std::size_t>(k)] || value[k] == 0.0) continue;
      for (SparseMatrixd::InnerIterator it(q_, k); it; ++it) {
        const int r = local_[static_cast<std::size_t>(it.row())];
        if (r >= 0) rhs[r] -= it.value() * value[k];
      }
    }
    const Eigen::VectorXd wf = ldlt_.solve(rhs);
    require(ldlt_.info() == Eigen::Success && wf.allFinite(), "weights: the biharmonic solve failed");
    for (std::size_t f = 0; f < free_.size(); ++f) out[free_[f]] = wf[static_cast<Eigen::Index>(f)];
    return out;
  }

 private:
  SparseMatrixd q_;
  std::vector<int> local_, free_;
  std::vector<char> is_constrained_;
  Eigen::SimplicialLDLT<SparseMatrixd> ldlt_;
};

}  // namespace

SparseMatrixd linearly_precise_laplacian(const RowMatrixX3d& nodes, const RowMatrixX4i& tets) {
  const Eigen::Index n = nodes.rows();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(tets.rows()) * 16 * 2);
  Eigen::Matrix<double, 4, 3> grad;
  double volume = 0.0;
  for (int e = 0; e < tets.rows(); ++e) {
    shape_gradients(nodes, tets, e, grad, volume);
    const Eigen::Matrix4d local = volume * grad * grad.transpose();  // L_ab = V ∇φ_a·∇φ_b
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) entries.emplace_back(tets(e, a), tets(e, b), local(a, b));
  }
  // −N: on each boundary face f of tet e, ∫_f φ_a dA = A_f/3 for its three nodes a, and ∇φ_b·n_f is constant.
  for (const BoundaryFace& face : boundary_faces(tets)) {
    shape_gradients(nodes, tets, face.tet, grad, volume);
    std::array<int, 3> f{};
    int k = 0;
    for (int a = 0; a < 4; ++a)
      if (a != face.opposite) f[static_cast<std::size_t>(k++)] = a;
    const Eigen::Vector3d p0 = nodes.row(tets(face.tet, f[0])), p1 = nodes.row(tets(face.tet, f[1])),
                          p2 = nodes.row(tets(face.tet, f[2]));
    Eigen::Vector3d area_normal = 0.5 * (p1 - p0).cross(p2 - p0);  // |·| = A_f
    const Eigen::Vector3d opposite = nodes.row(tets(face.tet, face.opposite));
    if (area_normal.dot(p0 - opposite) < 0.0) area_normal = -area_normal;  // outward
    for (int b = 0; b < 4; ++b) {
      const double flux = grad.row(b).dot(area_normal) / 3.0;  // (A_f/3) ∇φ_b·n
      for (int a : f) entries.emplace_back(tets(face.tet, a), tets(face.tet, b), -flux);
    }
  }
  SparseMatrixd K(n, n);
  K.setFromTriplets(entries.begin(), entries.end());
  return K;
}

SparseMatrixd linearly_precise_biharmonic(const RowMatrixX3d& nodes, const RowMatrixX4i& tets) {
  const SparseMatrixd K = linearly_precise_laplacian(nodes, tets);
  const Eigen::VectorXd m = lumped_volume(nodes, tets);
  const SparseMatrixd minv_k = m.cwiseInverse().asDiagonal() * K;
  SparseMatrixd Q = SparseMatrixd(K.transpose()) * minv_k;
  // Symmetrize against round-off so the LDLᵀ sees an exactly symmetric matrix.
  SparseMatrixd Qt = Q.transpose();
  return 0.5 * (Q + Qt);
}

Eigen::MatrixXd handle_weights(const RowMatrixX3d& nodes, const RowMatrixX4i& tets, const HandleSets& handles,
                               int columns) {
  require(!handles.handle_nodes.empty(), "weights: no handles");
  std::vector<int> constrained;
  for (std::size_t k = 0; k < handles.handle_nodes.size(); ++k) {
    require(!handles.handle_nodes[k].empty(), "weights: handle {} has no nodes", k);
    constrained.insert(constrained.end(), handles.handle_nodes[k].begin(), handles.handle_nodes[k].end());
  }
  const int count = columns < 0 ? static_cast<int>(handles.handle_nodes.size()) : columns;
  require(count <= static_cast<int>(handles.handle_nodes.size()), "weights: {} columns requested of {} handles", count,
          handles.handle_nodes.size());
  const ConstrainedSolve solver(nodes, tets, constrained);
  Eigen::MatrixXd W(nodes.rows(), count);
  for (std::size_t k = 0; k < static_cast<std::size_t>(count); ++k) {
    Eigen::VectorXd value = Eigen::VectorXd::Zero(nodes.rows());
    for (int v : handles.handle_nodes[k]) value[v] = 1.0;
    W.col(static_cast<Eigen::Index>(k)) = solver.solve(value);
  }
  return W;
}

Eigen::VectorXd biharmonic_interpolate(const RowMatrixX3d& nodes, const RowMatrixX4i& tets,
                                       const std::vector<int>& constrained, const Eigen::VectorXd& values) {
  require(values.size() == static_cast<Eigen::Index>(constrained.size()), "weights: {} values for {} constrained nodes",
          values.size(), constrained.size());
  const ConstrainedSolve solver(nodes, tets, constrained);
  Eigen::VectorXd full = Eigen::VectorXd::Zero(nodes.rows());
  for (std::size_t k = 0; k < constrained.size(); ++k) full[constrained[k]] = values[static_cast<Eigen::Index>(k)];
  return solver.solve(full);
}

Subspace point_handle_subspace(const Eigen::MatrixXd& weights, const std::vector<char>& attached,
                               const RowMatrixX3d& nodes, const std::vector<int>& handle_nodes,
                               const BasisOptions& options) {
  const Eigen::Index n = weights.rows(), p = weights.cols();
  require(static_cast<Eigen::Index>(attached.size()) == n && nodes.rows() == n,
          "subspace: {} weight rows, {} attachment flags, {} nodes", n, attached.size(), nodes.rows());
  require(static_cast<Eigen::Index>(handle_nodes.size()) == p, "subspace: {} handle nodes for {} weight columns",
          handle_nodes.size(), p);
  require(options.max_influences >= 1, "subspace: max_influences must be at least 1");
  require(options.affine_length > 0.0, "subspace: affine_length must be positive");
  const int per_handle = options.affine ? 4 : 1;
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<std::pair<double, int>> row;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (attached[static_cast<std::size_t>(i)]) continue;
    row.clear();
    for (Eigen::Index j = 0; j < p; ++j)
      if (std::abs(weights(i, j)) >= options.drop_below)
        row.emplace_back(-std::abs(weights(i, j)), static_cast<int>(j));
    std::sort(row.begin(), row.end());
    if (static_cast<int>(row.size()) > options.max_influences)
      row.resize(static_cast<std::size_t>(options.max_influences));
    for (const auto& [negative, j] : row) {
      const double w = weights(i, j);
      entries.emplace_back(static_cast<int>(i), per_handle * j, w);
      if (options.affine) {
        const Eigen::RowVector3d r =
            (nodes.row(i) - nodes.row(handle_nodes[static_cast<std::size_t>(j)])) / options.affine_length;
        for (int c = 0; c < 3; ++c) entries.emplace_back(static_cast<int>(i), per_handle * j + 1 + c, w * r[c]);
      }
    }
  }
  Subspace s;
  s.basis.resize(n, per_handle * p);
  s.basis.setFromTriplets(entries.begin(), entries.end());
  s.basis.makeCompressed();
  return s;
}

}  // namespace sflsh::reduced
