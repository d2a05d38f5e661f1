#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/model/layer_settings.hpp>  // region_normals
#include <sflsh/model/simulation_output.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace sflsh::model {

DynamicsAmplitude::DynamicsAmplitude(RowMatrixX3d normals)
    : normals_(std::move(normals)),
      sum_(RowMatrixX3d::Zero(normals_.rows(), 3)),
      sum_sq_(Eigen::VectorXd::Zero(normals_.rows())),
      sum_n_(Eigen::VectorXd::Zero(normals_.rows())),
      sum_sq_n_(Eigen::VectorXd::Zero(normals_.rows())) {}

void DynamicsAmplitude::add(const RowMatrixX3d& u) {
  require(u.rows() == normals_.rows(), "dynamics amplitude: {} displacements for {} vertices", u.rows(),
          normals_.rows());
  sum_ += u;
  sum_sq_ += u.rowwise().squaredNorm();
  const Eigen::VectorXd un = (u.array() * normals_.array()).rowwise().sum();
  sum_n_ += un;
  sum_sq_n_ += un.array().square().matrix();
  ++frames_;
}

// mean_t ‖u − ū‖² = mean_t ‖u‖² − ‖ū‖² (docs/physics.md §4 step 5), clamped at 0 against round-off.
Eigen::VectorXd DynamicsAmplitude::sigma() const {
  if (frames_ == 0) return Eigen::VectorXd::Zero(normals_.rows());
  const double inv = 1.0 / frames_;
  const Eigen::VectorXd mean_sq = (sum_ * inv).rowwise().squaredNorm();
  return (sum_sq_ * inv - mean_sq).cwiseMax(0.0).cwiseSqrt();
}

Eigen::VectorXd DynamicsAmplitude::sigma_normal() const {
  if (frames_ == 0) return Eigen::VectorXd::Zero(normals_.rows());
  const double inv = 1.0 / frames_;
  return (sum_sq_n_ * inv - (sum_n_ * inv).array().square().matrix()).cwiseMax(0.0).cwiseSqrt();
}

// σ² = σ_n² + σ_t² (docs/physics.md §4 step 6).
Eigen::VectorXd DynamicsAmplitude::sigma_tangent() const {
  const Eigen::VectorXd s = sigma(), sn = sigma_normal();
  return (s.array().square() - sn.array().square()).cwiseMax(0.0).sqrt().matrix();
}

RowMatrixX3d vertex_normals(const RowMatrixX3d& vertices,
                            const Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>& faces) {
  return vtk::vertex_normals(vertices, faces);
}

namespace {

double tet_energy_density(const Problem& problem, const Eigen::VectorXd& x, int e) {
  material::TetNodes nodes;
  for (int a = 0; a < 4; ++a) nodes.col(a) = x.segment<3>(3 * problem.tets(e, a));
  const auto se = static_cast<std::size_t>(e);
  const double scale = problem.tet_energy_scale.empty() ? 1.0 : problem.tet_energy_scale[se];
  try {
    return scale * material::tet_elastic_energy(problem.tet_rest[se], nodes, problem.tet_material[se]) /
           problem.tet_rest[se].volume;
  } catch (const Error&) {
    return std::numeric_limits<double>::infinity();
  }
}

}  // namespace

Eigen::VectorXd strain_energy_density(const Problem& problem, const Eigen::VectorXd& x) {
  Eigen::VectorXd psi(problem.num_tets());
  for (int e = 0; e < problem.num_tets(); ++e) psi[e] = tet_energy_density(problem, x, e);
  return psi;
}

Eigen::VectorXd strain_energy_density(const Problem& problem, const Eigen::VectorXd& x, const std::vector<int>& tets) {
  Eigen::VectorXd psi(static_cast<Eigen::Index>(tets.size()));
  for (std::size_t k = 0; k < tets.size(); ++k)
    psi[static_cast<Eigen::Index>(k)] = tet_energy_density(problem, x, tets[k]);
  return psi;
}

}  // namespace sflsh::model

