// Writing and checking shape-model files, and the material of a subject of shape β (shape_model_file.hpp).
#include <sflsh/body/body_io.hpp>
#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/toml_reader.hpp>
#include <sflsh/reduced/shape_model_file.hpp>

#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <sstream>

namespace sflsh::reduced {

namespace {

// "<what>:<line>" for points read from a file, "<what>" otherwise.
std::string where(std::string_view what, const ShapeModelControlPoint& point) {
  return point.line > 0 ? fmt::format("{}:{}", what, point.line) : std::string(what);
}

std::string toml_strings(const std::vector<std::string>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + toml_string(values[i]);
  return out + "]";
}

}  // namespace

std::vector<int> ShapeModelFile::vertices() const {
  std::vector<int> out;
  out.reserve(control_points.size());
  for (const ShapeModelControlPoint& p : control_points) out.push_back(p.vertex);
  return out;
}

ShapeElasticity ShapeModelFile::elasticity() const {
  ShapeElasticity s;
  s.b.resize(num_controls(), material::kNumKappa);
  for (int i = 0; i < num_controls(); ++i) {
    const ShapeModelControlPoint& p = control_points[static_cast<std::size_t>(i)];
    s.A.push_back(p.A);
    s.b.row(i) = p.b;
  }
  return s;
}

ShapeModelFile make_shape_model_file(const ShapeElasticity& elasticity, const body::BodyModel& model,
                                     const std::vector<int>& control_vertices, const material::ParameterBounds& bounds,
                                     double poisson, double saturation) {
  require(static_cast<int>(control_vertices.size()) == elasticity.num_controls() &&
              static_cast<int>(elasticity.A.size()) == elasticity.num_controls(),
          "shape model: {} control vertices for a model of {} control points ({} A blocks)", control_vertices.size(),
          elasticity.num_controls(), elasticity.A.size());
  ShapeModelFile file;
  file.body = model.name;
  file.poisson = poisson;
  file.saturation = saturation;
  file.bounds = bounds;
  for (int i = 0; i < elasticity.num_controls(); ++i) {
    const int v = control_vertices[static_cast<std::size_t>(i)];
    require(v >= 0 && v < model.num_vertices(), "shape model: control vertex {} is outside the body's {} vertices", v,
            model.num_vertices());
    ShapeModelControlPoint p;
    p.vertex = v;
    p.position = model.v_template.row(v).transpose();
    p.A = elasticity.A[static_cast<std::size_t>(i)];
    p.b = elasticity.b.row(i);
    file.control_points.push_back(p);
  }
  validate(file, "shape model");
  return file;
}

void validate(const ShapeModelFile& model, std::string_view what) {
  require(!model.body.empty(), "{}: 'body' must not be empty", what);
  require(std::isfinite(model.poisson) && model.poisson > -1.0 && model.poisson < 0.5,
          "{}: 'poisson' = {} is outside (-1, 0.5)", what, model.poisson);
  require(std::isfinite(model.saturation) && model.saturation > 0.0 && model.saturation <= material::kSaturationMax,
          "{}: saturation: {} is outside (0, {}]", what, model.saturation, material::kSaturationMax);
  try {
    material::validate(model.bounds);
  } catch (const Error& e) {
    throw_error("{}: {}", what, e.what());
  }
  if (model.fit)
    require(std::isfinite(model.fit->lambda) && model.fit->lambda >= 0.0, "{}: 'lambda' in [fit] = {} must be >= 0",
            what, model.fit->lambda);
  require(!model.control_points.empty(), "{}: no control points", what);
  std::map<int, std::size_t> seen;  // vertex → index of its first point
  for (std::size_t i = 0; i < model.control_points.size(); ++i) {
    const ShapeModelControlPoint& p = model.control_points[i];
    const std::string at = where(what, p);
    require(p.vertex >= 0, "{}: control_point #{} has 'vertex' = {} (must be >= 0)", at, i, p.vertex);
    const auto [it, inserted] = seen.emplace(p.vertex, i);
    require(inserted, "{}: control_point #{} repeats vertex {} of control_point #{}", at, i, p.vertex, it->second);
    require(!p.position || p.position->allFinite(), "{}: control_point #{} has a non-finite 'position'", at, i);
    require(p.A.allFinite() && p.b.allFinite(), "{}: control_point #{} has a non-finite entry in 'A' or 'b'", at, i);
  }
}

void save_shape_model_file(const std::filesystem::path& path, const ShapeModelFile& model, const std::string& header) {
  validate(model, fmt::format("save_shape_model_file {}", path.string()));
  std::ostringstream out;
  std::istringstream lines(header);
  for (std::string line; std::getline(lines, line);) out << "# " << line << "\n";
  if (!header.empty()) out << "\n";
  out << "# Shape-dependent elasticity (SFLSH eq. 1): per control point, normalized (h, Y_t, Y_n) / κ_max =\n"
         "# A^T β + b, clamped into the bounds; format in reduced/include/sflsh/reduced/shape_model_file.hpp.\n";
  out << "version = " << kShapeModelFileVersion << "\n";
  out << "body = " << toml_string(model.body) << "\n";
  out << "poisson = " << toml_float(model.poisson) << "\n";
  out << "saturation = " << toml_float(model.saturation) << "\n";
  out << "\n[bounds]  # closed ranges of each parameter; the maxima normalize κ (SFLSH §4)\n";
  constexpr std::array<std::string_view, material::kNumKappa> comments = {"  # fraction of the maximum thickness",
                                                                          "  # Pa", "  # Pa"};
  for (int c = 0; c < material::kNumKappa; ++c) {
    const auto i = static_cast<std::size_t>(c);
    out << material::kKappaNames[i] << " = [" << toml_float(model.bounds[c].min) << ", "
        << toml_float(model.bounds[c].max) << "]" << comments[i] << "\n";
  }
  out << "\n[basis]  # how control values are interpolated (material::layer_basis)\n";
  out << "kind = " << toml_string(std::string(kShapeModelBasisKind)) << "\n";
  if (!model.region.empty()) out << "region = " << toml_string(model.region) << "\n";
  if (!model.mesh.empty()) out << "mesh = " << toml_string(model.mesh) << "\n";
  if (model.fit) {
    out << "\n[fit]  # how the model was fitted (metadata)\n";
    out << "regularizer = " << toml_string(regularizer_key(model.fit->regularizer)) << "\n";
    out << "lambda = " << toml_float(model.fit->lambda) << "\n";
    out << "subjects = " << toml_strings(model.fit->subjects) << "\n";
    out << "motions = " << toml_strings(model.fit->motions) << "\n";
  }
  for (const ShapeModelControlPoint& p : model.control_points) {
    out << "\n[[control_point]]\n";
    out << "vertex = " << p.vertex << "\n";
    if (p.position)
      out << "position = [" << toml_float(p.position->x()) << ", " << toml_float(p.position->y()) << ", "
          << toml_float(p.position->z()) << "]\n";
    out << "b = [" << toml_float(p.b[0]) << ", " << toml_float(p.b[1]) << ", " << toml_float(p.b[2]) << "]\n";
    out << "A = [  # rows β_1..β_10, columns h, Y_t, Y_n\n";
    for (int k = 0; k < body::kNumBetas; ++k)
      out << "  [" << toml_float(p.A(k, 0)) << ", " << toml_float(p.A(k, 1)) << ", " << toml_float(p.A(k, 2)) << "],\n";
    out << "]\n";
  }
  write_text_atomically(path, out.str());
}

std::filesystem::path default_shape_model_path() { return body::data_dir() / "shape_models" / "default.toml"; }

void check_layer_match(const ShapeModelFile& model, const std::string& layer_region, const std::string& layer_mesh,
                       std::string_view user) {
  const std::string at = model.basis_line > 0 ? fmt::format("{}:{}", model.source, model.basis_line)
                                              : (model.source.empty() ? std::string("shape model") : model.source);
  require(model.region.empty() || model.region == layer_region,
          "{}: region in [basis]: the shape model was fitted on region '{}', but {} uses layers of region '{}'", at,
          model.region, user, layer_region);
  require(model.mesh.empty() || model.mesh == layer_mesh,
          "{}: mesh in [basis]: the shape model was fitted on the '{}' mesh, but {} uses the '{}' mesh", at, model.mesh,
          user, layer_mesh);
}

material::MaterialFile material_for_beta(const ShapeModelFile& model, const body::BodyModel& body,
                                         const body::Betas& beta, const std::string& subject) {
  // Messages name the shape-model file (the material is derived from it), or "shape model" when built in memory.
  const std::string what = model.source.empty() ? std::string("shape model") : model.source;
  validate(model, what);
  require(model.body == body.name, "{}: body: the shape model is for body '{}', but the run uses body '{}'", what,
          model.body, body.name);
  require(beta.allFinite(), "{}: β has non-finite entries (subject '{}')", what, subject);
  const material::KappaMatrix normalized = clamp_normalized(model.elasticity().kappa_normalized(beta), model.bounds);
  material::KappaMatrix kappa = material::denormalize(normalized, model.bounds);  // κ = κ̂ κ_max
  // κ̂_min · κ_max can differ from κ_min by an ulp: clamp once more in physical units.
  for (Eigen::Index i = 0; i < kappa.rows(); ++i)
    for (int c = 0; c < material::kNumKappa; ++c)
      kappa(i, c) = std::clamp(kappa(i, c), model.bounds[c].min, model.bounds[c].max);

  material::MaterialFile file;
  file.body = model.body;
  file.subject = subject.empty() ? "beta" : subject;
  file.source = model.source;  // later checks name the shape model and its control point's line
  file.poisson = model.poisson;
  file.saturation = model.saturation;
  file.bounds = model.bounds;
  for (int i = 0; i < model.num_controls(); ++i) {
    const ShapeModelControlPoint& p = model.control_points[static_cast<std::size_t>(i)];
    material::MaterialControlPoint cp;
    cp.line = p.line;  // messages point at the shape model's control point
    cp.vertex = p.vertex;
    cp.position = p.position;
    if (!cp.position && p.vertex >= 0 && p.vertex < body.num_vertices())
      cp.position = body.v_template.row(p.vertex).transpose();
    cp.kappa = material::from_row(kappa.row(i));
    file.control_points.push_back(cp);
  }
  material::validate(file, what);
  material::check_against_body(file, body.v_template, 1e-6, what);
  return file;
}

}  // namespace sflsh::reduced
