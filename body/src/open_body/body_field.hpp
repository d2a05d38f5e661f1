#pragma once
// The implicit field of one open-body sample: its primitives united by a chain of polynomial smooth
// minima, f = smin(…smin(smin(d_0, d_1, k_1), d_2, k_2)…, d_n, k_n). f < 0 inside, f ≈ distance [m].
#include "implicit_primitives.hpp"
#include "skeleton.hpp"

#include <Eigen/Core>

#include <cmath>
#include <span>
#include <vector>

namespace sflsh::body::detail {

/// Bone tag of the trunk primitives, whose vertices are split between pelvis/spine1/spine2/spine3 by height.
inline constexpr int kTrunkBone = -1;

/// A primitive in the union, with the smooth-min radius it joins with and the bone that moves it.
/// Left/right pairs are consecutive and join as one step, smin(f, smin(d_left, d_right, k), k), so
/// that the field is exactly mirror-symmetric (smin is commutative but not associative).
struct PlacedPrimitive {
  Primitive shape;
  double blend = 0.0;         ///< k of the smooth minimum that adds it to the union [m] (ignored for the first)
  int bone = 0;               ///< SMPL joint whose rotation moves it, or kTrunkBone
  bool left_of_pair = false;  ///< the next primitive is its mirror image
};

class BodyField {
 public:
  BodyField() = default;
  explicit BodyField(std::vector<PlacedPrimitive> primitives);

  /// f(p) and ∇f(p).
  FieldSample evaluate(const Eigen::Vector3d& p) const;
  /// f(p) and ∇f(p) from the primitives listed in `active` only (increasing indices starting with 0):
  /// the same value as evaluate(p) wherever the others cannot reach, see active_near().
  FieldSample evaluate(const Eigen::Vector3d& p, std::span<const int> active) const;
  /// Appends to `out` (increasing) the primitives that can change f anywhere within `radius` of p [m],
  /// assuming f is 1-Lipschitz: those whose lower bound at p is within f(p) + 2·radius + 2k + 2 cm.
  void active_near(const Eigen::Vector3d& p, double radius, std::vector<int>& out) const;
  /// f(p) only.
  double value(const Eigen::Vector3d& p) const { return evaluate(p).value; }
  /// ∂f/∂d_i for every primitive i at p: non-negative and summing to 1 (the primitives' share of the
  /// surface at p; only blend zones have more than one nonzero).
  Eigen::VectorXd memberships(const Eigen::Vector3d& p) const;

  const std::vector<PlacedPrimitive>& primitives() const { return primitives_; }

 private:
  /// True when primitive i cannot change the union whose value so far is `current` (see evaluate()).
  bool beyond_reach(std::size_t i, const Eigen::Vector3d& p, double current) const;
  /// The smooth-min chain over the primitives idx[0] = 0 < idx[1] < … (any indexable range).
  template <class Indices>
  FieldSample evaluate_over(const Eigen::Vector3d& p, const Indices& idx) const;

  std::vector<PlacedPrimitive> primitives_;
  /// Per primitive: bounding-sphere centre and R + 2k + 2 cm, packed for the culling test [m].
  std::vector<Eigen::Vector4d> reach_;
};

/// Newton projection of p onto f = 0 along ∇f, x ← x − f ∇f/|∇f|², each step capped at `max_step` [m].
/// Stops at |f| < `tolerance` [m] or after `max_iterations`; returns the last iterate.
/// `evaluate(x)` returns the FieldSample of the field at x.
template <class Evaluate>
Eigen::Vector3d newton_project(const Evaluate& evaluate, const Eigen::Vector3d& p, double max_step = 0.01,
                               int max_iterations = 40, double tolerance = 1e-7) {
  Eigen::Vector3d x = p;
  for (int it = 0; it < max_iterations; ++it) {
    const FieldSample s = evaluate(x);
    if (std::abs(s.value) < tolerance) break;
    const double g2 = s.gradient.squaredNorm();
    if (g2 < 1e-12) break;
    Eigen::Vector3d step = -s.value / g2 * s.gradient;
    const double len = step.norm();
    if (len > max_step) step *= max_step / len;
    x += step;
  }
  return x;
}

/// newton_project() with the whole field.
inline Eigen::Vector3d project_to_surface(const BodyField& field, const Eigen::Vector3d& p) {
  return newton_project([&field](const Eigen::Vector3d& x) { return field.evaluate(x); }, p);
}

/// The open body's primitives (trunk loft, belly, breasts, buttocks, shoulders, neck, head, arms,
/// hands, legs, feet) placed on `skeleton`.
BodyField make_body_field(const Skeleton& skeleton);

}  // namespace sflsh::body::detail
