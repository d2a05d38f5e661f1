#include <sflsh/core/error.hpp>
#include <sflsh/material/parameters.hpp>

#include <cmath>

namespace sflsh::material {

namespace {

constexpr std::array<std::string_view, kNumKappa> kUnits = {"", " Pa", " Pa"};

}  // namespace

const ParameterRange& ParameterBounds::operator[](int column) const {
  switch (column) {
    case kThickness:
      return thickness;
    case kYoungTangent:
      return young_tangent;
    case kYoungNormal:
      return young_normal;
    default:
      throw_error("parameter column {} outside [0, {})", column, kNumKappa);
  }
}

Eigen::RowVector3d ParameterBounds::minimum() const { return {thickness.min, young_tangent.min, young_normal.min}; }
Eigen::RowVector3d ParameterBounds::maximum() const { return {thickness.max, young_tangent.max, young_normal.max}; }

void validate(const ParameterBounds& bounds) {
  for (int c = 0; c < kNumKappa; ++c) {
    const ParameterRange& r = bounds[c];
    require(std::isfinite(r.min) && std::isfinite(r.max) && r.min > 0.0 && r.min <= r.max,
            "parameter bounds: {} = [{}, {}] must be finite with 0 < min <= max",
            kKappaNames[static_cast<std::size_t>(c)], r.min, r.max);
  }
  require(bounds.thickness.max <= 1.0, "parameter bounds: thickness max {} exceeds 1 (h is a fraction)",
          bounds.thickness.max);
  for (int c : {kYoungTangent, kYoungNormal}) {
    const ParameterRange& r = bounds[c];
    require(r.min >= kYoungModulusLimits.min && r.max <= kYoungModulusLimits.max,
            "parameter bounds: {} = [{:.6g}, {:.6g}] Pa is outside the physical range [{:.6g}, {:.6g}] Pa",
            kKappaNames[static_cast<std::size_t>(c)], r.min, r.max, kYoungModulusLimits.min, kYoungModulusLimits.max);
  }
}

void validate(const Kappa& kappa, const ParameterBounds& bounds, std::string_view what) {
  const Eigen::RowVector3d value = to_row(kappa);
  for (int c = 0; c < kNumKappa; ++c) {
    const auto i = static_cast<std::size_t>(c);
    const ParameterRange& r = bounds[c];
    require(std::isfinite(value(c)) && value(c) >= r.min && value(c) <= r.max, "{}: {} = {} is outside [{}, {}]{}",
            what, kKappaNames[i], value(c), r.min, r.max, kUnits[i]);
  }
}

void validate(const KappaMatrix& kappa, const ParameterBounds& bounds, std::string_view what) {
  for (Eigen::Index i = 0; i < kappa.rows(); ++i)
    validate(from_row(kappa.row(i)), bounds, fmt::format("{} {}", what, i));
}

Eigen::RowVector3d to_row(const Kappa& kappa) { return {kappa.thickness, kappa.young_tangent, kappa.young_normal}; }

Kappa from_row(const Eigen::Ref<const Eigen::RowVector3d>& row) { return {row(0), row(1), row(2)}; }

KappaMatrix to_matrix(const std::vector<Kappa>& kappa) {
  KappaMatrix m(static_cast<Eigen::Index>(kappa.size()), kNumKappa);
  for (std::size_t i = 0; i < kappa.size(); ++i) m.row(static_cast<Eigen::Index>(i)) = to_row(kappa[i]);
  return m;
}

std::vector<Kappa> from_matrix(const KappaMatrix& kappa) {
  std::vector<Kappa> out;
  out.reserve(static_cast<std::size_t>(kappa.rows()));
  for (Eigen::Index i = 0; i < kappa.rows(); ++i) out.push_back(from_row(kappa.row(i)));
  return out;
}

KappaMatrix normalize(const KappaMatrix& physical, const ParameterBounds& bounds) {
  return physical.array().rowwise() / bounds.maximum().array();
}

KappaMatrix denormalize(const KappaMatrix& normalized, const ParameterBounds& bounds) {
  return normalized.array().rowwise() * bounds.maximum().array();
}

ParameterBounds normalized_bounds(const ParameterBounds& bounds) {
  ParameterBounds out;
  out.thickness = {bounds.thickness.min / bounds.thickness.max, 1.0};
  out.young_tangent = {bounds.young_tangent.min / bounds.young_tangent.max, 1.0};
  out.young_normal = {bounds.young_normal.min / bounds.young_normal.max, 1.0};
  return out;
}

Kappa initial_kappa(const ParameterBounds& bounds) {
  validate(bounds);
  return {0.5 * (bounds.thickness.min + bounds.thickness.max),
          std::sqrt(bounds.young_tangent.min * bounds.young_tangent.max),
          std::sqrt(bounds.young_normal.min * bounds.young_normal.max)};
}

KappaMatrix evaluate_field(const Eigen::MatrixXd& phi, const KappaMatrix& kappa) {
  require(phi.cols() == kappa.rows(), "evaluate_field: basis has {} functions but {} control values are given",
          phi.cols(), kappa.rows());
  require(kappa.allFinite(), "evaluate_field: control values are not all finite");
  return phi * kappa;
}

}  // namespace sflsh::material
