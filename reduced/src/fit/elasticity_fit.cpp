#include "fit_checkpoint.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/material/surface_operators.hpp>
#include <sflsh/reduced/elasticity_fit.hpp>
#include <sflsh/reduced/young_map.hpp>

#include <nlohmann/json.hpp>

#include <chrono>
#include <functional>

namespace sflsh::reduced {

namespace {

constexpr int kK = material::kNumKappa;

int params_per_control(FitKind kind) { return kind == FitKind::shape ? kParamsPerControl : kK; }

/// p of an independent fit: κ̂ row-major (control i, column c at 3i + c).
material::KappaMatrix independent_kappa(const Eigen::VectorXd& p) {
  return Eigen::Map<const material::KappaMatrix>(p.data(), p.size() / kK, kK);
}

Eigen::VectorXd flatten(const material::KappaMatrix& k) {
  return Eigen::Map<const Eigen::VectorXd>(k.data(), k.size());
}

/// Everything one stage needs, fixed while TAO iterates.
struct Stage {
  const FitContext* context = nullptr;
  const FitSpec* spec = nullptr;
  const std::vector<FitTarget>* targets = nullptr;
  const LayerParameterization* parameterization = nullptr;
  int controls = 0;
  std::vector<Eigen::SparseMatrix<double>> dq_dp;  ///< per subject (3N × P)
  Eigen::SparseMatrix<double> L;                   ///< eq. 7 without √λ (shape fits)
  double weight = 1.0;                             ///< w of r_fit
  int fit_rows = 0;
  std::vector<const DynamicsCase*> cases;
  std::vector<std::vector<int>> targets_of_subject;
  Eigen::MatrixXd young_map;  ///< W (cubature tets × N), sensitivities only
  long simulations = 0;
  int jacobians = 0;
  double residual_seconds = 0.0, jacobian_seconds = 0.0;
  const FitPoint* reuse = nullptr;  ///< a warm start's point: what matches is not simulated again
  FitPoint last_residual;           ///< σ per target of the last residual, evaluated at last_residual_p
  Eigen::VectorXd last_residual_p;
  FitPoint last_jacobian;  ///< σ and terms per target at last_jacobian_p (the stage's result's FitPoint)
  Eigen::VectorXd last_jacobian_p;

  int num_subjects() const { return static_cast<int>(spec->betas.size()); }

  material::KappaMatrix q(int subject, const Eigen::VectorXd& p, Eigen::VectorXd* active = nullptr) const {
    const Eigen::VectorXd raw = dq_dp[static_cast<std::size_t>(subject)] * p;
    const material::KappaMatrix unclamped = Eigen::Map<const material::KappaMatrix>(raw.data(), controls, kK);
    const material::KappaMatrix clamped = clamp_normalized(unclamped, context->bounds);
    if (active) {
      active->resize(raw.size());
      for (Eigen::Index i = 0; i < raw.size(); ++i)
        (*active)[i] = clamped(i / kK, i % kK) == unclamped(i / kK, i % kK) ? 1.0 : 0.0;
    }
    return clamped;
  }

  std::vector<Eigen::VectorXd> simulate(std::vector<SimulationJob>& jobs) {
    simulations += static_cast<long>(jobs.size());
    return context->pool->run(cases, jobs, *parameterization, *context->model, context->reduced);
  }

