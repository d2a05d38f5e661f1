// The units of the output arrays (array_units.hpp). Every name here has a row in docs/output.md.
#include <sflsh/core/array_units.hpp>

#include <array>
#include <utility>

namespace sflsh::units {

namespace {

using Row = std::pair<std::string_view, std::string_view>;

// Sorted by where the arrays appear: body frames, σ maps, meshes and materials, scenes, field data.
constexpr std::array kUnits = {
    Row{"displacement", "m"},
    Row{"velocity", "m/s"},
    Row{"skin_weights_argmax", "index"},
    Row{"skin_weights", "1"},
    Row{"soft_tissue_displacement", "m"},
    Row{"elastic_displacement", "m"},
    Row{"strain_energy_density", "J/m^3"},
    Row{"thickness_fraction", "1"},
    Row{"thickness", "1"},  // the same quantity as thickness_fraction (older name, kept for scripts)
    Row{"young_tangent", "Pa"},
    Row{"young_normal", "Pa"},
    Row{"soft_region", "1"},
    Row{"Normals", "1"},
    Row{"contact_force", "N"},
    Row{"penetration", "m"},
    Row{"sigma", "mm"},
    Row{"region", "1"},  // compare.vtp's older name of soft_region
    Row{"shape_offset", "m"},
    Row{"node_kind", "label"},
    Row{"part", "label"},
    Row{"local_thickness", "m"},
    Row{"max_thickness", "m"},
    Row{"to_skeleton", "m"},
    Row{"displacement_from_template", "m"},
    Row{"volume", "m^3"},
    Row{"min_dihedral_deg", "deg"},
    Row{"radius_edge", "1"},
    Row{"normal", "1"},
    Row{"index", "index"},
    Row{"object_id", "index"},
    Row{"TimeValue", "s"},
};

// Families named by a prefix: the basis functions, the σ maps of compare and validate, their errors.
constexpr std::array kFamilies = {
    Family{"phi_", "1"},
    Family{"sigma_", "mm"},
    Family{"rms_error_", "mm"},
    Family{"covariance_", "1"},
};

}  // namespace

std::string_view of(std::string_view array_name) {
  for (const Row& row : kUnits)
    if (row.first == array_name) return row.second;
  for (const Family& f : kFamilies)
    if (array_name.size() > f.prefix.size() && array_name.starts_with(f.prefix)) return f.unit;
  return {};
}

std::vector<std::string> listed_names() {
  std::vector<std::string> names;
  for (const Row& row : kUnits) names.emplace_back(row.first);
  return names;
}

std::span<const Family> families() { return kFamilies; }

std::string entry(std::string_view array_name) {
  const std::string_view unit = of(array_name);
  return std::string(array_name) + ": " + (unit.empty() ? std::string("?") : std::string(unit));
}

}  // namespace sflsh::units
