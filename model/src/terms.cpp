#include "deterministic_reduce.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/model/terms.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <numeric>

namespace sflsh::model {

namespace {

material::TetNodes tet_nodes(const std::array<int, 4>& tet, const Eigen::VectorXd& x) {
  material::TetNodes nodes;
  for (int a = 0; a < 4; ++a) nodes.col(a) = x.segment<3>(3 * tet[static_cast<std::size_t>(a)]);
  return nodes;
}

double energy_scale(const Problem& problem, int e) {
  return problem.tet_energy_scale.empty() ? 1.0 : problem.tet_energy_scale[static_cast<std::size_t>(e)];
}

Eigen::Vector3d posed_node(const NodeFrame& frame, const Eigen::VectorXd& x, int node) {
  return frame.A[static_cast<std::size_t>(node)] * x.segment<3>(3 * node) + frame.d.row(node).transpose();
}

/// The order in which a term packs its subset's tets (ElasticTerm::PackedTet, InertiaTerm's arrays): the row tets
/// in their order, then the value tets that are not row tets; value_slots[k] is value tet k's place in `tets`.
struct PackOrder {
  std::vector<int> tets;
  std::size_t row_count = 0;
  std::vector<int> value_slots;
};

PackOrder pack_order(const Problem& problem, const TermSubset& subset, const char* term) {
  PackOrder order;
  std::vector<int> slot_of(static_cast<std::size_t>(problem.num_tets()), -1);
  // Every row tet takes its own place (the sink's k); a value tet takes its row tet's place or a new one.
  auto add = [&](int e, bool always) {
    require(e >= 0 && e < problem.num_tets(), "{} term: tet {} of the subset is not one of the problem's {}", term, e,
            problem.num_tets());
    int& slot = slot_of[static_cast<std::size_t>(e)];
    if (always || slot < 0) {
      slot = static_cast<int>(order.tets.size());
      order.tets.push_back(e);
    }
    return slot;
  };
  for (int e : subset.row_tets) add(e, true);
  order.row_count = order.tets.size();
  order.value_slots.reserve(subset.value_tets.size());
  for (int e : subset.value_tets) order.value_slots.push_back(add(e, false));
  return order;
}

}  // namespace

std::shared_ptr<const TermSubset> TermSubset::whole(const Problem& problem) {
  auto subset = std::make_shared<TermSubset>();
  subset->value_tets.resize(static_cast<std::size_t>(problem.num_tets()));
  std::iota(subset->value_tets.begin(), subset->value_tets.end(), 0);
  subset->row_tets = subset->value_tets;
  subset->nodes.resize(static_cast<std::size_t>(problem.num_nodes()));
  std::iota(subset->nodes.begin(), subset->nodes.end(), 0);
  return subset;
}

// ---------------------------------------------------------------------------------------------------------
// Elasticity

ElasticTerm::ElasticTerm(const Problem& problem, std::shared_ptr<const TermSubset> subset) {
  require(subset != nullptr, "elastic term: no subset");
  require(problem.tet_rest.size() == static_cast<std::size_t>(problem.num_tets()) &&
              problem.tet_material.size() == static_cast<std::size_t>(problem.num_tets()),
          "elastic term: the problem has {} tets but {} rest states and {} materials (Problem::validate first)",
          problem.num_tets(), problem.tet_rest.size(), problem.tet_material.size());
  PackOrder order = pack_order(problem, *subset, "elastic");
  packed_.reserve(order.tets.size());
  for (int e : order.tets) {
    const auto se = static_cast<std::size_t>(e);
    PackedTet t;
    t.rest = problem.tet_rest[se];
    t.material = problem.tet_material[se];
    t.energy_scale = energy_scale(problem, e);
    t.tet = e;
    for (int a = 0; a < 4; ++a) t.nodes[static_cast<std::size_t>(a)] = problem.tets(e, a);
    packed_.push_back(t);
  }
  row_count_ = order.row_count;
  value_slots_ = std::move(order.value_slots);
}

double ElasticTerm::value(const Eigen::VectorXd& x) const {
  const double total = deterministic_reduce(
      value_slots_.size(), 0.0,
      [&](const tbb::blocked_range<std::size_t>& range, double acc) {
        for (std::size_t k = range.begin(); k < range.end(); ++k) {
          const PackedTet& t = packed_[static_cast<std::size_t>(value_slots_[k])];
          try {
            acc += t.energy_scale * material::tet_elastic_energy(t.rest, tet_nodes(t.nodes, x), t.material);
          } catch (const Error&) {
            acc = kInfinity;  // the Fung exponent overflowed: this state is out of reach
          }
        }
        return acc;
      },
      [](double a, double b) { return a + b; });
  return std::isfinite(total) ? total : kInfinity;
}

bool ElasticTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const {
  struct Partial {
    Eigen::VectorXd gradient;
    int failed = 0;
  };
  const Partial total = deterministic_reduce(
      row_count_, Partial{Eigen::VectorXd::Zero(x.size()), 0},
      [&](const tbb::blocked_range<std::size_t>& range, Partial acc) {
        for (std::size_t k = range.begin(); k < range.end(); ++k) {
          const PackedTet& t = packed_[k];
          try {
            const material::Vector12d ge =
                t.energy_scale * material::tet_elastic_dq(t.rest, tet_nodes(t.nodes, x), t.material);
            for (int a = 0; a < 4; ++a)
              acc.gradient.segment<3>(3 * t.nodes[static_cast<std::size_t>(a)]) += ge.segment<3>(3 * a);
          } catch (const Error&) {
            ++acc.failed;
          }
        }
        return acc;
      },
      [](Partial a, const Partial& b) {
        a.gradient += b.gradient;
        a.failed += b.failed;
        return a;
      });
  g += total.gradient;
  return total.failed == 0 && g.allFinite();
}

// Blocks are computed in batches in parallel and handed to the sink in order (the sink is serial: it adds into
// the matrix), the sink taking one batch while the next is computed, so that the refill hides behind the kernels
// when there is more than one thread. 512 blocks (590 kB) stay in cache between the two.
bool ElasticTerm::add_hessian(const Eigen::VectorXd& x, HessianSink& sink) const {
  constexpr std::size_t kBatch = 512;
  std::array<std::vector<material::Matrix12d>, 2> buffers;
  for (auto& buffer : buffers) buffer.resize(std::min(kBatch, row_count_));
  std::atomic<int> failed{0};
  auto compute = [&](std::size_t first, std::vector<material::Matrix12d>& blocks) {
    const std::size_t count = std::min(kBatch, row_count_ - first);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 64), [&](const auto& range) {
      int failed_here = 0;
      for (std::size_t k = range.begin(); k < range.end(); ++k) {
        const PackedTet& t = packed_[first + k];
        material::Matrix12d& K = blocks[k];
        try {
          K = t.energy_scale * material::tet_elastic_dq2(t.rest, tet_nodes(t.nodes, x), t.material, projection_);
        } catch (const Error&) {
          K.setZero();
          ++failed_here;
        }
        if (!K.allFinite()) {
          K.setZero();
          ++failed_here;
        }
      }
      if (failed_here > 0) failed += failed_here;
    });
  };
  auto hand_over = [&](std::size_t first, const std::vector<material::Matrix12d>& blocks) {
    const std::size_t count = std::min(kBatch, row_count_ - first);
    for (std::size_t k = 0; k < count; ++k) sink.add_tet(first + k, packed_[first + k].tet, blocks[k]);
  };
  if (row_count_ == 0) return true;
  compute(0, buffers[0]);
  std::size_t batch = 0;
  for (std::size_t first = 0; first < row_count_; first += kBatch, ++batch) {
    const std::size_t next = first + kBatch;
    auto& current = buffers[batch % 2];
    if (next < row_count_) {
      tbb::parallel_invoke([&] { hand_over(first, current); }, [&] { compute(next, buffers[(batch + 1) % 2]); });
    } else {
      hand_over(first, current);
    }
  }
  return failed.load() == 0;
}

