#pragma once
// The energies of a free rigid object's implicit step, each a term with value [J], gradient and Hessian
// with respect to the increment z = (Δx, θ) of its placement (x + Δx, exp([θ]×) R) at z = 0. Newton
// re-bases the placement after every step, so derivatives at z = 0 are all it needs. The Hessians are
// exact (the finite-difference tests check them); the solver projects their sum to PSD.
// The step minimizes the incremental potential Φ = Σ terms (docs/contact.md, "Free rigid objects").
#include <sflsh/scene/obstacle.hpp>
#include <sflsh/scene/rigid_body.hpp>

#include <vector>

namespace sflsh::scene {

class RigidTerm {
 public:
  virtual ~RigidTerm() = default;
  /// The value [J] at `at`; ∇ [J, J/rad] and ∇² with respect to z at z = 0 when not null (added to, not set).
  virtual double evaluate(const RigidPlacement& at, Vector6d* gradient, Matrix6d* hessian) const = 0;
};

/// Inertia and gravity of one implicit Euler step of size h from `start`:
///   Φ_I = m/(2h²) |x − x̃|² − m g·x + 1/(2h²) tr((R − R̃) J (R − R̃)ᵀ),
///   x̃ = x_n + h v_n,  R̃ = exp(h [ω_n]×) R_n,
/// whose minimum without other terms is x_{n+1} = x̃ + h² g and R_{n+1} = R̃: a free object keeps v and ω
/// (world) and so its kinetic energy exactly (ωᵀ R I Rᵀ ω is constant when R turns about ω). The rotational
/// part is ½ tr(ΔR J ΔRᵀ)/h², the matrix form of ½ ωᵀ I ω (ΔR = R − R̃ ≈ h [δω]× R). Gyroscopic
/// precession of a spin about a non-principal axis is not modelled (ω stays fixed in the world).
class RigidInertiaTerm final : public RigidTerm {
 public:
  RigidInertiaTerm(const RigidProperties& properties, const RigidState& start, double h,
                   const Eigen::Vector3d& gravity);
  double evaluate(const RigidPlacement& at, Vector6d* gradient, Matrix6d* hessian) const override;

 private:
  RigidProperties properties_;
  double h_;
  Eigen::Vector3d gravity_;
  Eigen::Vector3d x_tilde_;
  Eigen::Matrix3d R_tilde_;
};

/// One point of the object that touches obstacles: `point` in the object's frame [m], `radius` [m] (the
/// sample stands for a ball, e.g. a sphere's centre with its radius), stiffness [N/m].
struct RigidSample {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  double radius = 0.0;
  double stiffness = 0.0;
};

/// The object's samples against obstacles posed in the world (the ground, fixed or prescribed objects):
///   u = Σ_s Σ_j ½ k_s (δ − φ_js)²  where φ_js = φ_j(R q_s + x) − ρ_s < δ.
class RigidObstacleContactTerm final : public RigidTerm {
 public:
  RigidObstacleContactTerm(std::vector<RigidSample> samples, std::vector<const Obstacle*> obstacles, double margin);
  double evaluate(const RigidPlacement& at, Vector6d* gradient, Matrix6d* hessian) const override;
  /// φ_js at the placement [m] (sample s, obstacle j).
  double gap(const RigidPlacement& at, std::size_t s, std::size_t j, Eigen::Vector3d* normal = nullptr) const;
  const std::vector<RigidSample>& samples() const { return samples_; }
  std::vector<RigidSample>& samples() { return samples_; }
  const std::vector<const Obstacle*>& obstacles() const { return obstacles_; }

