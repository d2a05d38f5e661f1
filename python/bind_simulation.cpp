// sflsh.Simulation: one body along a motion with the reduced model or the full-space solver, stepped from Python
// (scene::BodySimulation, the object `sflsh simulate` runs). Its keyword arguments are simulate's options with
// '-' spelled '_'; step(), run() and sigma() give the posed surface, the soft-tissue displacement and σ, and
// summary() the dictionary `sflsh simulate` writes as summary.json (without the command-line header and "output").
//
// Long calls release the GIL while the solver runs; run() takes the GIL back between frames to check for signals,
// so Ctrl-C raises KeyboardInterrupt at a frame boundary and leaves the simulation at the last finished frame,
// ready to step on.
#include "bind_common.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/petsc_session.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/scene/body_simulation.hpp>

#include <pybind11/stl.h>
#include <pybind11_json/pybind11_json.hpp>

#include <memory>
#include <optional>

namespace sflsh::python {

namespace {

using scene::BodySimulation;

/// PETSc (and MPI) for the full-space solver, started on first use and kept for the life of the process: PETSc
/// objects of simulations still referenced when the interpreter exits must never outlive a PetscFinalize.
void ensure_petsc() {
  static fullspace::PetscSession* session = nullptr;
  if (!session && !fullspace::petsc_initialized()) session = new fullspace::PetscSession();
}

std::unique_ptr<BodySimulation> make_simulation(const py::kwargs& kwargs) {
  scene::BodyRunSettings s;
  s.frames = 0;
  py::object material_arg = py::none();
  py::object betas_arg = py::none();
  for (const auto& [key_handle, value] : kwargs) {
    const std::string key = py::str(key_handle);
    auto text = [&] { return py::str(value).cast<std::string>(); };
    if (key == "subject")
      s.subject.subject = text();
    else if (key == "betas")
      betas_arg = py::reinterpret_borrow<py::object>(value);
    else if (key == "body")
      s.subject.body_path = body_path_from(py::reinterpret_borrow<py::object>(value));
    else if (key == "motion")
      s.motion = text();
    else if (key == "solver")
      s.solver = text();
    else if (key == "frames")
      s.frames = value.cast<int>();
    else if (key == "fps")
      s.fps = value.cast<double>();
    else if (key == "substeps")
      s.substeps = value.cast<int>();
    else if (key == "mesh")
      s.mesh = text();
    else if (key == "mesher")
      s.layer.mesher = text();
    else if (key == "material")
      material_arg = py::reinterpret_borrow<py::object>(value);
    else if (key == "control_points")
      s.layer.control_points = value.cast<int>();
    else if (key == "cache")
      s.layer.cache = text();
    else if (key == "density")
      s.layer.density = value.cast<double>();
    else if (key == "gravity")
      s.layer.gravity = value.cast<bool>();
    else if (key == "stiffness_scale")
      s.layer.stiffness_scale = value.cast<double>();
    else if (key == "mass")
      s.layer.mass = text();
    else if (key == "integrator")
      s.integrator = text();
    else if (key == "handles")
      s.handles = value.cast<int>();
    else if (key == "cubature")
      s.cubature = value.cast<int>();
    else if (key == "cubature_weights")
      s.cubature_weights = text();
    else if (key == "affine")
      s.affine = value.cast<bool>();
    else if (key == "newton_tolerance")
      s.newton_tolerance = value.cast<double>();
    else if (key == "allow_long")
      s.allow_long = value.cast<bool>();
    else
      throw_error(
          "Simulation: unknown option '{}' (expected subject, betas, body, motion, solver, frames, fps, substeps, "
          "mesh, "
          "mesher, material, control_points, cache, density, gravity, stiffness_scale, mass, integrator, handles, "
          "cubature, cubature_weights, affine, newton_tolerance, allow_long)",
          key);
  }
  require(!s.motion.empty(), "simulate: --motion is required (a procedural name or an AMASS .npz path)");
  require(!(!s.subject.subject.empty() && !betas_arg.is_none()), "--subject and --betas exclude each other");
  if (!betas_arg.is_none()) s.subject.beta_values = betas_from(betas_arg);
  if (py::isinstance<material::MaterialFile>(material_arg))
    s.material_data = material_arg.cast<std::shared_ptr<material::MaterialFile>>();
  else if (!material_arg.is_none())
    s.layer.material = py::str(material_arg).cast<std::string>();
  if (s.solver == "full") ensure_petsc();
  py::gil_scoped_release release;
  return std::make_unique<BodySimulation>(s, nullptr, 0, 1, scene::BodyRunReporting{false, false, {}, {}});
}

/// Posed surface and soft-tissue displacement of the current frame into rows [0, n) of two T × n × 3 buffers.
void write_frame(const BodySimulation& sim, double* vertices, double* soft) {
  const body::RowMatrixX3d posed = sim.posed_surface();
  Eigen::Map<body::RowMatrixX3d>(vertices, posed.rows(), 3) = posed;
  Eigen::Map<body::RowMatrixX3d>(soft, posed.rows(), 3) = posed - sim.skinned_surface();
}

py::dict run(BodySimulation& sim, const std::optional<int>& frames) {
  const int remaining = sim.num_frames() - 1 - sim.frame();
  const int count = frames ? *frames : remaining;
  require(count >= 0 && count <= remaining,
          "run: {} frames asked for, {} remain (the motion has {} frames; the simulation is at frame {})", count,
          remaining, sim.num_frames(), sim.frame());
  const auto n = static_cast<py::ssize_t>(sim.body().num_vertices());
  const py::ssize_t rows = count + 1;
  py::array_t<double> vertices({rows, n, py::ssize_t{3}});
  py::array_t<double> soft({rows, n, py::ssize_t{3}});
  py::array_t<int> index(rows);
  py::array_t<double> times(rows);
  double* v = vertices.mutable_data();
  double* d = soft.mutable_data();
  index.mutable_data()[0] = sim.frame();
  times.mutable_data()[0] = sim.time();
  write_frame(sim, v, d);
  for (py::ssize_t k = 1; k < rows; ++k) {
    {
      py::gil_scoped_release release;
      sim.step();
      write_frame(sim, v + k * n * 3, d + k * n * 3);
    }
    index.mutable_data()[k] = sim.frame();
    times.mutable_data()[k] = sim.time();
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // KeyboardInterrupt at a frame boundary
  }
  py::dict out;
  out["vertices"] = vertices;
  out["soft_tissue_displacement"] = soft;
  out["frames"] = index;
  out["times"] = times;
  return out;
}

}  // namespace

void bind_simulation(py::module_& m) {
  py::class_<BodySimulation, std::unique_ptr<BodySimulation>>(
      m, "Simulation",
      "One body along a motion (`sflsh simulate`): Simulation(subject=… or betas=…, motion=…, solver='full'|'reduced', "
      "mesh='coarse'|'default'|'fine', integrator=…, mass=…, material=path|Material, …)")
      .def(py::init(&make_simulation),
           "Keyword arguments as `sflsh simulate`'s options ('-' as '_'), with the same defaults: subject | betas, "
           "body, "
           "motion (required), solver ('full'), frames (0: the motion's length), fps (60), substeps (1), mesh "
           "('default'), "
           "mesher ('layered'), material (a path or a sflsh.Material), control_points (12), cache, density (1000), "
           "gravity, "
           "stiffness_scale (1), mass ('lumped'), integrator ('backward_euler'), handles (86), cubature (-1: auto), "
           "cubature_weights ('nnls'), affine, newton_tolerance (1e-5 m), allow_long")
      .def(
          "step",
          [](BodySimulation& sim) {
            {
              py::gil_scoped_release release;
              sim.step();
            }
            return sim.frame();
          },
          "Solves the next frame; returns its number")
      .def("run", &run, py::arg("frames") = py::none(),
           "Solves `frames` more frames (default: to the end) and returns a dict: vertices (T × n × 3, the posed body "
           "surface as body.pvd holds it) and soft_tissue_displacement (T × n × 3, posed − skinned) [m], frames and "
           "times (T), for the current frame and every frame solved (T = frames + 1)")
      .def(
          "vertices", [](const BodySimulation& sim) { return own(sim.posed_surface()); },
          "The posed body surface at the current frame (n × 3) [m]")
      .def(
          "soft_tissue_displacement",
          [](const BodySimulation& sim) {
            return own(body::RowMatrixX3d(sim.posed_surface() - sim.skinned_surface()));
          },
          "Posed − skinned surface at the current frame (n × 3) [m]; zero outside the soft-tissue region")
      .def(
          "sigma",
          [](const BodySimulation& sim) {
            return py::make_tuple(own(sim.writer().sigma_per_vertex()), own(sim.writer().sigma_normal_per_vertex()),
                                  own(sim.writer().sigma_tangent_per_vertex()));
          },
          "(σ, σ_n, σ_t) per body vertex [m] over the frames so far (docs/physics.md §4; zero outside the region)")
      .def(
          "summary",
          [](const BodySimulation& sim) {
            nlohmann::json s = sim.summary();
            s.erase("compression");
            return pyjson::from_json(s);  // pybind11_json (Debian pybind11-json-dev)
          },
          "summary.json of `sflsh simulate` over the frames so far (without the command-line header and \"output\")")
      .def(
          "state",
          [](const BodySimulation& sim) {
            const model::State st = sim.state();
            const auto nodes = st.x.size() / 3;
            return py::make_tuple(own(body::RowMatrixX3d(Eigen::Map<const body::RowMatrixX3d>(st.x.data(), nodes, 3))),
                                  own(body::RowMatrixX3d(Eigen::Map<const body::RowMatrixX3d>(st.w.data(), nodes, 3))));
          },
          "(x, w): unposed elastic positions and their velocities per layer node (N × 3)")
      .def_property_readonly("frame", &BodySimulation::frame, "The frame the state is at (0 at the start)")
      .def_property_readonly("num_frames", &BodySimulation::num_frames, "The motion's frames, frame 0 included")
      .def_property_readonly("finished", &BodySimulation::finished)
      .def_property_readonly("last_step_seconds", &BodySimulation::last_step_seconds,
                             "Wall time of the last frame's C++ step (solver and recording) [s]")
      .def_property_readonly("time", &BodySimulation::time, "Time of the current frame [s]")
      .def_property_readonly("subject", &BodySimulation::subject_label)
      .def_property_readonly("beta", [](const BodySimulation& sim) { return own(Eigen::VectorXd(sim.beta())); })
      .def_property_readonly(
          "faces", [](py::object self) { return view(self.cast<BodySimulation&>().body().faces, self); },
          "The body's faces (m × 3, int32, read-only view)")
      .def_property_readonly("num_vertices", [](const BodySimulation& sim) { return sim.body().num_vertices(); })
      .def_property_readonly(
          "nodes", [](py::object self) { return view(self.cast<BodySimulation&>().layer().layer.nodes, self); },
          "The layer's rest nodes for the subject (N × 3) [m] (read-only view)")
      .def_property_readonly(
          "tets", [](py::object self) { return view(self.cast<BodySimulation&>().layer().mesh->tets, self); },
          "The layer's tets (K × 4, int32, read-only view)")
      .def("__repr__", [](const BodySimulation& sim) {
        return "<sflsh.Simulation " + sim.settings().solver + " '" + sim.subject_label() + "' along '" +
               sim.motion().name + "': frame " + std::to_string(sim.frame()) + " of " +
               std::to_string(sim.num_frames()) + ">";
      });
}

}  // namespace sflsh::python