// ---------------------------------------------------------------------------------------------------------
// Inertia

InertiaTerm::InertiaTerm(const Problem& problem, std::shared_ptr<const TermSubset> subset)
    : problem_(problem), subset_(std::move(subset)) {
  require(subset_ != nullptr, "inertia term: no subset");
  require(problem.mass_kind == MassKind::lumped || problem.tet_mass.size() == problem.num_tets(),
          "inertia term: consistent mass without ρV per tet");
  if (problem.mass_kind != MassKind::consistent) return;
  PackOrder order = pack_order(problem, *subset_, "inertia");
  std::vector<char> used(static_cast<std::size_t>(problem.num_nodes()), 0);
  for (int e : order.tets) {
    std::array<int, 4> nodes{};
    for (int a = 0; a < 4; ++a) {
      nodes[static_cast<std::size_t>(a)] = problem.tets(e, a);
      used[static_cast<std::size_t>(problem.tets(e, a))] = 1;
    }
    tet_nodes_.push_back(nodes);
    tet_mass_.push_back(problem.tet_mass[e]);
  }
  row_count_ = order.row_count;
  value_slots_ = std::move(order.value_slots);
  for (int i = 0; i < problem.num_nodes(); ++i)
    if (used[static_cast<std::size_t>(i)]) residual_nodes_.push_back(i);
}

