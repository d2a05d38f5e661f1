#include "body_field.hpp"

#include <sflsh/core/error.hpp>

#include <cmath>

namespace sflsh::body::detail {

BodyField::BodyField(std::vector<PlacedPrimitive> primitives) : primitives_(std::move(primitives)) {
  require(!primitives_.empty(), "open body: a body field needs at least one primitive");
  for (const PlacedPrimitive& prim : primitives_) {
    const Eigen::Vector3d& c = prim.shape.bound_center();
    reach_.emplace_back(c.x(), c.y(), c.z(), prim.shape.bound_radius() + 2.0 * prim.blend + 0.02);
  }
  for (std::size_t i = 0; i < primitives_.size(); ++i)
    require(!primitives_[i].left_of_pair || (i > 0 && i + 1 < primitives_.size()),
            "open body: primitive {} is marked as a left/right pair without a partner", i);
}

// smin(f, d, k) equals f exactly when d ≥ f + k, and a pair step is exact when both are beyond f + 2k.
// The bounding sphere gives a cheap lower bound of d: |p − c| − R > f + 2k ⇔ |p − c|² > (f + 2k + R)²
// (with 2 cm of margin for the approximate distances).
bool BodyField::beyond_reach(std::size_t i, const Eigen::Vector3d& p, double current) const {
  const Eigen::Vector4d& r = reach_[i];
  const double reach = current + r.w();
  const double dx = p.x() - r.x(), dy = p.y() - r.y(), dz = p.z() - r.z();
  return reach > 0.0 && dx * dx + dy * dy + dz * dz > reach * reach;
}

namespace {

/// The indices 0, 1, …, n − 1.
struct AllIndices {
  std::size_t n;
  std::size_t size() const { return n; }
  int operator[](std::size_t k) const { return static_cast<int>(k); }
};

}  // namespace

template <class Indices>
FieldSample BodyField::evaluate_over(const Eigen::Vector3d& p, const Indices& idx) const {
  FieldSample acc = primitives_.front().shape.evaluate(p);
  double w = 0.0;
  const std::size_t m = idx.size();
  for (std::size_t k = 1; k < m; ++k) {
    const auto i = static_cast<std::size_t>(idx[k]);
    const PlacedPrimitive& prim = primitives_[i];
    FieldSample d;
    if (prim.left_of_pair && k + 1 < m && static_cast<std::size_t>(idx[k + 1]) == i + 1) {
      ++k;
      const bool use_left = !beyond_reach(i, p, acc.value), use_right = !beyond_reach(i + 1, p, acc.value);
      if (!use_left && !use_right) continue;
      if (use_left && use_right) {
        const FieldSample l = prim.shape.evaluate(p), r = primitives_[i + 1].shape.evaluate(p);
        d.value = smooth_min(l.value, r.value, prim.blend, w);
        d.gradient = (1.0 - w) * l.gradient + w * r.gradient;
      } else {
        d = primitives_[use_left ? i : i + 1].shape.evaluate(p);
      }
    } else {
      if (beyond_reach(i, p, acc.value)) continue;
      d = prim.shape.evaluate(p);
    }
    acc.value = smooth_min(acc.value, d.value, prim.blend, w);
    acc.gradient = (1.0 - w) * acc.gradient + w * d.gradient;
  }
  return acc;
}

FieldSample BodyField::evaluate(const Eigen::Vector3d& p) const {
  return evaluate_over(p, AllIndices{primitives_.size()});
}

FieldSample BodyField::evaluate(const Eigen::Vector3d& p, std::span<const int> active) const {
  return evaluate_over(p, active);
}

void BodyField::active_near(const Eigen::Vector3d& p, double radius, std::vector<int>& out) const {
  const double f = evaluate(p).value;
  out.push_back(0);
  for (std::size_t i = 1; i < primitives_.size(); ++i) {
    const PlacedPrimitive& prim = primitives_[i];
    if (prim.shape.lower_bound(p) <= f + 2.0 * radius + 2.0 * prim.blend + 0.02) out.push_back(static_cast<int>(i));
  }
}

Eigen::VectorXd BodyField::memberships(const Eigen::Vector3d& p) const {
  const auto n = static_cast<Eigen::Index>(primitives_.size());
  // Per primitive: its weight inside its step (1, or the pair's split), and the step's weight ∂f_s/∂d_s.
  Eigen::VectorXd inner = Eigen::VectorXd::Ones(n), step = Eigen::VectorXd::Ones(n);
  double acc = primitives_.front().shape.evaluate(p).value;
  for (Eigen::Index i = 1; i < n; ++i) {
    const PlacedPrimitive& prim = primitives_[static_cast<std::size_t>(i)];
    double d = prim.shape.evaluate(p).value, w = 0.0;
    if (prim.left_of_pair) {
      d = smooth_min(d, primitives_[static_cast<std::size_t>(i) + 1].shape.evaluate(p).value, prim.blend, w);
      inner(i) = 1.0 - w;
      inner(i + 1) = w;
    }
    acc = smooth_min(acc, d, prim.blend, w);
    step(i) = w;
    if (prim.left_of_pair) step(++i) = w;
  }
  // ∂f/∂d_i = inner_i · w_s Π_{later steps t} (1 − w_t), accumulated from the end of the chain.
  Eigen::VectorXd out(n);
  double carry = 1.0;
  for (Eigen::Index i = n - 1; i >= 1; --i) {
    const bool right_of_pair = i > 0 && primitives_[static_cast<std::size_t>(i) - 1].left_of_pair;
    out(i) = inner(i) * step(i) * carry;
    if (!right_of_pair) carry *= 1.0 - step(i);
  }
  out(0) = carry;
  return out;
}

}  // namespace sflsh::body::detail
