#include <sflsh/model/simulation_output.hpp>

#include <sflsh/core/error.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace sflsh::model {

DynamicsAmplitude::DynamicsAmplitude(RowMatrixX3d normals)
    : normals_(std::move(normals)),
      sum_(RowMatrixX3d::Zero(normals_.rows(), 3)),
      sum_sq_(Eigen::VectorXd::Zero(normals_.rows())),
      sum_n_(Eigen::VectorXd::Zero(normals_.rows())),
      sum_sq_n_(Eigen::VectorXd::Zero(normals_.rows())) {}

void DynamicsAmplitude::add(const RowMatrixX3d& u) {
  require(u.rows() == normals_.rows(), "dynamics amplitude: {} displacements for {} vertices", u.rows(), normals_.rows());
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

RowMatrixX3d vertex_normals(const RowMatrixX3d& vertices, const Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>& faces) {
  RowMatrixX3d normals = RowMatrixX3d::Zero(vertices.rows(), 3);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector3d a = vertices.row(faces(f, 0)), b = vertices.row(faces(f, 1)), c = vertices.row(faces(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);   // length = 2 × area: area weighting
    for (int k = 0; k < 3; ++k) normals.row(faces(f, k)) += n.transpose();
  }
  for (Eigen::Index v = 0; v < normals.rows(); ++v) {
    const double len = normals.row(v).norm();
    if (len > 0.0) normals.row(v) /= len;
  }
  return normals;
}

Eigen::VectorXd strain_energy_density(const Problem& problem, const Eigen::VectorXd& x) {
  Eigen::VectorXd psi(problem.num_tets());
  for (int e = 0; e < problem.num_tets(); ++e) {
    material::TetNodes nodes;
    for (int a = 0; a < 4; ++a) nodes.col(a) = x.segment<3>(3 * problem.tets(e, a));
    const auto se = static_cast<std::size_t>(e);
    const double scale = problem.tet_energy_scale.empty() ? 1.0 : problem.tet_energy_scale[se];
    try {
      psi[e] = scale * material::tet_elastic_energy(problem.tet_rest[se], nodes, problem.tet_material[se]) /
               problem.tet_rest[se].volume;
    } catch (const Error&) {
      psi[e] = std::numeric_limits<double>::infinity();
    }
  }
  return psi;
}

}  // namespace sflsh::model

