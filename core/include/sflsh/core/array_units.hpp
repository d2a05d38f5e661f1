#pragma once
// The unit of every array sflsh writes into its output files, by the array's name: one name, one quantity,
// one unit in every file (docs/output.md, "The arrays"). The writers (vtk_io, xdmf_series) look the units up
// here and write them beside the arrays: the `units` field data of a .vtp/.vtu, the `unit` attribute of a
// dataset in an .h5 and the `units` Information of an .xmf.
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace sflsh::units {

/// Units as written: SI symbols in ASCII ("m", "m/s", "N", "Pa", "J/m^3", "m^3", "s"), "mm" for σ and its
/// relatives, "deg" for angles, "1" for ratios, fractions, weights, masks and unit vectors, "label" for an
/// integer code whose names are the field data `<name>_names`, "index" for an index into a list (joints,
/// objects, control points). Empty when the name is not one of sflsh's output arrays.
std::string_view of(std::string_view array_name);

/// The names listed exactly (the families by prefix, e.g. `phi_NN`, `sigma_…`, are not).
std::vector<std::string> listed_names();

/// The prefixes of the families of arrays ("phi_", "sigma_", …), each with its unit.
struct Family {
  std::string_view prefix;
  std::string_view unit;
};
std::span<const Family> families();

/// "<name>: <unit>", the entry of a `units` list; "?" for a name without a unit.
std::string entry(std::string_view array_name);

}  // namespace sflsh::units
