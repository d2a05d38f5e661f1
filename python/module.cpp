// The Python module `sflsh` (docs/python.md): the body, the soft-tissue layer, materials, simulations and the
// dynamics metric, named as the command line names them. sflsh::Error becomes sflsh.Error (a RuntimeError)
// carrying the same one-line message the CLI prints after "sflsh: error: ".
#include "bind_common.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/summary.hpp>

#include <pybind11/stl.h>

#include <cmath>

namespace sflsh::python {

body::Betas betas_from(const py::object& values, const char* what) {
  body::Betas beta = body::Betas::Zero();
  if (values.is_none()) return beta;
  const DoubleArray a = DoubleArray::ensure(values);
  if (!a) throw Error(std::string("--") + what + ": expected up to 10 numbers");
  require(a.ndim() <= 1, "--{}: expected a vector of up to 10 numbers, got an array with {} dimensions", what,
          a.ndim());
  const py::ssize_t n = a.size();
  require(n <= body::kNumBetas, "--{}: {} values, at most {} are used", what, n, body::kNumBetas);
  for (py::ssize_t i = 0; i < n; ++i) {
    require(std::isfinite(a.data()[i]), "--{}: value {} is not finite", what, i + 1);
    beta(i) = a.data()[i];
  }
  return beta;
}

body::RowMatrixX3d rows3_from(const DoubleArray& a, const char* what) {
  require(a.ndim() == 2 && a.shape(1) == 3, "{}: expected an array of shape (n, 3), got {} dimensions", what, a.ndim());
  return Eigen::Map<const body::RowMatrixX3d>(a.data(), a.shape(0), 3);
}

std::string body_path_from(const py::object& body) {
  if (body.is_none()) return "";
  if (py::isinstance<py::str>(body)) return body.cast<std::string>();
  require(py::hasattr(body, "_selection_path"), "--body: expected None, a path or a sflsh.Body");
  return body.attr("_selection_path").cast<std::string>();
}

}  // namespace sflsh::python

PYBIND11_MODULE(sflsh, m) {
  namespace py = pybind11;
  using namespace sflsh::python;
  m.doc() = "sflsh: shape-dependent soft-flesh avatars (docs/python.md)";
  m.attr("__version__") = sflsh::version();  // the project's version (CMake), as `sflsh --version` prints it
  py::register_exception<sflsh::Error>(m, "Error", PyExc_RuntimeError).attr("__doc__") =
      "A refused input or a failed solve (a RuntimeError), with the one-line message the command line prints";
  // A library embedded in a Python session reports warnings and errors; sflsh.set_log_level("info") shows the
  // progress lines the CLI prints.
  sflsh::logger()->set_level(spdlog::level::warn);
  m.def(
      "set_log_level",
      [](const std::string& level) {
        const spdlog::level::level_enum l = spdlog::level::from_str(level);
        sflsh::require(l != spdlog::level::off || level == "off",
                       "--log-level: '{}' is not a level (trace, debug, info, warn, error, off)", level);
        sflsh::logger()->set_level(l);
      },
      py::arg("level"), "Log level of the sflsh logger: trace | debug | info | warn (default) | error | off");
  m.def(
      "data_dir", [] { return sflsh::body::data_dir().string(); },
      "The project's data folder ($SFLSH_DATA or the source tree's data/)");
  bind_body(m);
  bind_layer(m);
  bind_material(m);
  bind_simulation(m);
  bind_metrics(m);
  add_text_signatures(m);
}