  Eigen::VectorXd residual(const Eigen::VectorXd& p) {
    const ScopedSeconds timer(residual_seconds);
    std::vector<SimulationJob> jobs;
    std::vector<material::KappaMatrix> kappa(static_cast<std::size_t>(num_subjects()));
    for (int j = 0; j < num_subjects(); ++j)
      kappa[static_cast<std::size_t>(j)] = material::denormalize(q(j, p), context->bounds);
    std::vector<Eigen::VectorXd> sigma(targets->size());
    for (std::size_t t = 0; t < targets->size(); ++t) {
      const material::KappaMatrix& kappa_t = kappa[static_cast<std::size_t>((*targets)[t].subject)];
      if (const Eigen::VectorXd* known = reuse ? reuse->sigma((*targets)[t].simulation, kappa_t) : nullptr)
        sigma[t] = *known;
      else
        jobs.push_back({static_cast<int>(t), kappa_t});
    }
    if (!jobs.empty()) {
      std::vector<Eigen::VectorXd> run = simulate(jobs);
      for (std::size_t i = 0; i < jobs.size(); ++i)
        sigma[static_cast<std::size_t>(jobs[i].case_index)] = std::move(run[i]);
    }
    last_residual.targets.resize(targets->size());
    for (std::size_t t = 0; t < targets->size(); ++t) {
      FitPoint::Target& entry = last_residual.targets[t];
      entry.simulation = (*targets)[t].simulation;
      entry.kappa = kappa[static_cast<std::size_t>((*targets)[t].subject)];
      entry.sigma = sigma[t];
    }
    last_residual_p = p;
    Eigen::VectorXd r(fit_rows + (spec->kind == FitKind::shape ? L.rows() : 0));
    int at = 0;
    for (std::size_t t = 0; t < targets->size(); ++t) {
      const auto n = sigma[t].size();
      r.segment(at, n) = weight * (sigma[t] - (*targets)[t].sigma);  // eq. 6
      at += static_cast<int>(n);
    }
    if (spec->kind == FitKind::shape) r.tail(L.rows()) = std::sqrt(spec->lambda) * (L * p);  // eq. 7
    return r;
  }

  /// Keeps σ (when the last residual was at p) and, with `with_terms`, the terms of the targets `mine` at p.
  void record_jacobian_point(const Eigen::VectorXd& p, const std::vector<int>& mine,
                             const material::KappaMatrix& kappa0, bool with_terms, bool exact_thickness,
                             const std::vector<Eigen::VectorXd>& terms) {
    if (last_jacobian_p.size() != p.size() || last_jacobian_p != p) {
      last_jacobian.targets.assign(targets->size(), FitPoint::Target{});
      last_jacobian_p = p;
    }
    const bool sigma_here = last_residual_p.size() == p.size() && last_residual_p == p;
    for (std::size_t m = 0; m < mine.size(); ++m) {
      const auto t = static_cast<std::size_t>(mine[m]);
      FitPoint::Target& entry = last_jacobian.targets[t];
      entry.simulation = (*targets)[t].simulation;
      entry.kappa = kappa0;
      if (sigma_here) entry.sigma = last_residual.targets[t].sigma;
      if (!with_terms) continue;
      entry.parameterization = parameterization;
      entry.exact_thickness = exact_thickness;
      entry.weight = weight;
      entry.target_sigma = (*targets)[t].sigma;
      entry.terms = terms[m];
    }
  }

  NormalEquations normal_equations(const Eigen::VectorXd& p, const Eigen::VectorXd& r) {
    ++jacobians;
    const ScopedSeconds timer(jacobian_seconds);
    const auto P = p.size();
    NormalEquations ne;
    ne.JtJ = Eigen::MatrixXd::Zero(P, P);
    ne.Jtr = Eigen::VectorXd::Zero(P);
    // Residual offsets per target.
    std::vector<int> offset(targets->size() + 1, 0);
    for (std::size_t t = 0; t < targets->size(); ++t)
      offset[t + 1] = offset[t] + static_cast<int>((*targets)[t].sigma.size());
    for (int j = 0; j < num_subjects(); ++j)
      if (!targets_of_subject[static_cast<std::size_t>(j)].empty()) add_subject_terms(j, p, r, offset, ne);
    if (spec->kind == FitKind::shape) {
      const Eigen::MatrixXd LtL = Eigen::MatrixXd(L.transpose() * L);
      ne.JtJ += spec->lambda * LtL;
      ne.Jtr += std::sqrt(spec->lambda) * (L.transpose() * r.tail(L.rows()));
    }
    return ne;
  }

