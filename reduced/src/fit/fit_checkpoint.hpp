#pragma once
// The fit's checkpoint: written after every iteration so an interrupted fit resumes where it stopped, and read
// back only when its fingerprint (what the fit depends on) matches.
#include <sflsh/reduced/elasticity_fit.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace sflsh::reduced {

struct Checkpoint {
  bool finished = false;  ///< the whole fit is done: p is the result, `done` has every stage
  int stage = 0;
  int iteration = 0;
  Eigen::VectorXd p;
  std::vector<FitStageReport> done;
};

void save_checkpoint(const std::filesystem::path& path, const std::string& fingerprint, const Checkpoint& c);
/// Nothing when there is no file, it belongs to another fit (a warning) or cannot be read (a warning).
std::optional<Checkpoint> load_checkpoint(const std::filesystem::path& path, const std::string& fingerprint);

}  // namespace sflsh::reduced
