#pragma once
// What every binding file of the Python module shares: Eigen ↔ NumPy without copies where the layout allows, β
// and array arguments with one-line errors, and the binders module.cpp calls.
//
// NumPy without copies:
//   - own(m): a matrix computed for the caller is moved to the heap and handed to NumPy with a capsule that
//     frees it: the array is the result's memory, nothing is copied.
//   - view(m, owner): an array the C++ object keeps (a body's template, a layer's nodes) is exposed read-only
//     with `owner` (the Python object) as its base, so it lives as long as any view of it.
//   - Inputs are taken as float64 C-contiguous arrays (py::array::forcecast): an array already in that layout is
//     read in place, anything else is converted once by NumPy.
#include <sflsh/body/skinning.hpp>

#include <Eigen/Core>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sflsh::python {

namespace py = pybind11;

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IntArray = py::array_t<int, py::array::c_style | py::array::forcecast>;

/// Row-major Eigen matrices map onto C-ordered NumPy arrays as they are; column vectors as 1-D arrays.
template <class Matrix>
std::vector<py::ssize_t> numpy_shape(const Matrix& m) {
  if constexpr (Matrix::ColsAtCompileTime == 1)
    return {static_cast<py::ssize_t>(m.rows())};
  else
    return {static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())};
}
template <class Matrix>
std::vector<py::ssize_t> numpy_strides(const Matrix& m) {
  using Scalar = typename Matrix::Scalar;
  const auto s = static_cast<py::ssize_t>(sizeof(Scalar));
  if constexpr (Matrix::ColsAtCompileTime == 1)
    return {s};
  else if constexpr (Matrix::IsRowMajor)
    return {s * static_cast<py::ssize_t>(m.cols()), s};
  else
    return {s, s * static_cast<py::ssize_t>(m.rows())};
}

/// The matrix, moved to the heap, as a NumPy array that owns it (no copy).
template <class Matrix>
py::array own(Matrix&& m) {
  using M = std::decay_t<Matrix>;
  auto* heap = new M(std::forward<Matrix>(m));
  py::capsule free_when_done(heap, [](void* p) { delete static_cast<M*>(p); });
  return py::array_t<typename M::Scalar>(numpy_shape(*heap), numpy_strides(*heap), heap->data(), free_when_done);
}

/// A read-only NumPy view of a matrix that `owner` keeps alive (no copy).
template <class Matrix>
py::array view(const Matrix& m, py::handle owner) {
  py::array a = py::array_t<typename Matrix::Scalar>(numpy_shape(m), numpy_strides(m), m.data(), owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

/// A read-only view with an explicit shape and strides in bytes (e.g. shapedirs as n × 3 × B).
template <class Scalar>
py::array view(const Scalar* data, std::vector<py::ssize_t> shape, std::vector<py::ssize_t> strides, py::handle owner) {
  py::array a = py::array_t<Scalar>(std::move(shape), std::move(strides), data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

/// β from None (zero), or up to 10 numbers (fewer are zero-padded, as `--betas`). `what` names the argument.
body::Betas betas_from(const py::object& values, const char* what = "betas");
/// An n × 3 float64 array as an Eigen matrix (read through a map; copied once into the result).
body::RowMatrixX3d rows3_from(const DoubleArray& a, const char* what);
/// The body path of a `body=` argument: None → "" (the open body), a str → that path, a sflsh.Body → its path.
std::string body_path_from(const py::object& body);

void bind_body(py::module_& m);
void bind_layer(py::module_& m);
void bind_material(py::module_& m);
void bind_simulation(py::module_& m);
void bind_metrics(py::module_& m);
/// Gives every function, method and class of the module a signature inspect.signature() reads (text_signatures.cpp);
/// called last, once every binding is defined.
void add_text_signatures(py::module_& m);
/// The text signature "(params)" of a pybind11 docstring "name(params) -> type…" without annotations ("self, /"
/// first for a method); nullopt when it has none Python can read (overloads, *args, an object as a default).
std::optional<std::string> text_signature(const std::string& doc, const std::string& name, bool method);

}  // namespace sflsh::python