  /// Subject j's part of JᵀJ and Jᵀr: the terms of its targets, through the clamp and dq/dp (eq. 8).
  void add_subject_terms(int j, const Eigen::VectorXd& p, const Eigen::VectorXd& r, const std::vector<int>& offset,
                         NormalEquations& ne) {
    const std::vector<int>& mine = targets_of_subject[static_cast<std::size_t>(j)];
    const double step = spec->fd_step;
    const material::ParameterBounds nb = material::normalized_bounds(context->bounds);
    Eigen::VectorXd active;
    const material::KappaMatrix q0 = q(j, p, &active);
    // One-sided differences (backwards at an upper bound) in every entry of q_j, or only in the thickness
    // entries when the Young moduli come from sensitivities.
    const bool sensitive = spec->jacobian == JacobianMethod::sensitivities;
    const bool exact_thickness = sensitive && !spec->thickness_differences;
    std::vector<int> fd_columns;
    for (int k = 0; k < 3 * controls; ++k)
      if (!sensitive || (k % kK == material::kThickness && !exact_thickness)) fd_columns.push_back(k);
    std::vector<SimulationJob> jobs;
    std::vector<double> h(static_cast<std::size_t>(3 * controls), 0.0);
    for (int k : fd_columns) {
      material::KappaMatrix qk = q0;
      const int i = k / kK, c = k % kK;
      h[static_cast<std::size_t>(k)] = q0(i, c) + step <= nb[c].max ? step : -step;
      qk(i, c) += h[static_cast<std::size_t>(k)];
      const material::KappaMatrix kappa = material::denormalize(qk, context->bounds);
      for (int t : mine) jobs.push_back({t, kappa});
    }
    const std::vector<Eigen::VectorXd> sigma = jobs.empty() ? std::vector<Eigen::VectorXd>{} : simulate(jobs);
    // Per target t: G_t = dσ_t/dq_j and its terms w² G_tᵀG_t, w G_tᵀ r_t (packed: 9N², then 3N), from the
    // difference columns and, with sensitivities, dσ/dY (2R × 2N or 3N) [mm/Pa] of the target's run.
    const int Q = 3 * controls;
    auto normal_terms = [&](std::size_t m, const Eigen::MatrixXd* dsigma_dyoung) {
      const int t = mine[m];
      const Eigen::VectorXd rt =
          r.segment(offset[static_cast<std::size_t>(t)],
                    offset[static_cast<std::size_t>(t) + 1] - offset[static_cast<std::size_t>(t)]);
      const Eigen::VectorXd sigma_t = rt / weight + (*targets)[static_cast<std::size_t>(t)].sigma;
      Eigen::MatrixXd G(sigma_t.size(), Q);
      for (std::size_t f = 0; f < fd_columns.size(); ++f) {
        const int k = fd_columns[f];
        G.col(k) = (sigma[f * mine.size() + m] - sigma_t) / h[static_cast<std::size_t>(k)];
      }
      if (dsigma_dyoung)  // dσ/dq̂ = dσ/dY · Y_max (q̂ = Y / Y_max)
        for (int i = 0; i < controls; ++i) {
          G.col(kK * i + material::kYoungTangent) = dsigma_dyoung->col(i) * context->bounds.young_tangent.max;
          G.col(kK * i + material::kYoungNormal) = dsigma_dyoung->col(controls + i) * context->bounds.young_normal.max;
          if (exact_thickness)  // dσ/dĥ = dσ/dh · h_max
            G.col(kK * i + material::kThickness) = dsigma_dyoung->col(2 * controls + i) * context->bounds.thickness.max;
        }
      G *= weight;
      Eigen::VectorXd out(Q * Q + Q);
      Eigen::Map<Eigen::MatrixXd>(out.data(), Q, Q).noalias() = G.transpose() * G;
      out.tail(Q).noalias() = G.transpose() * rt;
      return out;
    };
    std::vector<Eigen::VectorXd> terms(mine.size());
    const material::KappaMatrix kappa0 = material::denormalize(q0, context->bounds);
    if (sensitive)  // one differentiated run per target, its G_tᵀG_t made where it ran (in parallel)
      terms = sensitivity_terms(mine, kappa0, !fd_columns.empty(), exact_thickness, normal_terms);
    else
      for (std::size_t m = 0; m < mine.size(); ++m) terms[m] = normal_terms(m, nullptr);
    record_jacobian_point(p, mine, kappa0, sensitive && fd_columns.empty(), exact_thickness, terms);
    // H_q = Σ_t w² G_tᵀG_t, g_q = Σ_t w G_tᵀ r_t, summed in target order (the same on every rank).
    Eigen::MatrixXd Hq = Eigen::MatrixXd::Zero(Q, Q);
    Eigen::VectorXd gq = Eigen::VectorXd::Zero(Q);
    for (const Eigen::VectorXd& term : terms) {
      Hq += Eigen::Map<const Eigen::MatrixXd>(term.data(), Q, Q);
      gq += term.tail(Q);
    }
    // Chain rule through the clamp and dq/dp (eq. 8).
    // dq/dp stays sparse (11 entries per row for a shape fit): JqᵀHqJq costs P²·11 instead of P²·3N.
    const Eigen::SparseMatrix<double> Jq = active.asDiagonal() * dq_dp[static_cast<std::size_t>(j)];
    const Eigen::MatrixXd HqJq = Hq * Jq;
    ne.JtJ.noalias() += Jq.transpose() * HqJq;
    ne.Jtr.noalias() += Jq.transpose() * gq;
  }

