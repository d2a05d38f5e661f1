// sflsh.Body, sflsh.Motion, subjects and motions: the parametric body in SMPL's layout (docs/physics.md §3.1)
// as `sflsh body` and `sflsh motion` see it. Arrays the body keeps are read-only views; posed vertices are new
// arrays that own their memory.
#include "bind_common.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/subject_selection.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>

#include <pybind11/stl.h>

#include <memory>
#include <optional>

namespace sflsh::python {

namespace {

/// A body model and the path it was read from ("" for the open body).
struct PyBody {
  std::string path;
  body::BodyModel model;
};

/// Poses (72) or (T, 72), translations (3) or (T, 3) or None: T frames of θ and trans.
struct Frames {
  std::vector<body::Pose> poses;
  std::vector<Eigen::Vector3d> trans;
  bool batched = false;
};

Frames frames_from(const DoubleArray& poses, const py::object& trans) {
  Frames f;
  require(poses.ndim() == 1 || poses.ndim() == 2, "poses: expected shape (72,) or (T, 72), got {} dimensions",
          poses.ndim());
  f.batched = poses.ndim() == 2;
  const py::ssize_t frames = f.batched ? poses.shape(0) : 1;
  const py::ssize_t width = poses.shape(poses.ndim() - 1);
  require(width == 3 * body::kNumJoints, "poses: {} values per frame, expected {} (24 joints × axis-angle)", width,
          3 * body::kNumJoints);
  f.poses.resize(static_cast<std::size_t>(frames));
  for (py::ssize_t t = 0; t < frames; ++t)
    f.poses[static_cast<std::size_t>(t)] = Eigen::Map<const body::Pose>(poses.data() + t * width);
  f.trans.assign(static_cast<std::size_t>(frames), Eigen::Vector3d::Zero());
  if (!trans.is_none()) {
    const DoubleArray tr = DoubleArray::ensure(trans);
    require(tr && tr.size() == 3 * frames && tr.shape(tr.ndim() - 1) == 3,
            "trans: expected shape {} to go with the poses", f.batched ? "(T, 3)" : "(3,)");
    for (py::ssize_t t = 0; t < frames; ++t)
      f.trans[static_cast<std::size_t>(t)] = Eigen::Map<const Eigen::Vector3d>(tr.data() + 3 * t);
  }
  return f;
}

Eigen::Matrix3d rotation_from(const py::object& world_from_body) {
  if (world_from_body.is_none()) return Eigen::Matrix3d::Identity();
  const DoubleArray r = DoubleArray::ensure(world_from_body);
  require(r && r.ndim() == 2 && r.shape(0) == 3 && r.shape(1) == 3, "world_from_body: expected a 3 × 3 rotation");
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(r.data());
}

/// Posed vertices (n × 3 or T × n × 3) or posed joints (24 × 3 or T × 24 × 3), written straight into the result.
py::array pose_frames(const PyBody& b, const py::object& betas, const DoubleArray& poses, const py::object& trans,
                      const py::object& world_from_body, bool joints) {
  const body::Betas beta = betas_from(betas);
  const Frames f = frames_from(poses, trans);
  const Eigen::Matrix3d rotation = rotation_from(world_from_body);
  const py::ssize_t rows = joints ? body::kNumJoints : static_cast<py::ssize_t>(b.model.num_vertices());
  const auto frames = static_cast<py::ssize_t>(f.poses.size());
  py::array_t<double> out =
      f.batched ? py::array_t<double>({frames, rows, py::ssize_t{3}}) : py::array_t<double>({rows, py::ssize_t{3}});
  double* data = out.mutable_data();
  {
    py::gil_scoped_release release;
    const body::Poser poser(b.model, beta);
    for (py::ssize_t t = 0; t < frames; ++t) {
      const auto k = static_cast<std::size_t>(t);
      Eigen::Map<body::RowMatrixX3d> target(data + t * rows * 3, rows, 3);
      // The same products as `sflsh motion export`: posed = poser.pose(θ, trans) · R_wbᵀ.
      if (joints)
        target = (poser.pose_joints(f.poses[k], f.trans[k]) * rotation.transpose()).eval();
      else
        target = (poser.pose(f.poses[k], f.trans[k]) * rotation.transpose()).eval();
    }
  }
  return out;
}

py::array pose_array(const std::vector<body::Pose>& poses, py::handle owner) {
  // std::vector<Pose> stores the 72 values of each frame contiguously, frame after frame.
  const auto s = static_cast<py::ssize_t>(sizeof(double));
  return view(poses.empty() ? nullptr : poses.front().data(), {static_cast<py::ssize_t>(poses.size()), py::ssize_t{72}},
              {s * 72, s}, owner);
}

/// sflsh.Body's class object: a body model and the path it was read from.
using PyBodyClass = py::class_<PyBody, std::shared_ptr<PyBody>>;

/// sflsh.Body's constructor and its read-only properties: names, sizes and the model's arrays.
void bind_body_properties(PyBodyClass& c) {
  c.def(py::init([](const py::object& path) {
          body::SubjectSelection selection;
          if (!path.is_none()) selection.body_path = py::str(path).cast<std::string>();  // str or os.PathLike
          auto b = std::make_shared<PyBody>();
          b->path = selection.body_path;
          b->model = body::load_selected_body(selection);
          return b;
        }),
        py::arg("path") = py::none(), "Loads a body .npz (default: data/open_body.npz); errors as `--body PATH`")
      .def_property_readonly(
          "name", [](const PyBody& b) { return b.model.name; }, "The body model's name ('open_body' for the open body)")
      .def_property_readonly(
          "path", [](const PyBody& b) { return b.path.empty() ? body::default_body_path().string() : b.path; },
          "The .npz file it was loaded from")
      .def_property_readonly("_selection_path", [](const PyBody& b) { return b.path; })
      .def_property_readonly(
          "num_vertices", [](const PyBody& b) { return b.model.num_vertices(); }, "Vertices n of the surface")
      .def_property_readonly(
          "num_faces", [](const PyBody& b) { return b.model.num_faces(); }, "Triangles m of the surface")
      .def_property_readonly(
          "v_template", [](py::object self) { return view(self.cast<PyBody&>().model.v_template, self); },
          "n × 3 rest template [m] (read-only view)")
      .def_property_readonly(
          "faces", [](py::object self) { return view(self.cast<PyBody&>().model.faces, self); },
          "m × 3 vertex indices (int32, read-only view)")
      .def_property_readonly(
          "weights", [](py::object self) { return view(self.cast<PyBody&>().model.weights, self); },
          "n × 24 skinning weights (read-only view; column-major storage)")
      .def_property_readonly(
          "shapedirs",
          [](py::object self) {
            const Eigen::MatrixXd& d = self.cast<PyBody&>().model.shapedirs;  // (3n) × B, column-major, row 3v + c
            const auto s = static_cast<py::ssize_t>(sizeof(double));
            return view(d.data(), {d.rows() / 3, py::ssize_t{3}, d.cols()}, {3 * s, s, s * d.rows()}, self);
          },
          "n × 3 × B shape directions (read-only view)")
      .def_property_readonly(
          "joint_regressor", [](const PyBody& b) { return own(Eigen::MatrixXd(b.model.joint_regressor)); },
          "24 × n joint regressor (a dense copy of the sparse matrix)")
      .def_property_readonly(
          "parents", [](const PyBody& b) { return std::vector<int>(b.model.parents.begin(), b.model.parents.end()); },
          "The parent of each of the 24 joints (-1 for the root; SMPL's kinematic tree)")
      .def_property_readonly_static(
          "joint_names",
          [](py::object) { return std::vector<std::string>(body::kJointNames.begin(), body::kJointNames.end()); },
          "The 24 joint names in SMPL's order");
}

/// sflsh.Body's methods: the shaped template, the rest joints and the posed vertices and joints.
void bind_body_methods(PyBodyClass& c) {
  c.def(
       "shape",
       [](const PyBody& b, const py::object& betas) { return own(body::shaped_template(b.model, betas_from(betas))); },
       py::arg("betas") = py::none(), "T̄ + B_S(β): the shaped rest template (n × 3) [m]")
      .def(
          "joints",
          [](const PyBody& b, const py::object& betas) {
            const body::RowMatrixX3d shaped = body::shaped_template(b.model, betas_from(betas));
            return own(body::RowMatrixX3d(body::regress_joints(b.model, shaped)));
          },
          py::arg("betas") = py::none(), "Rest joints regressed from the shaped template (24 × 3) [m]")
      .def(
          "pose",
          [](const PyBody& b, const py::object& betas, const DoubleArray& poses, const py::object& trans,
             const py::object& r) { return pose_frames(b, betas, poses, trans, r, false); },
          py::arg("betas"), py::arg("poses"), py::arg("trans") = py::none(), py::arg("world_from_body") = py::none(),
          "Posed vertices: poses (72,) → (n, 3), poses (T, 72) → (T, n, 3) [m]; trans (3,) / (T, 3); world_from_body "
          "(a Motion's) rotates the result as `sflsh motion export` does")
      .def(
          "pose_joints",
          [](const PyBody& b, const py::object& betas, const DoubleArray& poses, const py::object& trans,
             const py::object& r) { return pose_frames(b, betas, poses, trans, r, true); },
          py::arg("betas"), py::arg("poses"), py::arg("trans") = py::none(), py::arg("world_from_body") = py::none(),
          "Posed joints: (24, 3) or (T, 24, 3) [m]")
      .def("__repr__", [](const PyBody& b) {
        return "<sflsh.Body '" + b.model.name + "': " + std::to_string(b.model.num_vertices()) + " vertices>";
      });
}

/// sflsh.Body, the parametric body in SMPL's layout.
void bind_body_model_class(py::module_& m) {
  PyBodyClass c(m, "Body",
                "A body model in SMPL's layout: the open body (default) or an SMPL .npz; "
                "Body.joint_names: the 24 joint names in SMPL's order");
  bind_body_properties(c);
  bind_body_methods(c);
}

/// sflsh.subjects(), sflsh.subject() and sflsh.motions(): the shipped subjects and the procedural motions.
void bind_subject_and_motion_lists(py::module_& m) {
  m.def(
      "subjects",
      [] {
        py::dict out;
        for (const body::Subject& s : body::default_subjects()) out[py::str(s.name)] = own(Eigen::VectorXd(s.beta));
        return out;
      },
      "The shipped subjects (data/subjects.toml, data/open_body_subjects.toml): name → β (10,)");
  m.def(
      "subject",
      [](const std::string& name) {
        return own(Eigen::VectorXd(body::find_subject(body::default_subjects(), name).beta));
      },
      py::arg("name"), "β (10,) of a named subject; an unknown name lists the known ones");
  m.def(
      "motions",
      [] {
        std::vector<std::string> names = body::procedural_motion_names();
        for (const std::string& n : body::showcase_motion_names()) names.push_back(n);
        return names;
      },
      "The procedural motions (`sflsh motion list`)");
}

/// sflsh.Motion: poses, root translations and times of a procedural or AMASS motion.
void bind_motion_class(py::module_& m) {
  py::class_<body::Motion, std::shared_ptr<body::Motion>>(m, "Motion",
                                                          "A motion: poses θ (T × 72) and root translations (T × 3)")
      .def(py::init([](const std::string& name_or_path, double fps, int frames, double time_offset) {
             require(fps > 0.0, "--fps must be positive, got {}", fps);
             require(frames >= 0, "--frames must be non-negative, got {}", frames);
             py::gil_scoped_release release;
             auto motion = std::make_shared<body::Motion>(body::load_motion(name_or_path, fps, frames, time_offset));
             motion->validate();
             return motion;
           }),
           py::arg("motion"), py::arg("fps") = 60.0, py::arg("frames") = 0, py::arg("time_offset") = 0.0,
           "A procedural motion by name or an AMASS .npz, sampled at fps (frames 0: its own length)")
      .def_readonly("name", &body::Motion::name, "The motion's name (a procedural name or the file's stem)")
      .def_readonly("source", &body::Motion::source, "'procedural' or the AMASS file it was read from")
      .def_readonly("fps", &body::Motion::fps, "Frame rate [Hz]")
      .def_property_readonly("num_frames", &body::Motion::num_frames, "Frames T")
      .def_property_readonly(
          "poses", [](py::object self) { return pose_array(self.cast<body::Motion&>().poses, self); },
          "T × 72 axis-angle poses (read-only view)")
      .def_property_readonly(
          "trans",
          [](py::object self) {
            const auto& trans = self.cast<body::Motion&>().trans;  // Vector3d per frame, contiguous
            const auto s = static_cast<py::ssize_t>(sizeof(double));
            return view(trans.empty() ? nullptr : trans.front().data(),
                        {static_cast<py::ssize_t>(trans.size()), py::ssize_t{3}}, {3 * s, s}, self);
          },
          "T × 3 root translations [m] (read-only view)")
      .def_property_readonly(
          "world_from_body",
          [](const body::Motion& mo) { return own(Eigen::Matrix<double, 3, 3, Eigen::RowMajor>(mo.world_from_body)); },
          "3 × 3 rotation from the body's frame to the world (AMASS Z-up files: to Y-up)")
      .def_property_readonly(
          "times",
          [](const body::Motion& mo) {
            Eigen::VectorXd t(static_cast<Eigen::Index>(mo.num_frames()));
            for (std::size_t i = 0; i < mo.num_frames(); ++i) t(static_cast<Eigen::Index>(i)) = mo.time(i);
            return own(std::move(t));
          },
          "The frames' times (T) [s]")
      .def(
          "save", [](const body::Motion& mo, const std::string& path) { body::save_amass(path, mo); }, py::arg("path"),
          "Writes the motion as an AMASS .npz (atomically)")
      .def("__repr__", [](const body::Motion& mo) {
        return "<sflsh.Motion '" + mo.name + "': " + std::to_string(mo.num_frames()) + " frames>";
      });
}

}  // namespace

void bind_body(py::module_& m) {
  bind_body_model_class(m);
  bind_subject_and_motion_lists(m);
  bind_motion_class(m);
}

}  // namespace sflsh::python
