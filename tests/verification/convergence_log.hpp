#pragma once
// Observed convergence orders, and the measured errors behind them written where docs/verification.md's plots
// are drawn from: with SFLSH_VERIFICATION_OUT=DIR set, each study appends `study,case,h,error` rows to
// DIR/convergence.csv (scripts/plot_verification.py draws them).
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace sflsh::testing {

/// log2(e_coarse / e_fine) for a halved step or cell size.
inline double observed_order(double coarse_error, double fine_error) { return std::log2(coarse_error / fine_error); }

/// Appends `study,case,h,error` rows (h in the study's unit: s for time, m for space) when SFLSH_VERIFICATION_OUT
/// names a folder; nothing otherwise.
inline void log_convergence(const std::string& study, const std::string& name, const std::vector<double>& h,
                            const std::vector<double>& error) {
  const char* out = std::getenv("SFLSH_VERIFICATION_OUT");
  if (out == nullptr || *out == '\0') return;
  const std::filesystem::path file = std::filesystem::path(out) / "convergence.csv";
  std::filesystem::create_directories(file.parent_path());
  const bool fresh = !std::filesystem::exists(file);
  std::ofstream csv(file, std::ios::app);
  if (fresh) csv << "study,case,h,error\n";
  csv.precision(12);
  for (std::size_t k = 0; k < h.size() && k < error.size(); ++k)
    csv << study << ',' << name << ',' << h[k] << ',' << error[k] << '\n';
}

}  // namespace sflsh::testing
