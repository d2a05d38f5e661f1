// The dynamics metric of registrations (`sflsh metrics`, docs/validate.md) and DYNA files (docs/physics.md §3.2):
// metrics() fits pose (and β) per frame to a T × n × 3 registration array and returns σ, σ_n, σ_t per vertex;
// read_dyna / write_dyna move registrations between HDF5 files in the DYNA layout and NumPy arrays (T × V × 3).
#include "bind_common.hpp"

#include <sflsh/body/subject_selection.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/validate/dyna_file.hpp>
#include <sflsh/validate/registration_metrics.hpp>

#include <pybind11/stl.h>

#include <optional>

namespace sflsh::python {

namespace {

/// T frames of V × 3 from a (T, V, 3) array.
std::vector<body::RowMatrixX3d> frames_from(const DoubleArray& a, const char* what) {
  require(a.ndim() == 3 && a.shape(2) == 3, "{}: expected an array of shape (T, V, 3), got {} dimensions", what,
          a.ndim());
  std::vector<body::RowMatrixX3d> frames(static_cast<std::size_t>(a.shape(0)));
  const py::ssize_t v = a.shape(1);
  for (py::ssize_t t = 0; t < a.shape(0); ++t)
    frames[static_cast<std::size_t>(t)] = Eigen::Map<const body::RowMatrixX3d>(a.data() + t * v * 3, v, 3);
  return frames;
}

/// (T, V, 3) array of T frames, written straight into a new array.
py::array frames_to(const std::vector<body::RowMatrixX3d>& frames) {
  const auto t = static_cast<py::ssize_t>(frames.size());
  const py::ssize_t v = frames.empty() ? 0 : frames.front().rows();
  py::array_t<double> out({t, v, py::ssize_t{3}});
  for (py::ssize_t k = 0; k < t; ++k)
    Eigen::Map<body::RowMatrixX3d>(out.mutable_data() + k * v * 3, v, 3) = frames[static_cast<std::size_t>(k)];
  return out;
}

py::dict metrics(const DoubleArray& vertices, const py::object& faces, const py::object& betas, double fps,
                 const py::object& body, double soft_weight, const std::string& pose_weights) {
  require(soft_weight >= 0.0 && soft_weight <= 1.0, "metrics: --soft-weight must be in [0, 1], got {}", soft_weight);
  require(fps >= validate::kMinDynaFps && fps <= validate::kMaxDynaFps, "metrics: fps: {} Hz is outside [{}, {}] Hz",
          fps, validate::kMinDynaFps, validate::kMaxDynaFps);
  body::SubjectSelection selection;
  selection.body_path = body_path_from(body);
  const body::BodyModel model = body::load_selected_body(selection);
  const std::vector<body::RowMatrixX3d> frames = frames_from(vertices, "vertices");
  require(vertices.shape(1) == model.num_vertices(), "vertices: {} vertices per frame, the body model '{}' has {}",
          vertices.shape(1), model.name, model.num_vertices());
  if (!faces.is_none()) {
    const IntArray f = IntArray::ensure(faces);
    require(f && f.ndim() == 2 && f.shape(1) == 3, "faces: expected an array of shape (F, 3)");
    require(
        f.shape(0) == model.num_faces() && Eigen::Map<const body::RowMatrixX3i>(f.data(), f.shape(0), 3) == model.faces,
        "faces: the registration's triangles are not the body model '{}''s ({} faces); registrations must be in the "
        "body's topology",
        model.name, model.num_faces());
  }
  std::optional<body::Betas> beta;
  if (!betas.is_none()) beta = betas_from(betas);
  validate::PoseFitOptions options;
  options.soft_weight = soft_weight;
  options.weighting = validate::parse_weighting(pose_weights);
  validate::RegistrationMetrics result;
  {
    py::gil_scoped_release release;
    result = validate::registration_metrics(model, frames, fps, beta, options);
  }
  const validate::DynamicsResult& d = result.dynamics;
  py::dict out;
  out["sigma"] = own(Eigen::VectorXd(d.sigma));
  out["sigma_normal"] = own(Eigen::VectorXd(d.sigma_normal));
  out["sigma_tangent"] = own(Eigen::VectorXd(d.sigma_tangent));
  out["soft_vertices"] = d.soft_vertices;
  out["mean_sigma_soft"] = d.mean_sigma_soft();
  out["beta"] = own(Eigen::VectorXd(result.fit.beta));
  out["beta_fitted"] = result.fit.beta_fitted;
  Eigen::Matrix<double, Eigen::Dynamic, 72, Eigen::RowMajor> poses(
      static_cast<Eigen::Index>(result.fit.motion.num_frames()), 72);
  body::RowMatrixX3d trans(static_cast<Eigen::Index>(result.fit.motion.num_frames()), 3);
  for (std::size_t t = 0; t < result.fit.motion.num_frames(); ++t) {
    poses.row(static_cast<Eigen::Index>(t)) = result.fit.motion.poses[t].transpose();
    trans.row(static_cast<Eigen::Index>(t)) = result.fit.motion.trans[t].transpose();
  }
  out["poses"] = own(std::move(poses));
  out["trans"] = own(std::move(trans));
  out["fit_mean_rms"] = result.fit.mean_rms;
  out["fit_max_rms"] = result.fit.max_rms;
  return out;
}

py::dict read_dyna(const py::object& path, const std::optional<std::string>& key, int frames) {
  require(frames >= 0, "metrics: --frames must be non-negative, got {}", frames);
  const validate::DynaFile file(py::str(path).cast<std::string>());
  py::dict out;
  out["faces"] = own(body::RowMatrixX3i(file.faces()));
  py::dict sequences, rates;
  const std::vector<std::string> keys = key ? std::vector<std::string>{*key} : file.keys();
  for (const std::string& k : keys) {
    validate::DynaSequence s;
    {
      py::gil_scoped_release release;
      s = file.read(k, frames);
    }
    sequences[py::str(k)] = frames_to(s.frames);
    rates[py::str(k)] = s.fps;
  }
  out["sequences"] = sequences;
  out["fps"] = rates;
  return out;
}

void write_dyna(const py::object& path, const IntArray& faces, const py::dict& sequences, double fps) {
  require(faces.ndim() == 2 && faces.shape(1) == 3, "faces: expected an array of shape (F, 3)");
  const body::RowMatrixX3i f = Eigen::Map<const body::RowMatrixX3i>(faces.data(), faces.shape(0), 3);
  std::vector<validate::DynaSequence> out;
  for (const auto& [key, value] : sequences) {
    validate::DynaSequence s;
    s.key = py::str(key).cast<std::string>();
    s.frames = frames_from(DoubleArray::ensure(value), s.key.c_str());
    s.fps = fps;
    out.push_back(std::move(s));
  }
  py::gil_scoped_release release;
  validate::write_dyna_file(py::str(path).cast<std::string>(), f, out);
}

}  // namespace

void bind_metrics(py::module_& m) {
  m.def(
      "metrics", &metrics, py::arg("vertices"), py::arg("faces") = py::none(), py::arg("betas") = py::none(),
      py::kw_only(), py::arg("fps") = validate::kDynaFps, py::arg("body") = py::none(), py::arg("soft_weight") = 0.05,
      py::arg("pose_weights") = "rigidity",
      "The DYNA metric of registrations (T × n × 3, the body's vertex order) as `sflsh metrics`: fits pose (and β when "
      "betas is None) per frame (pose_weights 'rigidity', or 'soft_weight' for the earlier fit with soft_weight on the "
      "soft region) and returns a dict with sigma, sigma_normal, sigma_tangent per vertex [m], beta, "
      "poses, trans and the fit's RMS");
  m.def("read_dyna", &read_dyna, py::arg("path"), py::arg("key") = py::none(), py::arg("frames") = 0,
        "Reads a DYNA HDF5 file: {'faces': F × 3, 'sequences': {key: T × V × 3}, 'fps': {key: Hz}} (one key, or all; "
        "frames > 0 reads only the first frames)");
  m.def("write_dyna", &write_dyna, py::arg("path"), py::arg("faces"), py::arg("sequences"), py::kw_only(),
        py::arg("fps") = validate::kDynaFps,
        "Writes a DYNA HDF5 file (atomically): faces F × 3 and {key '<subject>_<sequence>': T × V × 3 [m]}");
}

}  // namespace sflsh::python
