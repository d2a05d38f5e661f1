#pragma once
// The elastic energy of the reduced model by cubature, with its gradient and Hessian in q (cubature.hpp).
// Per cubature tet c with nodes a and rest shape-function gradients g_a (rows of the 4 × 3 matrix G):
//   F_c(q) = F_D,c + Σ_{s ∈ S_c} t_s c_sᵀ,   c_s = Σ_a B_{a s} g_a     (c_s: row s of C_c = W_cᵀ G),
// where S_c are the basis functions touching the tet's nodes and F_D,c the deformation gradient of the
// prescribed state x_D. Hence
//   ∂E/∂t_s = ω V P c_s,     ∂²E/∂t_s∂t_r (i, k) = ω V Σ_{j,l} (∂P/∂F)_{(i j),(k l)} c_s(j) c_r(l),
// with (i j) the column-major vec index i + 3j (orthotropic_fung.hpp). No allocation per point.
#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/cubature.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <span>
#include <vector>

namespace sflsh::reduced {

class CubatureElastic {
 public:
  CubatureElastic(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature);

  /// F_D per point from the prescribed state x_D (3N). Call before the first evaluation and whenever x_D changes.
  void set_prescribed_state(const Eigen::VectorXd& x_prescribed);
  /// E(q) [J]. Throws sflsh::Error on a non-finite F or a Fung exponent over the cap.
  double energy(const Eigen::VectorXd& q) const;
  /// E(q); adds ∂E/∂q to `gradient` (3S).
  double add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const;
  /// Adds ∂²E/∂q² (3S × 3S, full symmetric) to `hessian`, with dP/dF projected to PSD when asked.
  void add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian, material::HessianProjection projection) const;
  /// One point's contribution weight · ω V ∂Ψ/∂q, added to `gradient` (for cubature fitting).
  void add_point_gradient(int point, const Eigen::VectorXd& q, Eigen::VectorXd& gradient, double weight) const;

  /// Appends tet e as a point of weight ω (multiplying V_e Ψ_e); returns its point index.
  int add_point(int tet, double weight);
  /// Sets a point's ω.
  void set_point_weight(int point, double weight);
  /// A point's ω (its weight ω V divided by V · energy scale).
  double point_weight_factor(int point) const;
  /// The basis functions s touching a point and their vectors c_s (F = F_D + Σ_s t_s c_sᵀ), parallel spans.
  std::span<const int> point_functions(int point) const {
    const auto p = static_cast<std::size_t>(point);
    return {function_.data() + offset_[p], static_cast<std::size_t>(offset_[p + 1] - offset_[p])};
  }
  std::span<const Eigen::Vector3d> point_vectors(int point) const {
    const auto p = static_cast<std::size_t>(point);
    return {c_.data() + offset_[p], static_cast<std::size_t>(offset_[p + 1] - offset_[p])};
  }

  int num_points() const { return static_cast<int>(point_tet_.size()); }
  /// F_c(q) of one point.
  Eigen::Matrix3d point_deformation_gradient(int point, const Eigen::VectorXd& q) const {
    return deformation_gradient(point, q);
  }
  /// The mesh tet of one point and its weight ω V (· energy scale).
  int point_tet(int point) const { return point_tet_[static_cast<std::size_t>(point)]; }
  double point_weight(int point) const { return point_weight_[static_cast<std::size_t>(point)]; }
  /// Adds scale · ω V · stress · c_s to the slots t_s of `gradient` (3S) for the point's functions: the reduced
  /// gradient of a stress-like 3×3 field at that point (∂E/∂t_s = ω V P c_s with stress = P).
  void add_point_stress(int point, const Eigen::Matrix3d& stress, double scale,
                        Eigen::Ref<Eigen::VectorXd> gradient) const;
  /// Largest number of basis functions touching one point (the size of its local Hessian / 3).
  int max_local_functions() const { return max_local_; }

 private:
  Eigen::Matrix3d deformation_gradient(int point, const Eigen::VectorXd& q) const;

  const model::Problem& problem_;
  const Subspace& subspace_;
  Eigen::VectorXd x_prescribed_;  ///< the prescribed state x_D (3N) of f_prescribed_
  std::vector<int> point_tet_;
  std::vector<double> tet_scale_;     ///< V_c (· energy scale) per point
  std::vector<double> point_weight_;  ///< ω_c V_c (· energy scale)
  std::vector<int> offset_;           ///< point p's functions are function_[offset_[p] .. offset_[p+1])
  std::vector<int> function_;
  std::vector<Eigen::Vector3d> c_;  ///< c_s per (point, function), parallel to function_
  std::vector<Eigen::Matrix3d> f_prescribed_;
  int max_local_ = 0;
};

}  // namespace sflsh::reduced
