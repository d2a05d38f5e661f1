// Writing and checking material files (material_file.hpp, docs/material_file.md).
#include <sflsh/body/body_model.hpp>
#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/toml_reader.hpp>
#include <sflsh/material/material_file.hpp>

#include <toml++/toml.h>

#include <array>
#include <cmath>
#include <map>
#include <sstream>

namespace sflsh::material {

static_assert(kNumBetasInFile == static_cast<std::size_t>(body::kNumBetas), "'betas' holds the body's β");

namespace {

// "<what>:<line>" for points read from a file, "<what>" otherwise.
std::string where(std::string_view what, const MaterialControlPoint& point) {
  return point.line > 0 ? fmt::format("{}:{}", what, point.line) : std::string(what);
}

}  // namespace

std::vector<int> MaterialFile::vertices() const {
  std::vector<int> out;
  out.reserve(control_points.size());
  for (const MaterialControlPoint& p : control_points) out.push_back(p.vertex);
  return out;
}

KappaMatrix MaterialFile::kappa() const {
  KappaMatrix out(static_cast<Eigen::Index>(control_points.size()), kNumKappa);
  for (std::size_t i = 0; i < control_points.size(); ++i)
    out.row(static_cast<Eigen::Index>(i)) = to_row(control_points[i].kappa);
  return out;
}

void validate(const MaterialFile& material, std::string_view what) {
  require(!material.body.empty(), "{}: 'body' must not be empty", what);
  require(!material.subject.empty(), "{}: 'subject' must not be empty", what);
  if (material.betas)
    for (double b : *material.betas) require(std::isfinite(b), "{}: 'betas' has a non-finite entry", what);
  require(std::isfinite(material.poisson) && material.poisson > -1.0 && material.poisson < 0.5,
          "{}: 'poisson' = {} is outside (-1, 0.5)", what, material.poisson);
  require(std::isfinite(material.saturation) && material.saturation > 0.0 && material.saturation <= kSaturationMax,
          "{}: saturation: {} is outside (0, {}]", what, material.saturation, kSaturationMax);
  try {
    validate(material.bounds);
  } catch (const Error& e) {
    throw_error("{}: {}", what, e.what());
  }
  require(!material.control_points.empty(), "{}: no control points", what);
  std::map<int, std::size_t> seen;  // vertex → index of its first point
  for (std::size_t i = 0; i < material.control_points.size(); ++i) {
    const MaterialControlPoint& p = material.control_points[i];
    const std::string at = where(what, p);
    require(p.vertex >= 0, "{}: control_point #{} has 'vertex' = {} (must be >= 0)", at, i, p.vertex);
    const auto [it, inserted] = seen.emplace(p.vertex, i);
    require(inserted, "{}: control_point #{} repeats vertex {} of control_point #{}", at, i, p.vertex, it->second);
    require(!p.position || p.position->allFinite(), "{}: control_point #{} has a non-finite 'position'", at, i);
    validate(p.kappa, material.bounds, fmt::format("{}: control_point #{} (vertex {})", at, i, p.vertex));
  }
}

void check_against_body(const MaterialFile& material, const RowMatrixX3d& V, double position_tolerance,
                        std::string_view what) {
  if (what.empty()) what = material.source.empty() ? std::string_view("material") : std::string_view(material.source);
  for (std::size_t i = 0; i < material.control_points.size(); ++i) {
    const MaterialControlPoint& p = material.control_points[i];
    const std::string at = where(what, p);
    require(p.vertex >= 0 && p.vertex < V.rows(),
            "{}: control_point #{} 'vertex' = {} is outside the body's {} vertices", at, i, p.vertex, V.rows());
    if (!p.position) continue;
    const Eigen::Vector3d actual = V.row(p.vertex).transpose();
    const double distance = (actual - *p.position).norm();
    require(distance <= position_tolerance,
            "{}: control_point #{} 'position' is {:.3g} m from vertex {} of body '{}' at ({:.6g}, {:.6g}, {:.6g}) "
            "(tolerance {:.3g} m): the file belongs to another body or template",
            at, i, distance, p.vertex, material.body, actual.x(), actual.y(), actual.z(), position_tolerance);
  }
}

void check_against_body(const MaterialFile& material, const body::BodyModel& body, double position_tolerance) {
  const std::string_view what =
      material.source.empty() ? std::string_view("material") : std::string_view(material.source);
  require(
      material.body == body.name,
      "{}: body: the material is for body '{}', but the run uses body '{}' (write one for it with `sflsh material`)",
      what, material.body, body.name);
  check_against_body(material, body.v_template, position_tolerance, what);
}

void save_material_file(const std::filesystem::path& path, const MaterialFile& material, const std::string& header) {
  validate(material, fmt::format("save_material_file {}", path.string()));
  std::ostringstream out;
  std::istringstream lines(header);
  for (std::string line; std::getline(lines, line);) out << "# " << line << "\n";
  if (!header.empty()) out << "\n";
  out << "version = " << kMaterialFileVersion << "\n";
  out << "body = " << toml_string(material.body) << "\n";
  out << "subject = " << toml_string(material.subject) << "\n";
  if (material.betas) {
    out << "betas = [";
    for (std::size_t k = 0; k < material.betas->size(); ++k) out << (k ? ", " : "") << toml_float((*material.betas)[k]);
    out << "]  # the subject's shape coefficients\n";
  }
  out << "poisson = " << toml_float(material.poisson) << "\n";
  out << "saturation = " << toml_float(material.saturation) << "\n";
  out << "\n[bounds]  # closed ranges of each parameter; the maxima normalize κ (SFLSH §4)\n";
  constexpr std::array<std::string_view, kNumKappa> comments = {"  # fraction of the maximum thickness", "  # Pa",
                                                                "  # Pa"};
  for (int c = 0; c < kNumKappa; ++c) {
    const auto i = static_cast<std::size_t>(c);
    out << kKappaNames[i] << " = [" << toml_float(material.bounds[c].min) << ", " << toml_float(material.bounds[c].max)
        << "]" << comments[i] << "\n";
  }
  for (const MaterialControlPoint& p : material.control_points) {
    out << "\n[[control_point]]\n";
    out << "vertex = " << p.vertex << "\n";
    if (p.position)
      out << "position = [" << toml_float(p.position->x()) << ", " << toml_float(p.position->y()) << ", "
          << toml_float(p.position->z()) << "]\n";
    out << "thickness = " << toml_float(p.kappa.thickness) << "\n";
    out << "young_tangent = " << toml_float(p.kappa.young_tangent) << "\n";
    out << "young_normal = " << toml_float(p.kappa.young_normal) << "\n";
  }
  write_text_atomically(path, out.str());
}

}  // namespace sflsh::material