namespace sflsh::model {

namespace {

/// Unit normals of the shaped neutral body at the region's vertices (the σ_n / σ_t split of docs/physics.md §4).
RowMatrixX3d region_normals(const BodyLayer& layer) {
  const RowMatrixX3d all = vertex_normals(layer.shaped, layer.model->faces);
  const std::vector<int>& region = layer.mesh->region_surface.vertices;
  RowMatrixX3d out(static_cast<Eigen::Index>(region.size()), 3);
  for (std::size_t r = 0; r < region.size(); ++r) out.row(static_cast<Eigen::Index>(r)) = all.row(region[r]);
  return out;
}

/// Scatters region rows (R×k) into a body-sized array (n×k), zero elsewhere.
Eigen::MatrixXd scatter(const BodyLayer& layer, const Eigen::MatrixXd& region_values) {
  const std::vector<int>& region = layer.mesh->region_surface.vertices;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(layer.shaped.rows(), region_values.cols());
  for (std::size_t r = 0; r < region.size(); ++r) out.row(region[r]) = region_values.row(static_cast<Eigen::Index>(r));
  return out;
}

void add_kappa_fields(std::vector<vtk::Field>& fields, const Eigen::MatrixXd& kappa) {
  for (int k = 0; k < material::kNumKappa; ++k)
    fields.push_back({std::string(material::kKappaNames[static_cast<std::size_t>(k)]), kappa.col(k), false});
}

double median(Eigen::VectorXd v) {
  if (v.size() == 0) return 0.0;
  std::sort(v.data(), v.data() + v.size());
  const Eigen::Index n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

SimulationWriter::SimulationWriter(const BodyLayer& layer, RunFolder* run, bool write_layer)
    : SimulationWriter(layer, run, SimulationWriterOptions{.write_layer = write_layer}) {}

SimulationWriter::SimulationWriter(const BodyLayer& layer, RunFolder* run, const SimulationWriterOptions& options)
    : layer_(layer), run_(run), options_(options), write_layer_(options.write_layer), amplitude_(region_normals(layer)) {
  const body::BodyModel& model = *layer.model;
  dominant_joint_.resize(model.num_vertices(), 1);
  for (Eigen::Index v = 0; v < model.num_vertices(); ++v) {
    Eigen::Index k;
    model.weights.row(v).maxCoeff(&k);
    dominant_joint_(v) = static_cast<double>(k);
  }
  vertex_kappa_ = scatter(layer, layer.fields.vertex);
  if (run_) {
    body_series_ = std::make_unique<vtk::PvdSeries>(run_->stage(options_.prefix + ".pvd"));
    if (write_layer_)
      layer_series_ = std::make_unique<vtk::PvdSeries>(run_->stage(options_.prefix == "body" ? "layer.pvd" : options_.prefix + "_layer.pvd"));
  }
}

void SimulationWriter::add_frame(double t, const State& state, const std::vector<vtk::Field>& extra) {
  const Problem& problem = layer_.problem;
  require(state.x.allFinite() && state.w.allFinite(), "simulation output: the state at t = {} is not finite", t);
  const RowMatrixX3d u = layer_.surface_displacement(state.x);
  amplitude_.add(u);
  RowMatrixX3d posed = layer_.posed_surface(state.x, t);
  if (run_) {
    const body::BodyModel& model = *layer_.model;
    const Eigen::Map<const Eigen::VectorXd> rest(problem.rest.data(), problem.num_dofs());
    const RowMatrixX3d skinned = layer_.posed_surface(rest, t);
    const Eigen::VectorXd psi = strain_energy_density(problem, state.x);
    const meshing::SkinEmbedding& skin = layer_.mesh->skin;
    Eigen::VectorXd vertex_psi(static_cast<Eigen::Index>(skin.tet.size()));
    for (std::size_t r = 0; r < skin.tet.size(); ++r) vertex_psi[static_cast<Eigen::Index>(r)] = psi[skin.tet[r]];

    vtk::Fields fields;
    fields.point_data.push_back({"displacement", posed - layer_.shaped, false});
    Eigen::MatrixXd velocity = Eigen::MatrixXd::Zero(posed.rows(), 3);
    if (frame_ > 0 && t > previous_t_) velocity = (posed - previous_posed_) / (t - previous_t_);
    fields.point_data.push_back({"velocity", velocity, false});
    fields.point_data.push_back({"skin_weights_argmax", dominant_joint_, true});
    fields.point_data.push_back({"soft_tissue_displacement", posed - skinned, false});
    fields.point_data.push_back({"elastic_displacement", scatter(layer_, u), false});
    fields.point_data.push_back({"strain_energy_density", scatter(layer_, vertex_psi), false});
    add_kappa_fields(fields.point_data, vertex_kappa_);
    fields.field_data.push_back({"TimeValue", Eigen::MatrixXd::Constant(1, 1, t), false});
    const bool placed = !options_.rotation.isIdentity(0.0) || !options_.translation.isZero(0.0);
    if (placed) {
      for (vtk::Field& f : fields.point_data)
        if (f.values.cols() == 3 && !f.integer) f.values = (f.values * options_.rotation.transpose()).eval();
    }
    for (const vtk::Field& f : extra) fields.point_data.push_back(f);
    const std::string name = fmt::format("{}_{:06d}.vtp", options_.prefix, frame_);
    const RowMatrixX3d written = placed ? RowMatrixX3d((posed * options_.rotation.transpose()).rowwise() + options_.translation.transpose()) : posed;
    vtk::write_surface(run_->stage(name), written, model.faces, fields);
    body_series_->add(t, name);

    if (write_layer_) {
      NodeFrame frame;
      problem.frame(t, frame);
      RowMatrixX3d nodes = posed_positions(frame, state.x);
      if (placed) nodes = ((nodes * options_.rotation.transpose()).rowwise() + options_.translation.transpose()).eval();
      const Eigen::Map<const RowMatrixX3d> x(state.x.data(), problem.num_nodes(), 3);
      const Eigen::Map<const RowMatrixX3d> w(state.w.data(), problem.num_nodes(), 3);
      vtk::Fields layer_fields;
      layer_fields.point_data.push_back({"displacement", nodes - problem.rest, false});
      layer_fields.point_data.push_back({"elastic_displacement", x - problem.rest, false});
      layer_fields.point_data.push_back({"velocity", w, false});
      add_kappa_fields(layer_fields.point_data, layer_.fields.node);
      add_kappa_fields(layer_fields.cell_data, layer_.fields.tet);
      layer_fields.cell_data.push_back({"strain_energy_density", psi, false});
      layer_fields.field_data.push_back({"TimeValue", Eigen::MatrixXd::Constant(1, 1, t), false});
      const std::string layer_name =
          options_.prefix == "body" ? fmt::format("layer_{:06d}.vtu", frame_) : fmt::format("{}_layer_{:06d}.vtu", options_.prefix, frame_);
      vtk::write_unstructured(run_->stage(layer_name), nodes, problem.tets, layer_fields);
      layer_series_->add(t, layer_name);
    }
  }
  previous_posed_ = std::move(posed);
  previous_t_ = t;
  ++frame_;
}

void SimulationWriter::finish() {
  if (!run_) return;
  body_series_->write();
  if (layer_series_) layer_series_->write();
  vtk::Fields fields;
  fields.point_data.push_back({"sigma", scatter(layer_, 1e3 * amplitude_.sigma()), false});
  fields.point_data.push_back({"sigma_normal", scatter(layer_, 1e3 * amplitude_.sigma_normal()), false});
  fields.point_data.push_back({"sigma_tangent", scatter(layer_, 1e3 * amplitude_.sigma_tangent()), false});
  add_kappa_fields(fields.point_data, vertex_kappa_);
  vtk::write_surface(run_->stage(options_.prefix == "body" ? "dynamics.vtp" : options_.prefix + "_dynamics.vtp"), layer_.shaped,
                     layer_.model->faces, fields);
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

}  // namespace sflsh::model
