#include <sflsh/core/error.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/material/surface_operators.hpp>
#include <sflsh/reduced/shape_elasticity.hpp>

#include <Eigen/Cholesky>

#include <cmath>

namespace sflsh::reduced {

namespace {
constexpr int kB = body::kNumBetas;
constexpr int kK = material::kNumKappa;
}  // namespace

ShapeElasticity ShapeElasticity::constant(const material::KappaMatrix& kappa_normalized) {
  ShapeElasticity s;
  s.b = kappa_normalized;
  s.A.assign(static_cast<std::size_t>(kappa_normalized.rows()), ShapeMatrix::Zero());
  return s;
}

material::KappaMatrix ShapeElasticity::kappa_normalized(const body::Betas& beta) const {
  require(static_cast<int>(A.size()) == num_controls(), "shape elasticity: {} A blocks for {} control points", A.size(),
          num_controls());
  material::KappaMatrix kappa(num_controls(), kK);
  for (int i = 0; i < num_controls(); ++i)
    kappa.row(i) = (A[static_cast<std::size_t>(i)].transpose() * beta).transpose() + b.row(i);  // eq. 1
  return kappa;
}

Eigen::VectorXd ShapeElasticity::pack() const {
  Eigen::VectorXd p(kParamsPerControl * num_controls());
  for (int i = 0; i < num_controls(); ++i) {
    const ShapeMatrix& a = A[static_cast<std::size_t>(i)];
    p.segment<kB * kK>(kParamsPerControl * i) = Eigen::Map<const Eigen::Matrix<double, kB * kK, 1>>(a.data());
    p.segment<kK>(kParamsPerControl * i + kB * kK) = b.row(i).transpose();
  }
  return p;
}

ShapeElasticity ShapeElasticity::unpack(const Eigen::VectorXd& p, int num_controls) {
  require(num_controls >= 1 && p.size() == kParamsPerControl * num_controls,
          "shape elasticity: parameter vector has {} entries, expected 33 × {} control points", p.size(), num_controls);
  require(p.allFinite(), "shape elasticity: parameter vector has non-finite entries");
  ShapeElasticity s;
  s.A.resize(static_cast<std::size_t>(num_controls));
  s.b.resize(num_controls, kK);
  for (int i = 0; i < num_controls; ++i) {
    s.A[static_cast<std::size_t>(i)] = Eigen::Map<const ShapeMatrix>(p.data() + kParamsPerControl * i);
    s.b.row(i) = p.segment<kK>(kParamsPerControl * i + kB * kK).transpose();
  }
  return s;
}

Eigen::SparseMatrix<double> kappa_jacobian(const body::Betas& beta, int num_controls) {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(num_controls) * kK * (kB + 1));
  for (int i = 0; i < num_controls; ++i)
    for (int c = 0; c < kK; ++c) {
      const int row = kK * i + c;
      for (int k = 0; k < kB; ++k) t.emplace_back(row, kParamsPerControl * i + kB * c + k, beta[k]);  // ∂κ̂_ic/∂A_i(k,c)
      t.emplace_back(row, kParamsPerControl * i + kB * kK + c, 1.0);  // ∂κ̂_ic/∂b_ic
    }
  Eigen::SparseMatrix<double> J(kK * num_controls, kParamsPerControl * num_controls);
  J.setFromTriplets(t.begin(), t.end());
  return J;
}

const char* regularizer_name(Regularizer r) {
  switch (r) {
    case Regularizer::l2:
      return "L2";
    case Regularizer::local:
      return "ours";
    case Regularizer::none:
      return "none";
  }
  return "?";
}

const char* regularizer_key(Regularizer r) {
  switch (r) {
    case Regularizer::l2:
      return "l2";
    case Regularizer::local:
      return "local";
    case Regularizer::none:
      return "none";
  }
  return "?";
}

Regularizer parse_regularizer(const std::string& text, const std::string& what) {
  for (Regularizer r : {Regularizer::l2, Regularizer::local, Regularizer::none})
    if (text == regularizer_key(r)) return r;
  throw_error("{}: unknown regularizer '{}' (expected l2, local or none)", what, text);
}

