#pragma once
// The outputs of `sflsh sweep` that do not depend on the solvers: one row per subject × motion × mesh run
// (sweep.csv), the Markdown table with the failures and their one-line errors (sweep.md), and the counts per
// mesh for summary.json.
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace sflsh::app::sweep {

/// One run of the sweep and what it measured (NaN / −1 where a failed run did not get that far).
struct SweepRun {
  std::string mesh, subject, motion;
  bool ok = false;
  std::string error;  ///< one line; empty when ok
  int frames = 0;     ///< output frames computed, frame 0 (the rest state) included
  int frames_requested = 0;
  double sigma_mm = 0.0;          ///< mean σ over the region's vertices [mm]
  double sigma_max_mm = 0.0;      ///< largest σ over the region's vertices [mm]
  double newton_per_frame = 0.0;  ///< Newton iterations per output frame
  double seconds = 0.0;           ///< wall time of the whole run: layer, model, steps [s]
  double solve_seconds = 0.0;     ///< the steps only [s]
  double fps = 0.0;               ///< output frames per second of solve time [1/s]
  long failed_attempts = 0;       ///< substep attempts rejected and retried (projection, splitting)
  long factorizations = 0;        ///< dense Hessian factorizations (reduced)
  int tets = 0;                   ///< tets of the layer
  int coordinates = 0;            ///< reduced coordinates (0: full space)
  int cubature_tets = 0;          ///< cubature tets used, after any automatic enlargement (0: full space)
};

/// The exact CSV header of sweep.csv.
inline constexpr const char* kSweepHeader =
    "mesh,subject,motion,status,error,frames,sigma_mm,newton_per_frame,seconds,fps,sigma_max_mm,solve_seconds,"
    "failed_attempts,factorizations,tets,coordinates,cubature_tets";

/// `text` as one CSV field: quoted (with doubled quotes) when it holds a comma, a quote or a line break.
std::string csv_field(const std::string& text);
/// `text` on one line: line breaks become spaces, surrounding blanks are trimmed.
std::string one_line(const std::string& text);

void write_sweep_csv(const std::filesystem::path& path, const std::vector<SweepRun>& runs);
/// sweep.md: a title, `context` lines, counts per mesh, the table of every run, then the failures with their errors.
void write_sweep_markdown(const std::filesystem::path& path, const std::string& title,
                          const std::vector<std::string>& context, const std::vector<SweepRun>& runs);
/// {"<mesh>": {"runs": n, "ok": n, "failures": n}, …} in the order the meshes first appear.
nlohmann::json counts_per_mesh(const std::vector<SweepRun>& runs);
/// [{"mesh", "subject", "motion", "frames", "error"}, …] of the failed runs.
nlohmann::json failures_json(const std::vector<SweepRun>& runs);

}  // namespace sflsh::app::sweep