  /// The normal terms of every target in `mine` from one differentiated run each (or the warm start's point where
  /// it holds them and no column is differenced), the runs shared over the pool.
  std::vector<Eigen::VectorXd> sensitivity_terms(
      const std::vector<int>& mine, const material::KappaMatrix& kappa0, bool with_differences, bool exact_thickness,
      const std::function<Eigen::VectorXd(std::size_t, const Eigen::MatrixXd*)>& normal_terms) {
    const int Q = 3 * controls;
    const int sensitivity_columns = exact_thickness ? 3 * controls : 2 * controls;
    std::vector<Eigen::VectorXd> terms(mine.size());
    std::vector<std::size_t> missing;  // into mine: the targets whose terms the warm start's point lacks
    for (std::size_t m = 0; m < mine.size(); ++m) {
      const FitTarget& target = (*targets)[static_cast<std::size_t>(mine[m])];
      const Eigen::VectorXd* known =
          reuse && !with_differences
              ? reuse->terms(target.simulation, kappa0, parameterization, exact_thickness, weight, target.sigma)
              : nullptr;
      if (known)
        terms[m] = *known;
      else
        missing.push_back(m);
    }
    std::vector<Eigen::VectorXd> made;
    if (!missing.empty())
      made = context->pool->run_tasks(
          static_cast<int>(missing.size()), [&](int) { return Eigen::Index{Q} * Q + Q; },
          [&](int i) {
            const std::size_t m = missing[static_cast<std::size_t>(i)];
            const DynamicsCase& c = *(*targets)[static_cast<std::size_t>(mine[m])].simulation;
            Eigen::MatrixXd d;
            c.simulate_with_sensitivity(*parameterization, kappa0, *context->model, young_map, d, context->reduced,
                                        exact_thickness);
            require(d.cols() == sensitivity_columns, "fit: a differentiated run gave {} columns, expected {}", d.cols(),
                    sensitivity_columns);
            return normal_terms(m, &d);
          });
    for (std::size_t i = 0; i < missing.size(); ++i) terms[missing[i]] = std::move(made[i]);
    simulations += static_cast<long>(missing.size());
    return terms;
  }
};

/// Fills a stage for N control points (the parts that do not change while TAO iterates).
void setup_stage(Stage& stage, const FitContext& context, const std::vector<FitTarget>& targets, const FitSpec& spec,
                 const LayerParameterization& parameterization, int N) {
  stage.context = &context;
  stage.spec = &spec;
  stage.targets = &targets;
  stage.parameterization = &parameterization;
  stage.controls = N;
  stage.targets_of_subject.resize(spec.betas.size());
  for (std::size_t t = 0; t < targets.size(); ++t) {
    stage.cases.push_back(targets[t].simulation);
    stage.targets_of_subject[static_cast<std::size_t>(targets[t].subject)].push_back(static_cast<int>(t));
    stage.fit_rows += static_cast<int>(targets[t].sigma.size());
  }
  stage.weight = 1.0 / std::sqrt(static_cast<double>(stage.fit_rows));
  for (const body::Betas& beta : spec.betas) {
    if (spec.kind == FitKind::shape) {
      stage.dq_dp.push_back(kappa_jacobian(beta, N));
    } else {
      Eigen::SparseMatrix<double> I(3 * N, 3 * N);
      I.setIdentity();
      stage.dq_dp.push_back(I);
    }
  }
  if (spec.kind == FitKind::shape) {
    std::vector<ShapeMetric> metric;
    if (spec.regularizer == Regularizer::local)
      metric = layer_shape_metric(*context.body, parameterization.mesh(), parameterization.phi());
    stage.L = regularizer_matrix(metric, N);
    if (spec.regularizer == Regularizer::none) stage.L *= 0.0;  // no regularizer rows carry weight
  }

  if (spec.jacobian == JacobianMethod::sensitivities)
    stage.young_map = young_tet_map(parameterization.retargeter(), parameterization.phi(), context.model->cubature.tets,
                                    targets.front().simulation->layer_options().stiffness_scale);
}

std::string kind_name(FitKind k) { return k == FitKind::shape ? "shape" : "independent"; }

/// A fingerprint of what the fit depends on, so a checkpoint of a different fit is never resumed.
std::string spec_fingerprint(const FitSpec& spec, const std::vector<FitTarget>& targets) {
  nlohmann::json j;
  j["name"] = spec.name;
  j["kind"] = kind_name(spec.kind);
  j["regularizer"] = regularizer_name(spec.regularizer);
  j["lambda"] = spec.lambda;
  j["stages"] = spec.stages;
  j["fd_step"] = spec.fd_step;
  j["a_max"] = spec.a_max;
  if (spec.warm_start.size() > 0) {  // a warm-started fit depends on where it started
    j["warm_start_from"] = spec.warm_start_from;
    j["warm_start"] = std::vector<double>(spec.warm_start.data(), spec.warm_start.data() + spec.warm_start.size());
  }
  std::vector<std::vector<double>> betas;
  for (const auto& b : spec.betas) betas.emplace_back(b.data(), b.data() + b.size());
  j["betas"] = betas;
  std::vector<std::string> cases;
  double target_sum = 0.0;
  for (const FitTarget& t : targets) {
    cases.push_back(t.simulation->subject() + "/" + t.simulation->motion());
    target_sum += t.sigma.sum();
  }
  j["cases"] = cases;
  j["target_sum"] = target_sum;
  return j.dump();
}

/// Per-control parameter rows (N × k) of p, and back.
Eigen::MatrixXd rows_of(const Eigen::VectorXd& p, int k) {
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(p.data(),
                                                                                                  p.size() / k, k);
}
Eigen::VectorXd from_rows(const Eigen::MatrixXd& rows) {
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> r = rows;
  return Eigen::Map<const Eigen::VectorXd>(r.data(), r.size());
}

/// Throws naming the fit when the context, the targets or the spec cannot make a fit.
void check_fit(const FitContext& context, const std::vector<FitTarget>& targets, const FitSpec& spec) {
  require(context.body && context.model && context.pool && context.parameterization, "fit {}: incomplete context",
          spec.name);
  require(!targets.empty(), "fit {}: no targets", spec.name);
  require(!spec.stages.empty() && spec.stages.front() >= 1, "fit {}: stages must start at ≥ 1 control point",
          spec.name);
  for (std::size_t s = 1; s < spec.stages.size(); ++s)
    require(spec.stages[s] > spec.stages[s - 1], "fit {}: stages must grow, got {} after {}", spec.name, spec.stages[s],
            spec.stages[s - 1]);
  require(!spec.betas.empty(), "fit {}: no subjects", spec.name);
  require(spec.kind == FitKind::shape || spec.betas.size() == 1, "fit {}: an independent fit has one subject, got {}",
          spec.name, spec.betas.size());
  require(spec.lambda >= 0.0 && std::isfinite(spec.lambda), "fit {}: λ must be ≥ 0, got {}", spec.name, spec.lambda);
  require(spec.fd_step > 0.0 && spec.fd_step < 0.1, "fit {}: finite-difference step {} outside (0, 0.1)", spec.name,
          spec.fd_step);
  for (const FitTarget& t : targets) {
    require(t.simulation && t.subject >= 0 && t.subject < static_cast<int>(spec.betas.size()),
            "fit {}: a target names subject {} of {}", spec.name, t.subject, spec.betas.size());
    require(t.sigma.size() == 2 * t.simulation->num_region_vertices() && t.sigma.allFinite(),
            "fit {}: target {}/{} has {} values, expected 2 × {} finite", spec.name, t.simulation->subject(),
            t.simulation->motion(), t.sigma.size(), t.simulation->num_region_vertices());
  }
}

/// Lower and upper bounds of the stage's parameters: shape fits (A_i, b_i) by parameter_bounds, independent fits
/// κ̂ within the normalized ranges.
void set_parameter_bounds(LeastSquaresProblem& problem, const FitSpec& spec, const material::ParameterBounds& bounds,
                          int N) {
  if (spec.kind == FitKind::shape) {
    parameter_bounds(bounds, N, spec.a_max, problem.lower, problem.upper);
    return;
  }
  const material::ParameterBounds nb = material::normalized_bounds(bounds);
  problem.lower.resize(kK * N);
  problem.upper.resize(kK * N);
  for (int i = 0; i < N; ++i)
    for (int c = 0; c < kK; ++c) {
      problem.lower[kK * i + c] = nb[c].min;
      problem.upper[kK * i + c] = nb[c].max;
    }
}

/// The first stage's start: the neutral material (initial_kappa) at every control point, no shape dependence.
Eigen::VectorXd neutral_start(FitKind kind, const material::ParameterBounds& bounds, int N) {
  material::KappaMatrix k0(N, kK);
  for (int i = 0; i < N; ++i) k0.row(i) = material::to_row(material::initial_kappa(bounds));
  const material::KappaMatrix kn = material::normalize(k0, bounds);
  return kind == FitKind::shape ? ShapeElasticity::constant(kn).pack() : flatten(kn);
}

/// A fit its checkpoint says is finished: its parameters and stage reports, without simulating.
FitResult finished_fit(const FitSpec& spec, const Checkpoint& checkpoint) {
  require(checkpoint.p.size() == params_per_control(spec.kind) * spec.stages.back(),
          "fit {}: checkpoint {} does not match the stages", spec.name, spec.checkpoint.string());
  logger()->info("fit {}: finished earlier (checkpoint {})", spec.name, spec.checkpoint.string());
  FitResult result;
  result.name = spec.name;
  result.kind = spec.kind;
  result.p = checkpoint.p;
  result.finished_earlier = true;
  result.controls = spec.stages.back();
  result.stages = checkpoint.done;
  return result;
}

/// The solver's settings for a stage that has `done_before` iterations behind it (a resumed checkpoint).
LeastSquaresOptions stage_options(const FitSpec& spec, int done_before) {
  LeastSquaresOptions options;
  options.max_iterations = std::max(0, spec.iterations - done_before);
  options.gradient_ttol = 1e-6;
  options.gradient_rtol = 1e-8;
  options.loss_rtol = spec.loss_rtol;
  // The trust radius keeps TAO's floor (1e-10): a floor of 1e-3 in these normalized parameters saved the ~20
  // residual evaluations of a run of rejected steps but stopped warm and full fits after one iteration where the
  // default floor's small accepted steps kept lowering the loss (the paper preset, docs/fit.md).
  return options;
}

/// Writes the fit's checkpoint (rank 0 only, when the spec names one).
void save_fit_checkpoint(const FitContext& context, const FitSpec& spec, const std::string& fingerprint,
                         const Checkpoint& checkpoint) {
  if (!spec.checkpoint.empty() && context.pool->rank() == 0) save_checkpoint(spec.checkpoint, fingerprint, checkpoint);
}

/// A stage's report from the solver's result: the loss split into its fit and regularizer parts at the solver's
/// own residual (no further simulation) and the test that stopped it.
FitStageReport stage_report(const Stage& stage, const LeastSquaresResult& ls, int N, int iterations, double seconds) {
  const Eigen::VectorXd& r = ls.residual;
  FitStageReport report;
  report.controls = N;
  report.iterations = iterations;
  report.loss_fit = r.head(stage.fit_rows).squaredNorm();
  report.loss_reg = r.size() > stage.fit_rows ? r.tail(r.size() - stage.fit_rows).squaredNorm() : 0.0;
  report.seconds = seconds;
  report.simulations = stage.simulations;
  report.jacobians = stage.jacobians;
  report.reason = ls.stopped_by.empty() ? ls.reason : ls.stopped_by;
  return report;
}

}  // namespace

const char* jacobian_method_name(JacobianMethod m) {
  return m == JacobianMethod::sensitivities ? "sensitivities" : "fd";
}

JacobianMethod parse_jacobian_method(const std::string& name) {
  if (name == "fd" || name == "finite-differences") return JacobianMethod::finite_differences;
  if (name == "sensitivities") return JacobianMethod::sensitivities;
  throw_error("fit: unknown Jacobian method '{}' (expected fd or sensitivities)", name);
}

NormalEquations fit_normal_equations(const FitContext& context, const std::vector<FitTarget>& targets,
                                     const FitSpec& spec, const Eigen::VectorXd& p, double* residual_seconds,
                                     double* jacobian_seconds) {
  require(!spec.stages.empty() && !targets.empty(), "fit {}: no stage or no target", spec.name);
  const int N = spec.stages.front();
  Stage stage;
  setup_stage(stage, context, targets, spec, context.parameterization(N), N);
  require(p.size() == params_per_control(spec.kind) * N, "fit {}: {} parameters for N = {}", spec.name, p.size(), N);
  const Eigen::VectorXd r = stage.residual(p);
  const NormalEquations ne = stage.normal_equations(p, r);
  if (residual_seconds) *residual_seconds = stage.residual_seconds;
  if (jacobian_seconds) *jacobian_seconds = stage.jacobian_seconds;
  return ne;
}

material::KappaMatrix FitResult::kappa_normalized(const body::Betas& beta,
                                                  const material::ParameterBounds& bounds) const {
  if (kind == FitKind::independent) return clamp_normalized(independent_kappa(p), bounds);
  return clamp_normalized(ShapeElasticity::unpack(p, controls).kappa_normalized(beta), bounds);
}

material::KappaMatrix FitResult::kappa(const body::Betas& beta, const material::ParameterBounds& bounds) const {
  return material::denormalize(kappa_normalized(beta, bounds), bounds);
}

ShapeElasticity FitResult::shape() const {
  require(kind == FitKind::shape, "fit {}: an independent fit has no shape model", name);
  return ShapeElasticity::unpack(p, controls);
}

const LayerParameterization& ParameterizationCache::get(int controls) {
  auto it = cache_.find(controls);
  if (it == cache_.end()) it = cache_.emplace(controls, std::make_unique<LayerParameterization>(base_, controls)).first;
  return *it->second;
}

FitResult fit_elasticity(const FitContext& context, const std::vector<FitTarget>& targets, const FitSpec& spec) {
  check_fit(context, targets, spec);
  const auto start_time = std::chrono::steady_clock::now();
  const std::string fingerprint = spec_fingerprint(spec, targets);
  std::optional<Checkpoint> checkpoint = load_checkpoint(spec.checkpoint, fingerprint);

  if (checkpoint && checkpoint->finished) return finished_fit(spec, *checkpoint);
  FitResult result;
  result.name = spec.name;
  result.kind = spec.kind;
  const int k = params_per_control(spec.kind);
  Eigen::VectorXd p;
  const LayerParameterization* previous = nullptr;
  std::size_t first_stage = 0;
  const bool warm = spec.warm_start.size() > 0;
  if (warm) {  // continuation: only the last stage, from the given parameters
    require(spec.warm_start.size() == k * spec.stages.back() && spec.warm_start.allFinite(),
            "fit {}: warm start has {} parameters, expected {} finite (N = {})", spec.name, spec.warm_start.size(),
            k * spec.stages.back(), spec.stages.back());
    first_stage = spec.stages.size() - 1;
    p = spec.warm_start;
    logger()->info("fit {}: warm start at N = {} from {}", spec.name, spec.stages.back(),
                   spec.warm_start_from.empty() ? std::string("given parameters") : spec.warm_start_from);
  }
  if (checkpoint) {
    first_stage = static_cast<std::size_t>(checkpoint->stage);
    result.stages = checkpoint->done;
    p = checkpoint->p;
    require(first_stage < spec.stages.size() && p.size() == k * spec.stages[first_stage],
            "fit {}: checkpoint {} does not match the stages", spec.name, spec.checkpoint.string());
    logger()->info("fit {}: resuming at N = {} after iteration {}", spec.name, spec.stages[first_stage],
                   checkpoint->iteration);
  }
  for (std::size_t s = first_stage; s < spec.stages.size(); ++s) {
    const int N = spec.stages[s];
    const LayerParameterization& parameterization = context.parameterization(N);
    // Warm start: the previous stage's field at the new control points; the first stage starts neutral.
    const bool resumed_here = checkpoint && s == first_stage;
    const bool warm_here = warm && !checkpoint && s == first_stage;
    if (!resumed_here && !warm_here) {
      p = previous ? from_rows(transfer_control_values(*previous, parameterization, rows_of(p, k)))
                   : neutral_start(spec.kind, context.bounds, N);
    }
    previous = &parameterization;

    Stage stage;
    setup_stage(stage, context, targets, spec, parameterization, N);
    if (warm_here) stage.reuse = spec.warm_start_point.get();

    LeastSquaresProblem problem;
    problem.residual = [&](const Eigen::VectorXd& x) { return stage.residual(x); };
    problem.normal_equations = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& r) {
      return stage.normal_equations(x, r);
    };
    set_parameter_bounds(problem, spec, context.bounds, N);
    const int done_before = resumed_here ? checkpoint->iteration : 0;
    LeastSquaresOptions lso = stage_options(spec, done_before);
    const auto stage_start = std::chrono::steady_clock::now();
    lso.monitor = [&](int iteration, const Eigen::VectorXd& x, double loss, double gnorm) {
      const double elapsed = seconds_since(stage_start);
      const int it = done_before + iteration;
      const double eta = iteration > 0 ? elapsed / iteration * std::max(0, lso.max_iterations - iteration) : 0.0;
      if (context.progress)
        logger()->info("fit {} · N = {} · iteration {}/{} · loss {:.5g} · |g| {:.3g} · {} simulations · ETA {:.0f} s",
                       spec.name, N, it, spec.iterations, 2.0 * loss, gnorm, stage.simulations, eta);
      save_fit_checkpoint(context, spec, fingerprint, {false, static_cast<int>(s), it, x, result.stages});
    };
    LeastSquaresResult ls;
    if (lso.max_iterations > 0) {
      ls = solve_bounded_least_squares(problem, p, lso);
    } else {
      ls.p = p;
      ls.residual = stage.residual(p);
      ls.reason = "resumed";
      ls.converged = true;
    }
    p = ls.p;
    const FitStageReport report = stage_report(stage, ls, N, done_before + ls.iterations, seconds_since(stage_start));
    result.stages.push_back(report);
    logger()->info("fit {}: N = {} done: loss fit {:.5g} mm², reg {:.4g}, {} iterations ({}), {} simulations, {:.1f} s",
                   spec.name, N, report.loss_fit, report.loss_reg, report.iterations, report.reason, report.simulations,
                   report.seconds);
    if (s + 1 < spec.stages.size())  // the next stage starts from this one's field at its control points
      save_fit_checkpoint(context, spec, fingerprint,
                          {false, static_cast<int>(s + 1), 0,
                           from_rows(transfer_control_values(
                               parameterization, context.parameterization(spec.stages[s + 1]), rows_of(p, k))),
                           result.stages});
    checkpoint.reset();
    result.controls = N;
    if (s + 1 == spec.stages.size() && stage.last_jacobian_p.size() == p.size() && stage.last_jacobian_p == p)
      result.final_point = std::make_shared<const FitPoint>(std::move(stage.last_jacobian));
  }
  save_fit_checkpoint(
      context, spec, fingerprint,
      {true, static_cast<int>(spec.stages.size()) - 1, result.stages.back().iterations, p, result.stages});
  result.p = p;
  logger()->debug("fit {}: {:.1f} s in total", spec.name, seconds_since(start_time));
  return result;
}

}  // namespace sflsh::reduced