std::vector<ShapeMetric> local_shape_covariance(const body::BodyModel& model, const std::vector<int>& region_vertices,
                                                const Eigen::VectorXd& area, const Eigen::MatrixXd& phi) {
  const auto R = static_cast<Eigen::Index>(region_vertices.size());
  require(area.size() == R && phi.rows() == R, "local shape metric: {} region vertices, {} areas, basis with {} rows",
          R, area.size(), phi.rows());
  require(model.shapedirs.cols() >= kB, "local shape metric: the body has {} shape directions, expected ≥ {}",
          model.shapedirs.cols(), kB);
  // Per vertex a(t) B(t)ᵀB(t), then the φ-weighted sums (eq. 3).
  std::vector<ShapeMetric> moment_of_vertex(static_cast<std::size_t>(R));
  for (Eigen::Index t = 0; t < R; ++t) {
    const int v = region_vertices[static_cast<std::size_t>(t)];
    const Eigen::Matrix<double, 3, kB> B = model.shapedirs.block(3 * v, 0, 3, kB);
    moment_of_vertex[static_cast<std::size_t>(t)] = area[t] * B.transpose() * B;
  }
  const int N = static_cast<int>(phi.cols());
  std::vector<ShapeMetric> M(static_cast<std::size_t>(N));
  double trace_sum = 0.0;
  for (int i = 0; i < N; ++i) {
    ShapeMetric& moment = M[static_cast<std::size_t>(i)];
    moment.setZero();
    for (Eigen::Index t = 0; t < R; ++t) moment += phi(t, i) * moment_of_vertex[static_cast<std::size_t>(t)];
    moment = 0.5 * (moment + moment.transpose()).eval();
    require(Eigen::LLT<ShapeMetric>(moment).info() == Eigen::Success && moment.diagonal().minCoeff() > 0.0,
            "local shape metric: the shape blend-shape moment of control point {} is not positive definite", i);
    trace_sum += moment.trace();
  }
  const double scale = kB * N / trace_sum;  // mean_i tr(M_i)/10 = 1: the covariance carries the scale, not Q
  for (ShapeMetric& m : M) m *= scale;
  return M;
}

std::vector<ShapeMetric> local_shape_metric(const body::BodyModel& model, const std::vector<int>& region_vertices,
                                            const Eigen::VectorXd& area, const Eigen::MatrixXd& phi) {
  std::vector<ShapeMetric> Q = local_shape_covariance(model, region_vertices, area, phi);
  for (ShapeMetric& q : Q) {
    const ShapeMetric inverse = Eigen::LLT<ShapeMetric>(q).solve(ShapeMetric::Identity());  // eq. 4
    q = 0.5 * (inverse + inverse.transpose());
  }
  return Q;
}

std::vector<ShapeMetric> layer_shape_metric(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                                            const Eigen::MatrixXd& phi) {
  const Eigen::VectorXd area =
      material::lumped_mass(material::region_positions(model, mesh), mesh.region_surface.faces);
  return local_shape_metric(model, mesh.region_surface.vertices, area, phi);
}

Eigen::SparseMatrix<double> regularizer_matrix(const std::vector<ShapeMetric>& metric, int num_controls) {
  require(metric.empty() || static_cast<int>(metric.size()) == num_controls,
          "regularizer: {} metrics for {} control points", metric.size(), num_controls);
  const double scale = 1.0 / std::sqrt(static_cast<double>(num_controls));
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < num_controls; ++i) {
    Eigen::Matrix<double, kB, kB> LT = Eigen::Matrix<double, kB, kB>::Identity();
    if (!metric.empty()) {
      Eigen::LLT<ShapeMetric> llt(metric[static_cast<std::size_t>(i)]);
      require(llt.info() == Eigen::Success, "regularizer: metric of control point {} is not positive definite", i);
      LT = llt.matrixL().transpose();  // tr(AᵀQA) = ‖L_iᵀA‖²_F
    }
    for (int c = 0; c < kK; ++c)
      for (int r = 0; r < kB; ++r)
        for (int k = 0; k < kB; ++k)
          if (LT(r, k) != 0.0)
            t.emplace_back(kB * kK * i + kB * c + r, kParamsPerControl * i + kB * c + k, scale * LT(r, k));
  }
  Eigen::SparseMatrix<double> L(kB * kK * num_controls, kParamsPerControl * num_controls);
  L.setFromTriplets(t.begin(), t.end());
  return L;
}

void parameter_bounds(const material::ParameterBounds& bounds, int num_controls, double a_max, Eigen::VectorXd& lower,
                      Eigen::VectorXd& upper) {
  require(a_max > 0.0 && std::isfinite(a_max), "shape elasticity: A bound must be positive, got {}", a_max);
  const material::ParameterBounds nb = material::normalized_bounds(bounds);
  lower.resize(kParamsPerControl * num_controls);
  upper.resize(kParamsPerControl * num_controls);
  for (int i = 0; i < num_controls; ++i) {
    lower.segment<kB * kK>(kParamsPerControl * i).setConstant(-a_max);
    upper.segment<kB * kK>(kParamsPerControl * i).setConstant(a_max);
    for (int c = 0; c < kK; ++c) {
      lower[kParamsPerControl * i + kB * kK + c] = nb[c].min;
      upper[kParamsPerControl * i + kB * kK + c] = nb[c].max;
    }
  }
}

material::KappaMatrix clamp_normalized(const material::KappaMatrix& kappa, const material::ParameterBounds& bounds,
                                       int* clamped) {
  const material::ParameterBounds nb = material::normalized_bounds(bounds);
  material::KappaMatrix out = kappa;
  int moved = 0;
  for (Eigen::Index i = 0; i < out.rows(); ++i)
    for (int c = 0; c < kK; ++c) {
      const double v = std::clamp(out(i, c), nb[c].min, nb[c].max);
      if (v != out(i, c)) ++moved;
      out(i, c) = v;
    }
  if (clamped) *clamped = moved;
  return out;
}

}  // namespace sflsh::reduced
