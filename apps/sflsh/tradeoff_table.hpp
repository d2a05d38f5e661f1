#pragma once
// The accuracy–time table of `sflsh tradeoff`, independent of the solvers: one row per configuration, the
// Pareto front of error against seconds per frame, the cheapest configuration within an error budget, and
// the outputs tradeoff.csv, tradeoff.md and tradeoff.png.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace sflsh::app::tradeoff {

/// One configuration and what its run measured against the reference.
struct Row {
  std::string model;               ///< reference | full | reduced
  std::string integrator;          ///< sundials (adaptive, error-controlled) | backward_euler | bdf2 | newmark
  std::string mesh;                ///< coarse | default | fine
  int handles = 0;                 ///< point handles (reduced; 0 otherwise)
  int cubature = 0;                ///< cubature tets used (reduced; 0 otherwise)
  int substeps = 0;                ///< steps per output frame (0: adaptive)
  double step = 0.0;               ///< 1 / (fps · substeps) [s] (0: adaptive)
  double setup_seconds = 0.0;      ///< layer build + solver (and reduced model) setup [s]
  double seconds_per_frame = 0.0;  ///< solve time per output frame [s]
  double rms_error_mm = 0.0;       ///< RMS over region vertices and frames 1..F of |p − p_ref| [mm]
  double relative_error = 0.0;     ///< rms_error / RMS of the reference's soft-tissue displacement
  double sigma_ratio = 0.0;        ///< mean σ / mean σ_ref over the region's vertices
  bool valid = true;               ///< every full-space tet stayed within the material's range (reduced)
  bool pareto = false;             ///< on the Pareto front of (seconds_per_frame, rms_error_mm)
  std::string mass = "lumped";     ///< lumped | consistent (docs/integrators.md)

  /// e.g. "reduced coarse h30 k200 1/60 s", "full default 1/120 s", "reference sundials coarse"; rows that are not
  /// backward Euler with lumped masses name their integrator and mass ("full coarse newmark consistent 1/60 s").
  std::string label() const;
};

/// The exact CSV header of tradeoff.csv.
inline constexpr const char* kHeader =
    "model,integrator,mesh,handles,cubature,substeps,step_s,setup_seconds,seconds_per_frame,rms_error_mm,relative_"
    "error,"
    "sigma_ratio,valid,pareto,mass";

/// Sets Row::pareto: a valid row is on the front when no other valid row is at least as fast and at least as
/// accurate and strictly better in one of the two. The reference (zero error) is on it by construction.
void mark_pareto_front(std::vector<Row>& rows);

/// An error budget: an absolute RMS error [mm], a relative error, or both (then both must hold).
struct Budget {
  std::optional<double> mm;
  std::optional<double> relative;
  bool given() const { return mm.has_value() || relative.has_value(); }
  bool admits(const Row& row) const;
  std::string text() const;  ///< e.g. "RMS error ≤ 0.5 mm and relative error ≤ 0.1"
};

/// Index of the cheapest (least seconds per frame) valid tested row within the budget; the reference is not
/// a candidate (its error is zero by definition). Nothing when no row meets the budget or none is given.
std::optional<std::size_t> recommend(const std::vector<Row>& rows, const Budget& budget);

/// One sentence: the recommended configuration, or why there is none (no budget, or none within it, with the
/// most accurate tested configuration).
std::string recommendation_text(const std::vector<Row>& rows, const Budget& budget,
                                const std::optional<std::size_t>& pick);

void write_csv(const std::filesystem::path& path, const std::vector<Row>& rows);
/// tradeoff.md: a title, `context` lines (what was measured, the reference, …), the table, the recommendation.
void write_markdown(const std::filesystem::path& path, const std::string& title,
                    const std::vector<std::string>& context, const std::vector<Row>& rows,
                    const std::string& recommendation);
/// tradeoff.png: RMS error against seconds per frame (log–log), one labelled point per tested row, the Pareto
/// front as a line and the reference's time as a dashed vertical line. Throws sflsh::Error without a display.
void write_png(const std::filesystem::path& path, const std::string& title, const std::vector<Row>& rows);

}  // namespace sflsh::app::tradeoff