namespace sflsh::model {

namespace {

/// Deviates the points by per-row affine maps and turns the first `vector_fields` three-column float arrays by their
/// linear parts (a tracking skeleton's deviation, before the placement).
void deviate(const std::vector<Eigen::Matrix<double, 3, 4>>& maps, RowMatrixX3d& points,
             std::vector<vtk::Field>& fields, std::size_t vector_fields) {
  require(maps.size() == static_cast<std::size_t>(points.rows()), "output: {} deviation maps for {} points",
          maps.size(), points.rows());
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Matrix<double, 3, 4>& M = maps[static_cast<std::size_t>(i)];
    points.row(i) = (M.leftCols<3>() * points.row(i).transpose() + M.col(3)).transpose();
  }
  for (std::size_t k = 0; k < vector_fields && k < fields.size(); ++k) {
    vtk::Field& f = fields[k];
    if (f.values.cols() != 3 || f.integer || f.values.rows() != points.rows()) continue;
    for (Eigen::Index i = 0; i < f.values.rows(); ++i)
      f.values.row(i) = (maps[static_cast<std::size_t>(i)].leftCols<3>() * f.values.row(i).transpose()).transpose();
  }
}

/// Scatters region rows (R×k) into a body-sized array (n×k), zero elsewhere.
Eigen::MatrixXd scatter(const BodyLayer& layer, const Eigen::MatrixXd& region_values) {
  const std::vector<int>& region = layer.mesh->region_surface.vertices;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(layer.shaped.rows(), region_values.cols());
  for (std::size_t r = 0; r < region.size(); ++r) out.row(region[r]) = region_values.row(static_cast<Eigen::Index>(r));
  return out;
}

/// The κ fields of `kappa`'s columns (h, Y_t, Y_n) that `wanted` accepts: thickness_fraction, the same values
/// under their older name thickness, young_tangent, young_normal.
template <typename Wanted>
void add_kappa_fields(std::vector<vtk::Field>& fields, const Eigen::MatrixXd& kappa, const Wanted& wanted) {
  static_assert(material::kNumKappa == 3);
  const std::pair<const char*, int> columns[] = {
      {"thickness_fraction", 0}, {"thickness", 0}, {"young_tangent", 1}, {"young_normal", 2}};
  for (const auto& [name, column] : columns)
    if (wanted(name)) fields.push_back({name, kappa.col(column), false});
}

double median(Eigen::VectorXd v) {
  if (v.size() == 0) return 0.0;
  std::sort(v.data(), v.data() + v.size());
  const Eigen::Index n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

const std::vector<std::string>& frame_field_names() {
  static const std::vector<std::string> names = {"displacement",         "velocity",
                                                 "skin_weights_argmax",  "soft_tissue_displacement",
                                                 "elastic_displacement", "strain_energy_density",
                                                 "thickness_fraction",   "thickness",
                                                 "young_tangent",        "young_normal",
                                                 "soft_region",          "Normals",
                                                 "contact_force",        "penetration"};
  return names;
}

void check_frame_field_names(const std::vector<std::string>& names, const std::string& where,
                             const std::string& context) {
  const std::vector<std::string>& known = frame_field_names();
  for (const std::string& name : names) {
    if (std::find(known.begin(), known.end(), name) != known.end()) continue;
    std::string list;
    for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
    throw_error("{}: unknown field '{}'{} (expected all, default, or some of {})", where, name, context, list);
  }
}

const std::vector<std::string>& default_frame_fields() {
  // Body frames: the soft tissue's own motion (σ's displacement), the energy density and the shading normals; layer
  // frames: the posed nodes with the energy density per tet; the fixed fields cost nothing per frame in an xdmf
  // series (stored once); contact arrays appear only in scenes with contact.
  static const std::vector<std::string> names = {"soft_tissue_displacement",
                                                 "strain_energy_density",
                                                 "Normals",
                                                 "skin_weights_argmax",
                                                 "thickness_fraction",
                                                 "young_tangent",
                                                 "young_normal",
                                                 "soft_region",
                                                 "contact_force",
                                                 "penetration"};
  return names;
}

std::optional<std::vector<std::string>> resolve_frame_fields(const std::vector<std::string>& names,
                                                             const std::string& where, const std::string& context) {
  if (names.size() == 1 && names.front() == "all") return std::nullopt;
  if (names.size() == 1 && names.front() == "default") return default_frame_fields();
  for (const std::string& name : names)
    require(name != "all" && name != "default", "{}: '{}'{} stands alone (not mixed with array names)", where, name,
            context);
  check_frame_field_names(names, where, context);
  return names;
}

bool is_written_frame(int frame, int frames, int every) {
  return frame == 0 || frame == frames - 1 || (every > 0 && frame % every == 0);
}

SimulationWriter::SimulationWriter(const BodyLayer& layer, RunFolder* run, bool write_layer)
    : SimulationWriter(layer, run, [write_layer] {
        SimulationWriterOptions options;
        options.write_layer = write_layer;
        return options;
      }()) {}

SimulationWriter::SimulationWriter(const BodyLayer& layer, RunFolder* run, const SimulationWriterOptions& options)
    : layer_(layer),
      run_(run),
      options_(options),
      write_layer_(options.write_layer),
      amplitude_(region_normals(layer)),
      frame_rotation_(options.rotation),
      frame_translation_(options.translation) {
  if (options_.fields) check_frame_field_names(*options_.fields, "simulation output");
  const body::BodyModel& model = *layer.model;
  dominant_joint_.resize(model.num_vertices(), 1);
  for (Eigen::Index v = 0; v < model.num_vertices(); ++v) {
    Eigen::Index k;
    model.weights.row(v).maxCoeff(&k);
    dominant_joint_(v) = static_cast<double>(k);
  }
  vertex_kappa_ = scatter(layer, layer.fields.vertex);
  soft_region_ =
      scatter(layer, Eigen::MatrixXd::Ones(static_cast<Eigen::Index>(layer.mesh->region_surface.vertices.size()), 1));
  // Neighbouring skin vertices share tets (on the coarse layer 6,929 vertices lie in about half as many tets).
  skin_tets_ = layer.mesh->skin.tet;
  std::sort(skin_tets_.begin(), skin_tets_.end());
  skin_tets_.erase(std::unique(skin_tets_.begin(), skin_tets_.end()), skin_tets_.end());
  skin_tet_slot_.reserve(layer.mesh->skin.tet.size());
  for (const int e : layer.mesh->skin.tet)
    skin_tet_slot_.push_back(
        static_cast<int>(std::lower_bound(skin_tets_.begin(), skin_tets_.end(), e) - skin_tets_.begin()));
  check_output_format(options_.format, "simulation output");
  const std::string layer_prefix = options_.prefix == "body" ? "layer" : options_.prefix + "_layer";
  if (run_ && options_.format == "xdmf") {
    // The fields that do not change go in once; every frame then holds positions and the moving fields.
    run_->stage(options_.prefix + ".h5");
    body_xdmf_ = std::make_unique<xdmf::Series>(run_->stage(options_.prefix + ".xmf"), layer.model->faces,
                                                options_.precision, options_.series_compression);
    vtk::Fields fixed;
    if (wants("skin_weights_argmax")) fixed.point_data.push_back({"skin_weights_argmax", dominant_joint_, true});
    add_kappa_fields(fixed.point_data, vertex_kappa_, [this](const std::string& name) { return wants(name); });
    if (wants("soft_region")) fixed.point_data.push_back({"soft_region", soft_region_, true});
    body_xdmf_->set_static(fixed);
    if (write_layer_) {
      run_->stage(layer_prefix + ".h5");
      layer_xdmf_ = std::make_unique<xdmf::Series>(run_->stage(layer_prefix + ".xmf"), layer.problem.tets,
                                                   options_.precision, options_.series_compression);
      vtk::Fields layer_fixed;
      add_kappa_fields(layer_fixed.point_data, layer.fields.node,
                       [this](const std::string& name) { return wants(name); });
      add_kappa_fields(layer_fixed.cell_data, layer.fields.tet,
                       [this](const std::string& name) { return wants(name); });
      layer_xdmf_->set_static(layer_fixed);
    }
  } else if (run_) {
    body_series_ = std::make_unique<vtk::PvdSeries>(run_->stage(options_.prefix + ".pvd"));
    if (write_layer_) layer_series_ = std::make_unique<vtk::PvdSeries>(run_->stage(layer_prefix + ".pvd"));
  }
}

void check_output_format(const std::string& format, const std::string& where) {
  require(format == "vtk" || format == "xdmf", "{}: format '{}' is not an output format (expected vtk or xdmf)", where,
          format);
}

bool SimulationWriter::wants(const std::string& field) const {
  return !options_.fields ||
         std::find(options_.fields->begin(), options_.fields->end(), field) != options_.fields->end();
}

void SimulationWriter::run_job(std::function<void()> job) {
  if (options_.jobs)
    options_.jobs->submit(std::move(job));
  else
    job();
}

void SimulationWriter::add_frame(double t, const State& state, const std::vector<vtk::Field>& extra) {
  add_frame(frame_, t, state, true, extra);
}

// The caller's thread does what needs the solver's objects (the skin displacement, posing along the motion);
// the job gets copies and computes the strain energies, places the fields and writes the file.
void SimulationWriter::add_frame(int index, double t, const State& state, bool write,
                                 const std::vector<vtk::Field>& extra) {
  require(state.w.allFinite(), "simulation output: the velocities at t = {} are not finite", t);
  add(index, t, state.x, &state, write, extra);
}

void SimulationWriter::add_positions(int index, double t, const Eigen::VectorXd& x, bool write,
                                     const std::vector<vtk::Field>& extra) {
  require(!(write && write_layer_ && run_), "simulation output: layer frames need the full state (add_frame)");
  add(index, t, x, nullptr, write, extra);
}

void SimulationWriter::add(int index, double t, const Eigen::VectorXd& x_state, const State* state, bool write,
                           const std::vector<vtk::Field>& extra) {
  require(x_state.allFinite(), "simulation output: the state at t = {} is not finite", t);
  const RowMatrixX3d u = layer_.surface_displacement(x_state);
  amplitude_.add(u);
  ++frame_;
  if (!run_ || !write) return;

  const auto clock = std::chrono::steady_clock::now();
  RowMatrixX3d posed = layer_.posed_surface_from_displacement(u, t);
  RowMatrixX3d skinned;
  if (wants("soft_tissue_displacement"))
    skinned = layer_.posed_surface_from_displacement(RowMatrixX3d::Zero(u.rows(), 3), t);
  posing_seconds_ += seconds_since(clock);

  vtk::Fields fields;
  if (wants("displacement")) fields.point_data.push_back({"displacement", posed - layer_.shaped, false});
  if (wants("velocity")) {
    Eigen::MatrixXd velocity = Eigen::MatrixXd::Zero(posed.rows(), 3);
    if (previous_posed_.rows() == posed.rows() && t > previous_t_)
      velocity = (posed - previous_posed_) / (t - previous_t_);
    fields.point_data.push_back({"velocity", velocity, false});
  }
  const bool xdmf = body_xdmf_ != nullptr;  // the fixed fields are in the series once
  if (wants("skin_weights_argmax") && !xdmf)
    fields.point_data.push_back({"skin_weights_argmax", dominant_joint_, true});
  if (wants("soft_tissue_displacement"))
    fields.point_data.push_back({"soft_tissue_displacement", posed - skinned, false});
  if (wants("elastic_displacement")) fields.point_data.push_back({"elastic_displacement", scatter(layer_, u), false});
  const bool energy = wants("strain_energy_density");
  if (energy) fields.point_data.push_back({"strain_energy_density", Eigen::MatrixXd(), false});  // filled by the job
  if (!xdmf) {
    add_kappa_fields(fields.point_data, vertex_kappa_, [this](const std::string& name) { return wants(name); });
    if (wants("soft_region")) fields.point_data.push_back({"soft_region", soft_region_, true});
  }
  fields.field_data.push_back({"TimeValue", Eigen::MatrixXd::Constant(1, 1, t), false});
  const std::size_t own_fields = fields.point_data.size();  // the extra ones are in the world frame already
  for (const vtk::Field& f : extra)
    if (wants(f.name)) fields.point_data.push_back(f);
  std::filesystem::path path;
  if (!xdmf) {
    const std::string name = fmt::format("{}_{:06d}.vtp", options_.prefix, index);
    body_series_->add(t, name);
    path = run_->stage(name);
  }
  run_job([this, path, t, posed, own_fields, fields = std::move(fields), R = frame_rotation_, T = frame_translation_,
           deviation = vertex_deviation_, x = energy ? x_state : Eigen::VectorXd()]() mutable {
    if (x.size() > 0) {
      // Only the tets under the skin's vertices (a sixth of the layer's on the coarse mesh), each once.
      const Eigen::VectorXd tet_psi = strain_energy_density(layer_.problem, x, skin_tets_);
      Eigen::VectorXd vertex_psi(static_cast<Eigen::Index>(skin_tet_slot_.size()));
      for (std::size_t k = 0; k < skin_tet_slot_.size(); ++k)
        vertex_psi[static_cast<Eigen::Index>(k)] = tet_psi[skin_tet_slot_[k]];
      for (vtk::Field& f : fields.point_data)
        if (f.name == "strain_energy_density" && f.values.size() == 0) f.values = scatter(layer_, vertex_psi);
    }
    if (deviation) deviate(*deviation, posed, fields.point_data, own_fields);
    if (!R.isIdentity(0.0) || !T.isZero(0.0)) {
      for (std::size_t k = 0; k < own_fields; ++k) {
        vtk::Field& f = fields.point_data[k];
        if (f.values.cols() == 3 && !f.integer) f.values = (f.values * R.transpose()).eval();
      }
      posed = (posed * R.transpose()).rowwise() + T.transpose();
    }
    // Normals of the placed posed surface: the vtk writer adds them (Float32), an xdmf series gets them here.
    fields.normals = wants("Normals");
    if (body_xdmf_ && fields.normals)
      fields.point_data.push_back({"Normals", vtk::vertex_normals(posed, layer_.model->faces), false});
    if (body_xdmf_)
      body_xdmf_->write(t, posed, fields);
    else
      vtk::write_surface(path, posed, layer_.model->faces, fields, options_.compression);
  });
  if (write_layer_ && state) write_layer_frame(index, t, *state);
  previous_posed_ = std::move(posed);
  previous_t_ = t;
}

void SimulationWriter::write_layer_frame(int index, double t, const State& state) {
  const Problem& problem = layer_.problem;
  NodeFrame frame;
  problem.frame(t, frame);
  RowMatrixX3d nodes = posed_positions(frame, state.x);
  std::filesystem::path path;
  if (!layer_xdmf_) {
    const std::string name = options_.prefix == "body" ? fmt::format("layer_{:06d}.vtu", index)
                                                       : fmt::format("{}_layer_{:06d}.vtu", options_.prefix, index);
    layer_series_->add(t, name);
    path = run_->stage(name);
  }
  run_job([this, &problem, path, t, nodes = std::move(nodes), x = Eigen::VectorXd(state.x),
           w = Eigen::VectorXd(state.w), R = frame_rotation_, T = frame_translation_,
           deviation = node_deviation_]() mutable {
    const Eigen::Map<const RowMatrixX3d> elastic(x.data(), problem.num_nodes(), 3);
    const Eigen::Map<const RowMatrixX3d> velocity(w.data(), problem.num_nodes(), 3);
    vtk::Fields fields;
    if (wants("displacement")) fields.point_data.push_back({"displacement", nodes - problem.rest, false});
    if (wants("elastic_displacement"))
      fields.point_data.push_back({"elastic_displacement", elastic - problem.rest, false});
    if (wants("velocity")) fields.point_data.push_back({"velocity", velocity, false});
    if (deviation) deviate(*deviation, nodes, fields.point_data, fields.point_data.size());
    if (!R.isIdentity(0.0) || !T.isZero(0.0)) {  // as the body frames: vectors turn with the body, positions move
      for (vtk::Field& f : fields.point_data) f.values = (f.values * R.transpose()).eval();
      nodes = (nodes * R.transpose()).rowwise() + T.transpose();
    }
    if (!layer_xdmf_) {  // an xdmf series holds them once
      add_kappa_fields(fields.point_data, layer_.fields.node, [this](const std::string& name) { return wants(name); });
      add_kappa_fields(fields.cell_data, layer_.fields.tet, [this](const std::string& name) { return wants(name); });
    }
    if (wants("strain_energy_density"))
      fields.cell_data.push_back({"strain_energy_density", strain_energy_density(problem, x), false});
    fields.field_data.push_back({"TimeValue", Eigen::MatrixXd::Constant(1, 1, t), false});
    if (layer_xdmf_)
      layer_xdmf_->write(t, nodes, fields);
    else
      vtk::write_unstructured(path, nodes, problem.tets, fields, options_.layer_compression);
  });
}

void SimulationWriter::finish() {
  if (!run_) return;
  if (body_series_) body_series_->write();
  if (layer_series_) layer_series_->write();
  if (body_xdmf_) body_xdmf_->close();
  if (layer_xdmf_) layer_xdmf_->close();
  vtk::Fields fields;
  fields.point_data.push_back({"sigma", scatter(layer_, 1e3 * amplitude_.sigma()), false});
  fields.point_data.push_back({"sigma_normal", scatter(layer_, 1e3 * amplitude_.sigma_normal()), false});
  fields.point_data.push_back({"sigma_tangent", scatter(layer_, 1e3 * amplitude_.sigma_tangent()), false});
  add_kappa_fields(fields.point_data, vertex_kappa_, [](const std::string&) { return true; });
  fields.point_data.push_back({"soft_region", soft_region_, true});
  // Where the body stands (a scene's placement), with the normals of the placed surface.
  vtk::write_surface(run_->stage(dynamics_file()), placed() ? place(layer_.shaped) : layer_.shaped, layer_.model->faces,
                     fields);
}

std::string SimulationWriter::dynamics_file() const {
  return options_.prefix == "body" ? "dynamics.vtp" : options_.prefix + "_dynamics.vtp";
}

void SimulationWriter::set_frame_deviation(std::vector<Eigen::Matrix<double, 3, 4>> vertex,
                                           std::vector<Eigen::Matrix<double, 3, 4>> node) {
  vertex_deviation_ =
      vertex.empty() ? nullptr : std::make_shared<const std::vector<Eigen::Matrix<double, 3, 4>>>(std::move(vertex));
  node_deviation_ =
      node.empty() ? nullptr : std::make_shared<const std::vector<Eigen::Matrix<double, 3, 4>>>(std::move(node));
}

void SimulationWriter::set_frame_placement(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) {
  frame_rotation_ = rotation;
  frame_translation_ = translation;
}

bool SimulationWriter::placed() const {
  return !options_.rotation.isIdentity(0.0) || !options_.translation.isZero(0.0);
}

RowMatrixX3d SimulationWriter::place(const RowMatrixX3d& points) const {
  return (points * options_.rotation.transpose()).rowwise() + options_.translation.transpose();
}

nlohmann::json SimulationWriter::dynamics_summary() const {
  const Eigen::VectorXd s = 1e3 * amplitude_.sigma();
  const Eigen::VectorXd sn = 1e3 * amplitude_.sigma_normal(), st = 1e3 * amplitude_.sigma_tangent();
  const bool any = s.size() > 0;
  return {{"frames", amplitude_.frames()},
          {"region_vertices", s.size()},
          {"sigma_mean_mm", any ? s.mean() : 0.0},
          {"sigma_median_mm", median(s)},
          {"sigma_max_mm", any ? s.maxCoeff() : 0.0},
          {"sigma_normal_mean_mm", any ? sn.mean() : 0.0},
          {"sigma_tangent_mean_mm", any ? st.mean() : 0.0}};
}

Eigen::VectorXd SimulationWriter::sigma_per_vertex() const { return scatter(layer_, amplitude_.sigma()); }
Eigen::VectorXd SimulationWriter::sigma_normal_per_vertex() const { return scatter(layer_, amplitude_.sigma_normal()); }
Eigen::VectorXd SimulationWriter::sigma_tangent_per_vertex() const {
  return scatter(layer_, amplitude_.sigma_tangent());
}

}  // namespace sflsh::model
