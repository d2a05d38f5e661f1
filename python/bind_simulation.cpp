// sflsh.Simulation: one body along a motion with the reduced model or the full-space solver, stepped from Python
// (run::BodySimulation, the object `sflsh simulate` runs). Its keyword arguments are simulate's options with
// '-' spelled '_' and the same defaults, visible in its signature; step(), run() and sigma() give the posed surface,
// the soft-tissue displacement and σ, summary() the dictionary `sflsh simulate` writes as summary.json (without the
// command-line header and "output"), and write() the run folder itself (simulation_write.cpp).
//
// Long calls release the GIL while the solver runs; run() takes the GIL back between frames to check for signals,
// so Ctrl-C raises KeyboardInterrupt at a frame boundary and leaves the simulation at the last finished frame,
// ready to step on.
#include "bind_common.hpp"
#include "simulation_object.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/petsc_session.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/run/body_simulation.hpp>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>
#include <pybind11_json/pybind11_json.hpp>

#include <memory>
#include <optional>

namespace sflsh::python {

namespace {

using run::BodySimulation;

/// PETSc (and MPI) for the full-space solver, started on first use and kept for the life of the process: PETSc
/// objects of simulations still referenced when the interpreter exits must never outlive a PetscFinalize.
void ensure_petsc() {
  static fullspace::PetscSession* session = nullptr;
  if (!session && !fullspace::petsc_initialized()) session = new fullspace::PetscSession();
}

/// The keyword arguments of sflsh.Simulation, in the signature's order after `motion`.
std::unique_ptr<PythonSimulation> make_simulation(
    const std::string& motion, const std::optional<std::string>& subject, const py::object& betas,
    const py::object& body, const std::string& solver, int frames, double fps, int substeps, const std::string& mesh,
    const std::string& mesher, const py::object& material, int control_points, const py::object& cache, double density,
    bool gravity, double stiffness_scale, const std::string& mass, const std::string& integrator, int handles,
    int cubature, const std::string& cubature_weights, bool affine, double newton_tolerance, bool allow_long,
    bool record, bool energies) {
  run::BodyRunSettings s;
  s.motion = motion;
  if (subject) s.subject.subject = *subject;
  s.subject.body_path = body_path_from(body);
  s.solver = solver;
  s.frames = frames;
  s.fps = fps;
  s.substeps = substeps;
  s.mesh = mesh;
  s.layer.mesher = mesher;
  s.layer.control_points = control_points;
  if (!cache.is_none()) s.layer.cache = py::str(cache).cast<std::string>();  // a str or a pathlib.Path
  s.layer.density = density;
  s.layer.gravity = gravity;
  s.layer.stiffness_scale = stiffness_scale;
  s.layer.mass = mass;
  s.integrator = integrator;
  s.handles = handles;
  s.cubature = cubature;
  s.cubature_weights = cubature_weights;
  s.affine = affine;
  s.newton_tolerance = newton_tolerance;
  s.allow_long = allow_long;
  s.energies = energies;
  require(!s.motion.empty(), "simulate: --motion is required (a procedural name or an AMASS .npz path)");
  require(!(subject && !betas.is_none()), "--subject and --betas exclude each other");
  if (!betas.is_none()) s.subject.beta_values = betas_from(betas);
  if (py::isinstance<material::MaterialFile>(material))
    s.material_data = material.cast<std::shared_ptr<material::MaterialFile>>();
  else if (!material.is_none())
    s.layer.material = py::str(material).cast<std::string>();
  if (s.solver == "full") ensure_petsc();
  auto out = std::make_unique<PythonSimulation>();
  out->record = record;
  py::gil_scoped_release release;
  out->simulation = std::make_unique<BodySimulation>(s, nullptr, 0, 1, run::BodyRunReporting{false, false, {}, {}});
  if (record) out->states.push_back(out->simulation->state());
  return out;
}

/// Posed surface and soft-tissue displacement of the current frame into rows [0, n) of two T × n × 3 buffers.
void write_frame(const BodySimulation& sim, double* vertices, double* soft) {
  const body::RowMatrixX3d posed = sim.posed_surface();
  Eigen::Map<body::RowMatrixX3d>(vertices, posed.rows(), 3) = posed;
  Eigen::Map<body::RowMatrixX3d>(soft, posed.rows(), 3) = posed - sim.skinned_surface();
}

py::dict run(PythonSimulation& python, const std::optional<int>& frames) {
  BodySimulation& sim = *python;
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
      python.step();
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

/// A read-only view of an array the simulation keeps, owned by the Python object `self`.
template <class Get>
py::array kept(py::object self, Get get) {
  return view(get(self.cast<PythonSimulation&>()), self);
}

void bind_methods(py::class_<PythonSimulation>& c) {
  c.def(
       "step",
       [](PythonSimulation& sim) {
         {
           py::gil_scoped_release release;
           sim.step();
         }
         return (*sim).frame();
       },
       "Solves the next frame (`substeps` solver steps); returns its number")
      .def("run", &run, py::arg("frames") = py::none(),
           "Solves `frames` more frames (None: to the end) and returns a dict: vertices (T × n × 3, the posed body "
           "surface as body.pvd holds it) and soft_tissue_displacement (T × n × 3, posed − skinned) [m], frames and "
           "times [s] (T), for the current frame and every frame solved (T = frames + 1)")
      .def(
          "vertices", [](const PythonSimulation& sim) { return own((*sim).posed_surface()); },
          "The posed body surface at the current frame (n × 3) [m]")
      .def(
          "soft_tissue_displacement",
          [](const PythonSimulation& sim) {
            return own(body::RowMatrixX3d((*sim).posed_surface() - (*sim).skinned_surface()));
          },
          "Posed − skinned surface at the current frame (n × 3) [m]; zero outside the soft-tissue region")
      .def(
          "sigma",
          [](const PythonSimulation& sim) {
            const model::SimulationWriter& w = (*sim).writer();
            return py::make_tuple(own(w.sigma_per_vertex()), own(w.sigma_normal_per_vertex()),
                                  own(w.sigma_tangent_per_vertex()));
          },
          "(σ, σ_n, σ_t) per body vertex [m] over the frames so far (docs/physics.md §4; zero outside the region; "
          "dynamics.vtp holds them in mm)")
      .def(
          "summary",
          [](const PythonSimulation& sim) {
            nlohmann::json s = (*sim).summary();
            s.erase("compression");
            s.erase("layer_compression");
            return pyjson::from_json(s);  // pybind11_json (Debian pybind11-json-dev)
          },
          "summary.json of `sflsh simulate` over the frames so far (without the command-line header and \"output\"; "
          "lengths in m, σ in mm, times in s)")
      .def(
          "state",
          [](const PythonSimulation& sim) {
            const model::State st = (*sim).state();
            const auto nodes = st.x.size() / 3;
            return py::make_tuple(own(body::RowMatrixX3d(Eigen::Map<const body::RowMatrixX3d>(st.x.data(), nodes, 3))),
                                  own(body::RowMatrixX3d(Eigen::Map<const body::RowMatrixX3d>(st.w.data(), nodes, 3))));
          },
          "(x, w): unposed elastic positions [m] and their velocities [m/s] per layer node (N × 3 each)")
      .def(
          "write",
          [](const PythonSimulation& sim, const std::filesystem::path& dir, const std::string& format, bool write_layer,
             int every, const std::string& precision, const std::optional<std::string>& compression,
             const std::optional<std::vector<std::string>>& fields) {
            py::gil_scoped_release release;
            write_run_folder(sim, dir, {format, write_layer, every, precision, compression.value_or(""), fields});
          },
          py::arg("dir"), py::kw_only(), py::arg("format") = "xdmf", py::arg("write_layer") = false,
          py::arg("every") = 1, py::arg("precision") = "float32", py::arg("compression") = py::none(),
          py::arg("fields") = py::none(),
          "Writes the run folder `sflsh simulate --out DIR` writes, for the frames solved so far (0 … frame): "
          "format 'xdmf' (body.xmf + body.h5: triangles and fixed fields once; write_layer: layer.xmf + layer.h5) or "
          "'vtk' (body.pvd of .vtp frames; write_layer: layer.pvd of .vtu frames), every N-th frame (the first and "
          "the last always), dynamics.vtp (σ in mm) and summary.json; precision 'float32' | 'float64' (xdmf), "
          "compression None (zlib xdmf datasets; LZ4 body and zlib layer vtk frames) | 'lz4' (vtk) | 'zlib' | "
          "'none', fields None (the format's default as `--fields`: xdmf the display arrays, vtk every one), "
          "['all'] (every array) or a list of the frames' arrays. The folder appears "
          "all at once; positions in m (docs/output.md)");
}

void bind_properties(py::class_<PythonSimulation>& c) {
  c.def_property_readonly(
       "frame", [](const PythonSimulation& sim) { return (*sim).frame(); },
       "The frame the state is at (0 at the start)")
      .def_property_readonly(
          "num_frames", [](const PythonSimulation& sim) { return (*sim).num_frames(); },
          "The motion's frames, frame 0 included")
      .def_property_readonly(
          "finished", [](const PythonSimulation& sim) { return (*sim).finished(); },
          "Whether the last frame of the motion is solved")
      .def_property_readonly(
          "last_step_seconds", [](const PythonSimulation& sim) { return (*sim).last_step_seconds(); },
          "Wall time of the last frame's C++ step (solver and recording) [s]")
      .def_property_readonly(
          "time", [](const PythonSimulation& sim) { return (*sim).time(); }, "Time of the current frame [s]")
      .def_property_readonly(
          "subject", [](const PythonSimulation& sim) { return (*sim).subject_label(); },
          "The subject's name, or 'custom' for betas")
      .def_property_readonly(
          "beta", [](const PythonSimulation& sim) { return own(Eigen::VectorXd((*sim).beta())); },
          "The subject's shape β (10,)")
      .def_property_readonly(
          "faces",
          [](py::object self) {
            return kept(
                self, [](auto& s) -> const auto& { return (*s).body().faces; });
          },
          "The body's faces (m × 3, int32, read-only view)")
      .def_property_readonly(
          "num_vertices", [](const PythonSimulation& sim) { return (*sim).body().num_vertices(); },
          "The body's vertices n")
      .def_property_readonly(
          "nodes",
          [](py::object self) {
            return kept(
                self, [](auto& s) -> const auto& { return (*s).layer().layer.nodes; });
          },
          "The layer's rest nodes for the subject (N × 3) [m] (read-only view)")
      .def_property_readonly(
          "tets",
          [](py::object self) {
            return kept(
                self, [](auto& s) -> const auto& { return (*s).layer().mesh->tets; });
          },
          "The layer's tets (K × 4, int32, read-only view)")
      .def_property_readonly(
          "recorded_frames", [](const PythonSimulation& sim) { return sim.states.size(); },
          "The frames whose states are kept for write() (frame + 1; 0 with record=False)")
      .def("__repr__", [](const PythonSimulation& python) {
        const BodySimulation& sim = *python;
        return "<sflsh.Simulation " + sim.settings().solver + " '" + sim.subject_label() + "' along '" +
               sim.motion().name + "': frame " + std::to_string(sim.frame()) + " of " +
               std::to_string(sim.num_frames()) + ">";
      });
}

}  // namespace

void bind_simulation(py::module_& m) {
  const run::BodyRunSettings d;  // the defaults of `sflsh simulate`
  py::class_<PythonSimulation> c(
      m, "Simulation",
      "One body along a motion (`sflsh simulate`), stepped from Python: step(), run(), sigma(), summary(), and "
      "write() for the run folder the command writes. Keyword arguments are simulate's options ('-' as '_') with "
      "its defaults; lengths in m, times in s, moduli in Pa.");
  c.def(py::init(&make_simulation), py::kw_only(), py::arg("motion"), py::arg("subject") = py::none(),
        py::arg("betas") = py::none(), py::arg("body") = py::none(), py::arg("solver") = d.solver,
        py::arg("frames") = 0, py::arg("fps") = d.fps, py::arg("substeps") = d.substeps, py::arg("mesh") = d.mesh,
        py::arg("mesher") = d.layer.mesher, py::arg("material") = py::none(),
        py::arg("control_points") = d.layer.control_points, py::arg("cache") = py::none(),
        py::arg("density") = d.layer.density, py::arg("gravity") = d.layer.gravity,
        py::arg("stiffness_scale") = d.layer.stiffness_scale, py::arg("mass") = d.layer.mass,
        py::arg("integrator") = d.integrator, py::arg("handles") = d.handles, py::arg("cubature") = d.cubature,
        py::arg("cubature_weights") = d.cubature_weights, py::arg("affine") = d.affine,
        py::arg("newton_tolerance") = d.newton_tolerance, py::arg("allow_long") = d.allow_long,
        py::arg("record") = true, py::arg("energies") = d.energies,
        "motion: a procedural name (sflsh.motions()) or an AMASS .npz path; subject (a name of sflsh.subjects()) or "
        "betas (up to 10 numbers; neither: β = 0); body: None (the open body), a path or a sflsh.Body; solver "
        "'full' | 'reduced'; frames (0: the motion's length); fps [Hz]; substeps per frame; mesh 'coarse' | "
        "'default' | 'fine'; mesher 'layered' | 'cgal' | 'gmsh'; material: None (the defaults at control_points), a "
        "material file path or a sflsh.Material; cache: the template-mesh and reduced-model cache (None: "
        "$SFLSH_CACHE or ~/.cache/sflsh); density [kg/m³]; gravity; stiffness_scale (multiplies Y_t and Y_n); mass "
        "'lumped' | 'consistent'; integrator 'backward_euler' | 'bdf2' | 'newmark'; reduced model: handles (point "
        "handles), cubature (tets; -1: auto), cubature_weights 'nnls' | 'voronoi', affine; newton_tolerance [m]; "
        "allow_long: run above the work limits; record: keep every frame's state for write() (6 float64 per layer "
        "node and frame); energies: each frame's kinetic, elastic and gravitational energy over every tet in "
        "summary()['frames'] [J] (they cost the reduced model about as much as its step)");
  bind_methods(c);
  bind_properties(c);
}

}  // namespace sflsh::python