 private:
  std::vector<RigidSample> samples_;
  std::vector<const Obstacle*> obstacles_;
  double margin_;
};

/// Surface points of another body fixed in the world during the solve (a body's skin nodes at the step's
/// end) against the object's own shape, evaluated in the object's coordinates:
///   u = Σ_i ½ k_i (δ − φ(Rᵀ(p_i − x)))²  where φ < δ,
/// the same penalty the body's ContactPotential puts on those nodes, so the two sides see one energy.
class ObjectSurfaceContactTerm final : public RigidTerm {
 public:
  /// shape: the object's shape (its own pose is ignored: the placement is the pose); points [m] world,
  /// stiffness [N/m] per point.
  ObjectSurfaceContactTerm(const Obstacle& shape, std::vector<Eigen::Vector3d> points, std::vector<double> stiffness,
                           double margin);
  double evaluate(const RigidPlacement& at, Vector6d* gradient, Matrix6d* hessian) const override;
  /// φ of point i in the object at the placement [m], with the outward normal (world) when asked.
  double gap(const RigidPlacement& at, std::size_t i, Eigen::Vector3d* normal = nullptr) const;
  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  double stiffness(std::size_t i) const { return stiffness_[i]; }
  void scale_stiffness(std::size_t i, double factor) { stiffness_[i] *= factor; }

 private:
  const Obstacle& shape_;
  std::vector<Eigen::Vector3d> points_;
  std::vector<double> stiffness_;
  double margin_;
};

/// One friction contact, all lagged from the previous solve: the object's material point `point` (its
/// frame) [m], the other side's displacement over the step [m] (world), the contact normal (world, unit) and
/// the normal force λ [N].
struct FrictionContact {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d other_displacement = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
  double normal_force = 0.0;
  int source = -1;  ///< the caller's index of the other side's point (−1: an obstacle)
};

/// The smoothed Coulomb friction of one contact (below) as a function of its displacement u over the step [m]:
/// w = P u (the slip, P = Id − n nᵀ); returns μλ f0'(|w|)/|w| (∇_u D = that · w), with μλ f0(|w|) and ∇²_u D when
/// not null. scale = μ λ [N], ε [m].
double smoothed_slip(double scale, double epsilon, const Eigen::Vector3d& normal, const Eigen::Vector3d& u,
                     Eigen::Vector3d& w, double* value, Eigen::Matrix3d* hessian);

/// Smoothed Coulomb friction with lagged normal force and tangent plane (IPC, Li et al. 2020):
///   D = Σ_c μ λ_c f0(|P_c u_c|),  u_c = (R q_c + x) − (R_n q_c + x_n) − Δp_c,  P_c = Id − n_c n_cᵀ,
///   f0(y) = −y³/(3ε²) + y²/ε + ε/3 for y < ε, y otherwise,
/// with ε = ε_v h [m]: sliding slower than ε_v is treated as sticking (a stiff spring, D is C²).
class RigidFrictionTerm final : public RigidTerm {
 public:
  RigidFrictionTerm(std::vector<FrictionContact> contacts, const RigidPlacement& start, double coefficient,
                    double smoothing_length);
  double evaluate(const RigidPlacement& at, Vector6d* gradient, Matrix6d* hessian) const override;
  /// Per contact, the friction force on the object at `at` [N] (world): −μ λ f0'(y) w/y, the other side feels
  /// its opposite.
  std::vector<Eigen::Vector3d> forces(const RigidPlacement& at) const;
  const std::vector<FrictionContact>& contacts() const { return contacts_; }

 private:
  /// μ λ f0'(|w|)/|w| and w = P u of contact c at `at` (slip over the step [m]).
  double slip(const FrictionContact& c, const RigidPlacement& at, Eigen::Vector3d& w, double* f0,
              Eigen::Matrix3d* Hp) const;
  std::vector<FrictionContact> contacts_;
  RigidPlacement start_;
  double coefficient_;
  double epsilon_;
};

/// The sum of the terms' values; gradients and Hessians summed when not null.
double evaluate_terms(const std::vector<const RigidTerm*>& terms, const RigidPlacement& at, Vector6d* gradient,
                      Matrix6d* hessian);

}  // namespace sflsh::scene
