// Signatures that inspect.signature() and help() read: pybind11 2.10 writes each function's typed signature as the
// first line of its docstring ("run(self: sflsh.Simulation, frames: Optional[int] = None) -> dict"), which Python
// does not parse. CPython reads a builtin function's signature from a docstring that starts with
// "name(params)\n--\n\n" (its __text_signature__), without annotations. add_text_signatures() puts that line, made
// from pybind11's own (names, defaults, '*' and '/'; annotations dropped), in front of every docstring of the module,
// its classes' methods and static methods, and gives every class a __signature__ (its __init__'s without self):
// the typed line stays in the docstring for help() and the stub (python/sflsh.pyi).
#include "bind_common.hpp"

#include <Python.h>

#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

namespace sflsh::python {

namespace {

/// The parameters between the parentheses that open at `open`, split at the commas outside brackets and quotes;
/// nullopt when the text ends first. `close` is set to the matching ')'.
std::optional<std::vector<std::string>> split_parameters(const std::string& text, std::size_t open,
                                                         std::size_t& close) {
  std::vector<std::string> out;
  std::string current;
  int depth = 0;
  char quote = 0;
  for (std::size_t i = open + 1; i < text.size(); ++i) {
    const char c = text[i];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == '(' || c == '[' || c == '{') {
      ++depth;
    } else if ((c == ')' || c == ']' || c == '}') && depth > 0) {
      --depth;
    } else if (c == ')') {
      if (!current.empty()) out.push_back(current);
      close = i;
      return out;
    } else if (c == ',' && depth == 0) {
      out.push_back(current);
      current.clear();
      continue;
    }
    current += c;
  }
  return std::nullopt;
}

std::string trimmed(const std::string& s) {
  const std::size_t a = s.find_first_not_of(' '), b = s.find_last_not_of(' ');
  return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

/// "name: type = default" → "name=default", "name: type" → "name"; nullopt for a default Python cannot read back
/// (an object's repr, "<…>").
std::optional<std::string> plain_parameter(const std::string& parameter) {
  const std::string p = trimmed(parameter);
  const std::size_t colon = p.find(':');
  const std::size_t equals = p.find(" = ");
  const std::string name = trimmed(p.substr(0, std::min(colon, equals)));
  if (equals == std::string::npos) return name;
  const std::string value = trimmed(p.substr(equals + 3));
  if (value.empty() || value.find('<') != std::string::npos) return std::nullopt;
  return name + "=" + value;
}

}  // namespace

std::optional<std::string> text_signature(const std::string& doc, const std::string& name, bool method) {
  if (doc.rfind(name + "(", 0) != 0) return std::nullopt;  // overloaded functions start "name(*args, **kwargs)"
  std::size_t close = 0;
  const auto parameters = split_parameters(doc, name.size(), close);
  if (!parameters) return std::nullopt;
  std::string out = "(";
  for (std::size_t k = 0; k < parameters->size(); ++k) {
    std::optional<std::string> p = plain_parameter((*parameters)[k]);
    if (!p) return std::nullopt;
    // A plain "self", not CPython's "$self": inspect drops "$self" from a function whose __self__ is set, and a
    // pybind11 function's __self__ is its capsule, so a bound method would lose its first argument as well.
    if (method && k == 0) p = "self, /";
    if (*p == "*args" || *p == "**kwargs") return std::nullopt;  // no signature to show
    out += (k == 0 ? "" : ", ") + *p;
  }
  return out + ")";
}

namespace {

/// Puts "name(params)\n--\n\n" in front of a pybind11 function's docstring (once).
void add_to_function(PyObject* function, bool method) {
  if (!PyCFunction_Check(function)) return;
  PyMethodDef* def = reinterpret_cast<PyCFunctionObject*>(function)->m_ml;
  if (!def->ml_doc || std::strstr(def->ml_doc, "\n--\n\n")) return;
  const std::string doc = def->ml_doc;
  const std::optional<std::string> signature = text_signature(doc, def->ml_name, method);
  if (!signature) return;
  const std::string full = def->ml_name + *signature + "\n--\n\n" + doc;
  // pybind11 allocates the docstring with strdup and frees it with free (pybind11.h, cpp_function).
  std::free(const_cast<char*>(def->ml_doc));
  def->ml_doc = strdup(full.c_str());
}

void add_to_class(py::handle cls) {
  const py::dict members = cls.attr("__dict__");
  for (const auto& [key, value] : members) {
    if (PyInstanceMethod_Check(value.ptr()))
      add_to_function(PyInstanceMethod_GET_FUNCTION(value.ptr()), true);
    else if (py::isinstance(value, py::module_::import("builtins").attr("staticmethod")))
      add_to_function(value.attr("__func__").ptr(), false);
  }
  if (!members.contains("__init__")) return;
  py::object init = cls.attr("__init__");
  if (init.attr("__text_signature__").is_none()) return;
  const py::object signature = py::module_::import("inspect").attr("signature")(init);
  const py::list parameters(signature.attr("parameters").attr("values")());
  py::list without_self;
  for (std::size_t k = 1; k < parameters.size(); ++k) without_self.append(parameters[k]);
  cls.attr("__signature__") = signature.attr("replace")(py::arg("parameters") = without_self);
}

}  // namespace

void add_text_signatures(py::module_& m) {
  for (const auto& [key, value] : m.attr("__dict__").cast<py::dict>()) {
    if (PyCFunction_Check(value.ptr()))
      add_to_function(value.ptr(), false);
    else if (PyType_Check(value.ptr()) && py::hasattr(value, "__module__") &&
             py::str(value.attr("__module__")).cast<std::string>() == "sflsh" &&
             !PyType_IsSubtype(reinterpret_cast<PyTypeObject*>(value.ptr()),
                               reinterpret_cast<PyTypeObject*>(PyExc_BaseException)))
      add_to_class(value);
  }
}

}  // namespace sflsh::python
