// A soft body's contact in a scene (scene_contact.hpp).
#include "contact/scene_contact.hpp"

#include "objects/coupled_objects.hpp"

#include <algorithm>
#include <limits>
#include <map>
#include <string>

namespace sflsh::scene::detail {

std::vector<double> node_areas(const SceneBody& body, const std::vector<int>& nodes) {
  const model::BodyLayer& layer = body.layer();
  const std::vector<double> vertex_area = lumped_vertex_areas(layer.rest_skin, layer.mesh->region_surface.faces);
  std::map<int, double> area;
  double sum = 0.0;
  for (std::size_t r = 0; r < vertex_area.size(); ++r) {
    sum += vertex_area[r];
    const int node = layer.mesh->skin.node[r];
    if (node >= 0) area[node] += vertex_area[r];
  }
  const double mean = vertex_area.empty() ? 2.25e-4 : sum / static_cast<double>(vertex_area.size());
  std::vector<double> out;
  for (int node : nodes) {
    const auto it = area.find(node);
    out.push_back(it == area.end() ? mean : it->second);
  }
  return out;
}

ContactParameters contact_parameters(const ContactSpec& spec) {
  ContactParameters p;
  if (spec.stiffness > 0.0) p.stiffness = spec.stiffness;
  p.tolerance = spec.tolerance;
  p.margin = spec.margin;
  p.max_refinements = spec.max_refinements;
  p.validate();
  return p;
}

double deepest(const RowMatrixX3d& points, const std::vector<const Obstacle*>& shapes) {
  double d = 0.0;
  for (const Obstacle* shape : shapes)
    for (Eigen::Index i = 0; i < points.rows(); ++i) d = std::max(d, -shape->distance(points.row(i).transpose()));
  return d;
}

std::vector<vtk::Field> contact_fields(const BodyContact& c, const SceneBody& body) {
  if (!c.objects && !c.bodies) return {};
  const auto n = static_cast<Eigen::Index>(body.model().num_vertices());
  Eigen::MatrixXd force = Eigen::MatrixXd::Zero(n, 3), depth = Eigen::MatrixXd::Zero(n, 1);
  for (Eigen::Index v = 0; v < n; ++v) {
    const int node = body.vertex_node()[static_cast<std::size_t>(v)];
    if (node < 0) continue;
    const int k = c.entry_of_node[static_cast<std::size_t>(node)];
    if (k < 0) continue;
    for (const ContactPotential* p : {c.objects.get(), c.bodies.get()}) {
      if (!p) continue;
      force.row(v) += p->contact_force().row(k) * body.placement().R.transpose();
      depth(v, 0) = std::max(depth(v, 0), p->penetration()[k]);
    }
    if (c.coupled) {  // entries of the object potential are the coupled objects' nodes too
      force.row(v) += (body.placement().R * c.coupled->node_force(k)).transpose();
      depth(v, 0) = std::max(depth(v, 0), c.coupled->node_penetration(k));
    }
  }
  return {{"contact_force", force, false}, {"penetration", depth, false}};
}

nlohmann::json contact_summary(const BodyContact& c, ContactTally& tally) {
  nlohmann::json contact = nlohmann::json::object();
  for (const auto& [label, p] : {std::pair{"objects", c.objects.get()}, std::pair{"bodies", c.bodies.get()}}) {
    if (!p) continue;
    ++tally.potentials;
    const ContactStats st = p->stats();
    const bool objects = std::string(label) == "objects";
    contact[label] = {{"broad_phase_passes", st.broad_phase_passes},
                      {"candidates", st.candidates},
                      {"narrow_phase_evaluations", st.narrow_phase_evaluations},
                      {"refinements", st.refinements},
                      {"unresolved", st.unresolved},
                      {"max_penetration_mm", 1e3 * st.max_penetration},
                      {"max_force_n", st.max_force},
                      {"max_force_time_s", st.max_force_time},
                      {"seconds", st.seconds}};
    if (objects && c.dent.near_vertices > 0) {
      contact[label]["dent_mm"] = 1e3 * c.dent.dent;
      contact[label]["spread_mm"] = 1e3 * c.dent.spread;
      contact[label]["dent_time_s"] = c.dent.time;
    }
    (objects ? tally.object_seconds : tally.body_seconds) += st.seconds;
    tally.total.broad_phase_passes += st.broad_phase_passes;
    tally.total.narrow_phase_evaluations += st.narrow_phase_evaluations;
    tally.total.max_penetration = std::max(tally.total.max_penetration, st.max_penetration);
  }
  tally.body_seconds += c.surface_seconds;
  if (!contact.empty()) contact["measured_max_penetration_mm"] = 1e3 * c.max_penetration;
  return contact;
}

void record_dent(const SceneBody& body, BodyContact& contact, double t) {
  if (!contact.objects || contact.objects->obstacles().empty()) return;
  const ContactStats stats = contact.objects->stats();
  if (!(stats.max_force > contact.dent.force)) return;
  const model::BodyLayer& layer = body.layer();
  const RowMatrixX3d posed = layer.posed_surface(body.positions(), t);
  const Eigen::VectorXd rest = Eigen::Map<const Eigen::VectorXd>(layer.problem.rest.data(), layer.problem.num_dofs());
  const RowMatrixX3d skinned = layer.posed_surface(rest, t);
  Dent d;
  d.force = stats.max_force;
  d.time = t;
  double near_sum = 0.0, far_sum = 0.0;
  for (Eigen::Index v = 0; v < posed.rows(); ++v) {
    double phi = std::numeric_limits<double>::infinity();
    for (const ContactObstacle& o : contact.objects->obstacles())
      phi = std::min(phi, o.shape->distance(posed.row(v).transpose()));
    const double u = (posed.row(v) - skinned.row(v)).norm();
    if (phi < 0.10) {
      near_sum += u;
      ++d.near_vertices;
    } else if (phi < 0.20) {
      far_sum += u;
      ++d.far_vertices;
    }
  }
  d.dent = d.near_vertices > 0 ? near_sum / d.near_vertices : 0.0;
  d.spread = d.far_vertices > 0 ? far_sum / d.far_vertices : 0.0;
  contact.dent = d;
}

}  // namespace sflsh::scene::detail
