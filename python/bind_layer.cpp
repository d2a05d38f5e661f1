// sflsh.Layer: a subject's soft-tissue layer as `sflsh mesh` builds it (docs/meshing.md): the cached template tet
// mesh of the region retargeted to the subject's β and a uniform thickness fraction. Node and tet arrays are
// read-only views of the layer the object keeps.
#include "bind_common.hpp"

#include <sflsh/body/subject_selection.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/meshing/region.hpp>
#include <sflsh/meshing/retarget.hpp>
#include <sflsh/meshing/subject_layer.hpp>
#include <sflsh/meshing/tet_backend.hpp>

#include <pybind11/stl.h>

#include <memory>
#include <optional>

namespace sflsh::python {

namespace {

struct PyLayer {
  body::BodyModel model;
  std::string subject;
  body::Betas beta = body::Betas::Zero();
  double thickness = 0.5;
  meshing::LayerMesh mesh;
  meshing::RetargetedLayer layer;
  std::string cache_outcome;
};

template <class Enum>
Eigen::VectorXi as_ints(const std::vector<Enum>& values) {
  Eigen::VectorXi out(static_cast<Eigen::Index>(values.size()));
  for (std::size_t i = 0; i < values.size(); ++i) out(static_cast<Eigen::Index>(i)) = static_cast<int>(values[i]);
  return out;
}

std::shared_ptr<PyLayer> make_layer(const std::optional<std::string>& subject, const py::object& betas,
                                    const py::object& body, double thickness, const std::string& mesher,
                                    const std::string& mesh, const std::string& region,
                                    const std::optional<std::string>& cache, bool rebuild_cache) {
  require(thickness > 0.0 && thickness < 1.0, "--thickness {}: expected a fraction 0 < h < 1", thickness);
  require(!(subject && !betas.is_none()), "--subject and --betas exclude each other");
  body::SubjectSelection selection;
  selection.body_path = body_path_from(body);
  if (subject) selection.subject = *subject;
  if (!betas.is_none()) selection.beta_values = betas_from(betas);
  auto out = std::make_shared<PyLayer>();
  out->model = body::load_selected_body(selection);
  out->beta = body::selected_betas(selection, out->subject);
  out->thickness = thickness;
  meshing::LayerMeshOptions options;
  options.region_names = meshing::parse_region_names(region);
  options.mesher = meshing::parse_mesher(mesher);
  options.size = meshing::parse_size_preset(mesh);
  const std::filesystem::path cache_dir = cache ? std::filesystem::path(*cache) : meshing::default_cache_dir();
  py::gil_scoped_release release;
  meshing::CacheOutcome outcome{};
  meshing::LayerMesh template_mesh =
      meshing::cached_layer_mesh(out->model, options, cache_dir, rebuild_cache, &outcome);
  out->cache_outcome = meshing::cache_outcome_name(outcome);
  // The template retargeted, or the subject's own layer where that inverts tets (meshing/subject_layer.hpp).
  const Eigen::VectorXd field = Eigen::VectorXd::Constant(template_mesh.region_surface.num_vertices(), thickness);
  meshing::SubjectLayer own =
      meshing::subject_layer(out->model, std::move(template_mesh), out->beta, field, options, cache_dir);
  out->mesh = *own.mesh;
  out->layer = std::move(own.layer);
  return out;
}

}  // namespace

void bind_layer(py::module_& m) {
  py::class_<PyLayer, std::shared_ptr<PyLayer>>(
      m, "Layer", "A subject's soft-tissue tet layer (torso, upper arms, thighs) as `sflsh mesh` builds it")
      .def(py::init(&make_layer), py::kw_only(), py::arg("subject") = py::none(), py::arg("betas") = py::none(),
           py::arg("body") = py::none(), py::arg("thickness") = 0.5, py::arg("mesher") = "cgal",
           py::arg("mesh") = "default", py::arg("region") = "torso,upper_arms,thighs", py::arg("cache") = py::none(),
           py::arg("rebuild_cache") = false,
           "Options as `sflsh mesh`: subject (a name of sflsh.subjects()) or betas (up to 10 numbers; neither: β = 0), "
           "body (None: the open body, a path or a sflsh.Body), thickness (the layer's thickness as a fraction of the "
           "skin-to-skeleton distance, 0 < h < 1), mesher 'cgal' | 'gmsh' | 'layered', mesh 'coarse' | 'default' | "
           "'fine', region (comma-separated parts), cache (the template-mesh cache folder; None: $SFLSH_CACHE or "
           "~/.cache/sflsh), rebuild_cache")
      .def_readonly("subject", &PyLayer::subject, "The subject's name, or 'custom' for betas")
      .def_readonly("thickness", &PyLayer::thickness, "Thickness fraction h of the skin-to-skeleton distance (1)")
      .def_readonly("cache_outcome", &PyLayer::cache_outcome,
                    "How the template mesh was had: read from the cache, built, or rebuilt")
      .def_property_readonly(
          "beta", [](const PyLayer& l) { return own(Eigen::VectorXd(l.beta)); }, "The subject's shape β (10,)")
      .def_property_readonly(
          "mesher", [](const PyLayer& l) { return std::string(meshing::mesher_name(l.mesh.mesher)); },
          "The mesher of the template: cgal | gmsh | layered")
      .def_property_readonly(
          "mesh", [](const PyLayer& l) { return std::string(meshing::size_preset_name(l.mesh.size)); },
          "The resolution: coarse | default | fine")
      .def_property_readonly(
          "nodes", [](py::object self) { return view(self.cast<PyLayer&>().layer.nodes, self); },
          "N × 3 node positions for (β, h), unposed [m] (read-only view)")
      .def_property_readonly(
          "template_nodes", [](py::object self) { return view(self.cast<PyLayer&>().mesh.nodes, self); },
          "N × 3 template node positions (β = 0, h = 0.5) [m] (read-only view)")
      .def_property_readonly(
          "tets", [](py::object self) { return view(self.cast<PyLayer&>().mesh.tets, self); },
          "K × 4 node indices, positively oriented (int32, read-only view)")
      .def_property_readonly(
          "node_parts", [](const PyLayer& l) { return own(as_ints(l.mesh.node_part)); },
          "part per node: 0 torso, 1 left upper arm, 2 right upper arm, 3 left thigh, 4 right thigh")
      .def_property_readonly(
          "tet_parts", [](const PyLayer& l) { return own(as_ints(l.mesh.tet_part)); }, "part per tet")
      .def_property_readonly(
          "node_kinds", [](const PyLayer& l) { return own(as_ints(l.mesh.kind)); },
          "kind per node: 0 interior, 1 outer (skin), 2 inner (on the bones), 3 side wall")
      .def_property_readonly(
          "region_vertices",
          [](const PyLayer& l) {
            return own(
                Eigen::Map<const Eigen::VectorXi>(l.mesh.region_surface.vertices.data(),
                                                  static_cast<Eigen::Index>(l.mesh.region_surface.vertices.size()))
                    .eval());
          },
          "R body-vertex indices of the region's skin vertices (ascending)")
      .def_property_readonly(
          "skin_map",
          [](const PyLayer& l) {
            const meshing::SkinEmbedding& s = l.mesh.skin;
            const auto r = static_cast<Eigen::Index>(s.tet.size());
            Eigen::VectorXi node(r), tet(r);
            Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> bary(r, 4);
            for (Eigen::Index i = 0; i < r; ++i) {
              const auto k = static_cast<std::size_t>(i);
              node(i) = s.node.empty() ? -1 : s.node[k];
              tet(i) = s.tet[k];
              bary.row(i) = s.bary[k].transpose();
            }
            py::dict out;
            out["node"] = own(std::move(node));
            out["tet"] = own(std::move(tet));
            out["bary"] = own(std::move(bary));
            return out;
          },
          "The skin map: per region vertex its mesh node (or −1), its tet and barycentric coordinates (R × 4): "
          "skin = Σ bary · nodes[tets[tet]]")
      .def(
          "skin_positions",
          [](const PyLayer& l, const py::object& nodes) {
            if (nodes.is_none()) return own(l.mesh.skin_positions(l.layer.nodes));
            return own(l.mesh.skin_positions(rows3_from(DoubleArray::ensure(nodes), "nodes")));
          },
          py::arg("nodes") = py::none(), "Skin positions (R × 3) read from node positions through the skin map")
      .def_property_readonly(
          "quality",
          [](const PyLayer& l) {
            const meshing::QualityReport& q = l.layer.quality;
            py::dict out;
            out["nodes"] = l.mesh.num_nodes();
            out["tets"] = l.mesh.num_tets();
            out["min_dihedral_deg"] = q.min_dihedral_deg;
            out["max_radius_edge"] = q.max_radius_edge;
            out["inverted"] = q.inverted;
            return out;
          },
          "The retargeted layer's quality: nodes, tets, min_dihedral_deg [deg], max_radius_edge (1), inverted tets")
      .def("__repr__", [](const PyLayer& l) {
        return "<sflsh.Layer '" + l.subject + "': " + std::to_string(l.mesh.num_nodes()) + " nodes, " +
               std::to_string(l.mesh.num_tets()) + " tets>";
      });
}

}  // namespace sflsh::python
