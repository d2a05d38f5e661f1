// sflsh.Material: a subject's heterogeneous material (docs/material_file.md): control points on the body template
// with κ = (thickness h, Y_t [Pa], Y_n [Pa]), read from a material file, made from a shape model for a β
// (reduced::material_for_beta, the shipped data/shape_models/default.toml by default) or given as arrays.
#include "bind_common.hpp"

#include <sflsh/body/subject_selection.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/reduced/shape_model_file.hpp>

#include <pybind11/stl.h>

#include <memory>
#include <optional>

namespace sflsh::python {

namespace {

using Material = material::MaterialFile;

/// material_for_beta for a subject (by name) or β, with the shape model at `shape_model` (None: the shipped one).
std::shared_ptr<Material> from_shape_model(const py::object& betas, const std::optional<std::string>& subject,
                                           const py::object& shape_model, const py::object& body) {
  require(!(subject && !betas.is_none()), "--subject and --betas exclude each other");
  body::SubjectSelection selection;
  selection.body_path = body_path_from(body);
  if (subject) selection.subject = *subject;
  if (!betas.is_none()) selection.beta_values = betas_from(betas);
  const std::filesystem::path path = shape_model.is_none()
                                         ? reduced::default_shape_model_path()
                                         : std::filesystem::path(py::str(shape_model).cast<std::string>());
  const reduced::ShapeModelFile model = reduced::load_shape_model_file(path);
  const body::BodyModel body_model = body::load_selected_body(selection);
  std::string label;
  const body::Betas beta = body::selected_betas(selection, label, "material_for_beta");
  return std::make_shared<Material>(reduced::material_for_beta(model, body_model, beta, subject ? *subject : ""));
}

std::shared_ptr<Material> from_arrays(const IntArray& vertices, const DoubleArray& kappa, const std::string& body_name,
                                      const std::string& subject, double poisson, double saturation) {
  require(vertices.ndim() == 1, "vertices: expected a vector of body vertex indices, got {} dimensions",
          vertices.ndim());
  require(kappa.ndim() == 2 && kappa.shape(1) == 3 && kappa.shape(0) == vertices.shape(0),
          "kappa: expected shape ({}, 3) (thickness, young_tangent [Pa], young_normal [Pa] per control point)",
          vertices.shape(0));
  auto out = std::make_shared<Material>();
  out->body = body_name;
  out->subject = subject;
  out->poisson = poisson;
  out->saturation = saturation;
  for (py::ssize_t i = 0; i < vertices.shape(0); ++i) {
    material::MaterialControlPoint p;
    p.vertex = vertices.data()[i];
    p.kappa.thickness = kappa.data()[3 * i];
    p.kappa.young_tangent = kappa.data()[3 * i + 1];
    p.kappa.young_normal = kappa.data()[3 * i + 2];
    out->control_points.push_back(p);
  }
  material::validate(*out, "material");
  return out;
}

}  // namespace

void bind_material(py::module_& m) {
  py::class_<Material, std::shared_ptr<Material>>(
      m, "Material", "A subject's material: control points with κ = (thickness, young_tangent [Pa], young_normal [Pa])")
      .def(py::init([](const py::object& path) {
             return std::make_shared<Material>(material::load_material_file(py::str(path).cast<std::string>()));
           }),
           py::arg("path"), "Reads a material file (TOML, docs/material_file.md); errors as `--material FILE`")
      .def_static(
          "from_shape_model", &from_shape_model, py::kw_only(), py::arg("betas") = py::none(),
          py::arg("subject") = py::none(), py::arg("shape_model") = py::none(), py::arg("body") = py::none(),
          "κ̂(β) of a shape model (default: data/shape_models/default.toml) for a subject (a name) or β (up to 10 "
          "numbers): thickness fraction (1), young_tangent and young_normal [Pa] per control point")
      .def_static("from_arrays", &from_arrays, py::arg("vertices"), py::arg("kappa"), py::kw_only(),
                  py::arg("body") = "open_body", py::arg("subject") = "custom", py::arg("poisson") = 0.2,
                  py::arg("saturation") = 4.0,
                  "Control points (body vertex indices, N) and their κ (N × 3: thickness fraction (1), young_tangent "
                  "[Pa], young_normal [Pa]), Poisson's ratio (1) and the skin's saturation strain (1)")
      .def_readonly("body", &Material::body, "The body model the control points index ('open_body', …)")
      .def_readonly("subject", &Material::subject, "The subject the material is for")
      .def_readonly("poisson", &Material::poisson, "Poisson's ratio ν (1)")
      .def_readonly("saturation", &Material::saturation, "The Fung skin's saturation strain (1)")
      .def_readonly("source", &Material::source, "Where the material came from (a file, a shape model, arrays)")
      .def_property_readonly(
          "num_control_points", [](const Material& mat) { return mat.control_points.size(); }, "Control points N")
      .def_property_readonly(
          "vertices",
          [](const Material& mat) {
            const std::vector<int> v = mat.vertices();
            return own(Eigen::Map<const Eigen::VectorXi>(v.data(), static_cast<Eigen::Index>(v.size())).eval());
          },
          "control points' body vertex indices")
      .def_property_readonly(
          "kappa",
          [](const Material& mat) {
            return own(Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>(mat.kappa()));
          },
          "N × 3 κ per control point: thickness fraction, young_tangent [Pa], young_normal [Pa]")
      .def(
          "save",
          [](const Material& mat, const py::object& path) {
            material::save_material_file(py::str(path).cast<std::string>(), mat);
          },
          py::arg("path"), "Writes the material file (atomically)")
      .def("__repr__", [](const Material& mat) {
        return "<sflsh.Material '" + mat.subject + "' on '" + mat.body +
               "': " + std::to_string(mat.control_points.size()) + " control points>";
      });
  m.def(
      "material_for_beta",
      [](const py::object& betas, const py::object& shape_model, const py::object& body) {
        return from_shape_model(betas, std::nullopt, shape_model, body);
      },
      py::arg("betas"), py::arg("shape_model") = py::none(), py::arg("body") = py::none(),
      "reduced::material_for_beta: the material a shape model (default: the shipped one) gives β");
}

}  // namespace sflsh::python