void InertiaTerm::set_step(const NodeFrame& frame, const InertiaTarget& target) {
  require(static_cast<int>(frame.A.size()) == problem_.num_nodes() && target.p_tilde.size() == problem_.num_dofs(),
          "inertia term: maps for {} nodes and p̃ of {} entries, expected {} nodes", frame.A.size(),
          target.p_tilde.size(), problem_.num_nodes());
  require(target.h_eff > 0.0, "inertia term: ĥ must be positive");
  frame_ = &frame;
  target_ = &target;
}

Eigen::Vector3d InertiaTerm::residual(const Eigen::VectorXd& x, int node) const {
  return posed_node(*frame_, x, node) - target_->p_tilde.segment<3>(3 * node);
}

// Each node's residual once (a tet's four would otherwise be recomputed by each of its ~5 tets per node).
Eigen::Matrix3Xd InertiaTerm::residuals(const Eigen::VectorXd& x) const {
  Eigen::Matrix3Xd r(3, problem_.num_nodes());
  for (int i : residual_nodes_) r.col(i) = residual(x, i);
  return r;
}

double InertiaTerm::value(const Eigen::VectorXd& x) const {
  require(frame_ != nullptr, "inertia term: set_step was not called");
  const double scale = 1.0 / (2.0 * target_->h_eff * target_->h_eff);
  double total = 0.0;
  if (problem_.mass_kind == MassKind::lumped) {
    for (int i : subset_->nodes) total += problem_.mass[i] * residual(x, i).squaredNorm();
  } else {
    const Eigen::Matrix3Xd residual_of = residuals(x);
    for (int slot : value_slots_) {
      const auto k = static_cast<std::size_t>(slot);
      Eigen::Matrix<double, 3, 4> r;
      for (int a = 0; a < 4; ++a) r.col(a) = residual_of.col(tet_nodes_[k][static_cast<std::size_t>(a)]);
      const Eigen::Vector3d sum = r.rowwise().sum();
      // Σ_ab ρV/20 (1 + δ_ab) r_a·r_b = ρV/20 (|Σ_a r_a|² + Σ_a |r_a|²)   (consistent mass, mass.hpp)
      total += tet_mass_[k] * 0.05 * (sum.squaredNorm() + r.colwise().squaredNorm().sum());
    }
  }
  return scale * total;
}

