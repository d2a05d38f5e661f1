#pragma once
// The material file of one subject (TOML, human-readable; format and example in docs/material_file.md):
// the body model and subject it belongs to, the uniform Poisson ratio and Fung saturation (SFLSH §3),
// optional parameter bounds, and the control points s_i with their κ_i = (h, Y_t, Y_n) in physical
// units, in insertion order (the order of place_control_points, so the first N of a larger file are
// the control points of a smaller N).
//
//   version = 1
//   body = "open_body"                        # the body model's name (the stem of its .npz)
//   subject = "OPEN_TRAIN_1"
//   betas = [0.5, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]   # optional: the subject's 10 shape coefficients
//   poisson = 0.2
//   saturation = 4.0
//   [bounds]                                  # optional; defaults of ParameterBounds
//   thickness = [0.1, 0.9]
//   young_tangent = [500.0, 50000.0]          # Pa
//   young_normal = [500.0, 50000.0]           # Pa
//   [[control_point]]
//   vertex = 1234                             # body (template) vertex index
//   position = [0.012, 0.345, 0.101]          # optional: template position [m], checked against the body
//   thickness = 0.5
//   young_tangent = 5000.0                    # Pa
//   young_normal = 2000.0                     # Pa
//
// Every problem (missing key, wrong type, value outside its bounds, repeated vertex, unknown key, TOML
// syntax) is a one-line sflsh::Error "<file>:<line>: <what>" naming the field.
#include <sflsh/material/parameters.hpp>
#include <sflsh/material/surface_operators.hpp>

namespace sflsh::body {
struct BodyModel;
}

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sflsh::material {

inline constexpr int kMaterialFileVersion = 1;
/// Entries of the optional `betas` key: the body model's shape coefficients (body::kNumBetas).
inline constexpr std::size_t kNumBetasInFile = 10;

struct MaterialControlPoint {
  int vertex = -1;                          ///< body template vertex index
  std::optional<Eigen::Vector3d> position;  ///< template position of that vertex [m], for checking
  Kappa kappa;                              ///< physical (h, Y_t [Pa], Y_n [Pa])
  int line = 0;                             ///< source line when read from a file (0 otherwise)
};

struct MaterialFile {
  std::string body;                                          ///< body model name (body::BodyModel::name)
  std::string subject;                                       ///< subject name (body::Subject::name)
  std::optional<std::array<double, kNumBetasInFile>> betas;  ///< the subject's β (`betas`), when the file gives it
  double poisson = 0.2;                                      ///< ν ∈ (−1, ½), uniform (SFLSH §3)
  double saturation = 4.0;                                   ///< Fung saturation s > 0, uniform (SFLSH §3)
  ParameterBounds bounds;                                    ///< ranges the κ_i must lie in; their maxima normalize κ
  std::vector<MaterialControlPoint> control_points;
  std::string source;  ///< the file it was read from (load_material_file); empty when built in memory

  std::vector<int> vertices() const;  ///< control vertices, in file order
  KappaMatrix kappa() const;          ///< N by 3 physical κ_i, in file order
};

/// Reads and validates a material file (see above). Errors: "<file>:<line>: …" naming the field.
MaterialFile load_material_file(const std::filesystem::path& path);

/// Writes the file atomically after validate(); positions are written when present. `header` becomes a
/// leading comment block (one "# " line per line).
void save_material_file(const std::filesystem::path& path, const MaterialFile& material,
                        const std::string& header = "");

/// Checks names non-empty, β finite when given, ν ∈ (−1, ½), s > 0, bounds (validate(ParameterBounds)), at least one
/// control point, vertices ≥ 0 and distinct, positions finite, every κ_i within the bounds. Messages start with `what`
/// (load passes "<file>:<line>").
void validate(const MaterialFile& material, std::string_view what = "material");

/// Checks the file against the body it names: every vertex < #V, and every given position within
/// `position_tolerance` [m] of V.row(vertex). `what` starts each message (empty: the file it was read from,
/// else "material"); points read from a file add their line.
void check_against_body(const MaterialFile& material, const RowMatrixX3d& V, double position_tolerance = 1e-6,
                        std::string_view what = "");
/// The same against a body model, after checking that the file names it (material.body == body.name):
/// a material written for another body (e.g. 'smpl' used with the open body) is refused naming both.
void check_against_body(const MaterialFile& material, const body::BodyModel& body, double position_tolerance = 1e-6);

}  // namespace sflsh::material