bool InertiaTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const {
  require(frame_ != nullptr, "inertia term: set_step was not called");
  const double scale = 1.0 / (target_->h_eff * target_->h_eff);
  if (problem_.mass_kind == MassKind::lumped) {
    for (int i : subset_->nodes)
      g.segment<3>(3 * i) +=
          scale * problem_.mass[i] * (frame_->A[static_cast<std::size_t>(i)].transpose() * residual(x, i));
    return true;
  }
  // Only the rows of the subset's nodes are complete; the others are partial sums, as for elasticity.
  const Eigen::Matrix3Xd residual_of = residuals(x);
  for (std::size_t k = 0; k < row_count_; ++k) {
    Eigen::Matrix<double, 3, 4> r;
    for (int a = 0; a < 4; ++a) r.col(a) = residual_of.col(tet_nodes_[k][static_cast<std::size_t>(a)]);
    const Eigen::Vector3d sum = r.rowwise().sum();
    for (int a = 0; a < 4; ++a) {
      const int i = tet_nodes_[k][static_cast<std::size_t>(a)];
      const Eigen::Vector3d force = tet_mass_[k] * 0.05 * (sum + r.col(a));  // Σ_b M_e(a, b) r_b
      g.segment<3>(3 * i) += scale * (frame_->A[static_cast<std::size_t>(i)].transpose() * force);
    }
  }
  return true;
}

bool InertiaTerm::add_hessian(const Eigen::VectorXd&, HessianSink& sink) const {
  require(frame_ != nullptr, "inertia term: set_step was not called");
  const double scale = 1.0 / (target_->h_eff * target_->h_eff);
  if (problem_.mass_kind == MassKind::lumped) {
    for (int i : subset_->nodes) {
      const Eigen::Matrix3d& A = frame_->A[static_cast<std::size_t>(i)];
      sink.add_node(i, scale * problem_.mass[i] * (A.transpose() * A));
    }
    return true;
  }
  for (std::size_t k = 0; k < row_count_; ++k) {
    const std::array<int, 4>& nodes = tet_nodes_[k];
    material::Matrix12d block;
    for (int a = 0; a < 4; ++a) {
      const Eigen::Matrix3d& Aa = frame_->A[static_cast<std::size_t>(nodes[static_cast<std::size_t>(a)])];
      for (int b = 0; b < 4; ++b) {
        const Eigen::Matrix3d& Ab = frame_->A[static_cast<std::size_t>(nodes[static_cast<std::size_t>(b)])];
        block.block<3, 3>(3 * a, 3 * b) = (scale * tet_mass_[k] * consistent_mass_factor(a, b)) * (Aa.transpose() * Ab);
      }
    }
    sink.add_tet(k, subset_->row_tets[k], block);
  }
  return true;
}

// ---------------------------------------------------------------------------------------------------------
// Gravity

GravityTerm::GravityTerm(const Problem& problem, std::shared_ptr<const TermSubset> subset)
    : problem_(problem), subset_(std::move(subset)) {
  require(subset_ != nullptr, "gravity term: no subset");
}

double GravityTerm::value(const Eigen::VectorXd& x) const {
  require(frame_ != nullptr, "gravity term: set_frame was not called");
  double total = 0.0;
  for (int i : subset_->nodes) total -= problem_.mass[i] * problem_.gravity.dot(posed_node(*frame_, x, i));
  return total;
}

bool GravityTerm::add_gradient(const Eigen::VectorXd&, Eigen::VectorXd& g) const {
  require(frame_ != nullptr, "gravity term: set_frame was not called");
  for (int i : subset_->nodes)
    g.segment<3>(3 * i) -= problem_.mass[i] * (frame_->A[static_cast<std::size_t>(i)].transpose() * problem_.gravity);
  return true;
}

bool GravityTerm::add_hessian(const Eigen::VectorXd&, HessianSink&) const { return true; }

// ---------------------------------------------------------------------------------------------------------
// Node potentials

PotentialTerm::PotentialTerm(const Problem& problem) : problem_(problem) {}

Eigen::Vector3d PotentialTerm::posed(const Eigen::VectorXd& x, int node) const { return posed_node(*frame_, x, node); }

bool PotentialTerm::begin(const RowMatrixX3d& p_n, double t0, double dt, const NodeFrame& frame,
                          const Eigen::VectorXd& x_prescribed, const std::function<bool(int)>& owns) {
  frame_ = &frame;
  active_.clear();
  for (const auto& potential : problem_.potentials) {
    const std::vector<int>& nodes = potential->nodes();
    RowMatrixX3d start(static_cast<Eigen::Index>(nodes.size()), 3), skinned(static_cast<Eigen::Index>(nodes.size()), 3);
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      start.row(static_cast<Eigen::Index>(k)) = p_n.row(nodes[k]);
      skinned.row(static_cast<Eigen::Index>(k)) = posed(x_prescribed, nodes[k]).transpose();
    }
    if (!potential->begin_substep(t0, dt, start, skinned)) continue;
    Active term;
    term.potential = potential.get();
    for (int c : potential->candidates()) term.node.push_back(nodes[static_cast<std::size_t>(c)]);
    for (std::size_t c = 0; c < term.node.size(); ++c)
      if (!owns || owns(term.node[c])) term.owned.push_back(static_cast<int>(c));
    active_.push_back(std::move(term));
  }
  return !active_.empty();
}

bool PotentialTerm::accept(const Eigen::VectorXd& x_new) const {
  bool accepted = true;
  for (const Active& term : active_) {
    RowMatrixX3d p_end(static_cast<Eigen::Index>(term.node.size()), 3);
    for (std::size_t c = 0; c < term.node.size(); ++c)
      p_end.row(static_cast<Eigen::Index>(c)) = posed(x_new, term.node[c]).transpose();
    accepted = term.potential->accept_substep(p_end) && accepted;  // every potential sees the result
  }
  return accepted;
}

std::string PotentialTerm::unresolved() const {
  for (const Active& term : active_)
    if (std::string reason = term.potential->unresolved(); !reason.empty()) return reason;
  return {};
}

int PotentialTerm::max_refinements() const {
  int most = 0;
  for (const Active& term : active_) most = std::max(most, term.potential->max_refinements());
  return most;
}

double PotentialTerm::value(const Eigen::VectorXd& x) const {
  double sum = 0.0;
  for (const Active& term : active_)
    for (int c : term.owned)
      sum += term.potential->evaluate(c, posed(x, term.node[static_cast<std::size_t>(c)]), nullptr, nullptr);
  return std::isfinite(sum) ? sum : kInfinity;
}

bool PotentialTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const {
  bool finite = true;
  for (const Active& term : active_) {
    for (int c : term.owned) {
      const int i = term.node[static_cast<std::size_t>(c)];
      Eigen::Vector3d gradient;
      term.potential->evaluate(c, posed(x, i), &gradient, nullptr);
      finite = finite && gradient.allFinite();
      g.segment<3>(3 * i) += frame_->A[static_cast<std::size_t>(i)].transpose() * gradient;  // A_iᵀ ∇u
    }
  }
  return finite;
}

bool PotentialTerm::add_hessian(const Eigen::VectorXd& x, HessianSink& sink) const {
  bool finite = true;
  for (const Active& term : active_) {
    for (int c : term.owned) {
      const int i = term.node[static_cast<std::size_t>(c)];
      const Eigen::Matrix3d& A = frame_->A[static_cast<std::size_t>(i)];
      Eigen::Vector3d gradient;
      Eigen::Matrix3d hessian;
      term.potential->evaluate(c, posed(x, i), &gradient, &hessian);
      const Eigen::Matrix3d block = A.transpose() * hessian * A;  // A_iᵀ ∇²u A_i
      finite = finite && block.allFinite();
      sink.add_node(i, block);
    }
  }
  return finite;
}

}  // namespace sflsh::model
