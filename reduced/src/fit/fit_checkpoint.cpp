#include "fit_checkpoint.hpp"

#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/log.hpp>

#include <nlohmann/json.hpp>

#include <fstream>

namespace sflsh::reduced {

nlohmann::json stage_report_json(const FitStageReport& s) {
  return {{"controls", s.controls},   {"iterations", s.iterations}, {"loss_fit", s.loss_fit},
          {"loss_reg", s.loss_reg},   {"seconds", s.seconds},       {"simulations", s.simulations},
          {"jacobians", s.jacobians}, {"reason", s.reason}};
}

FitStageReport stage_report_from_json(const nlohmann::json& s) {
  FitStageReport r;
  r.controls = s.at("controls");
  r.iterations = s.at("iterations");
  r.loss_fit = s.at("loss_fit");
  r.loss_reg = s.at("loss_reg");
  r.seconds = s.at("seconds");
  r.simulations = s.at("simulations");
  r.jacobians = s.at("jacobians");
  r.reason = s.at("reason");
  return r;
}

void save_checkpoint(const std::filesystem::path& path, const std::string& fingerprint, const Checkpoint& c) {
  nlohmann::json j;
  j["fingerprint"] = fingerprint;
  j["finished"] = c.finished;
  j["stage"] = c.stage;
  j["iteration"] = c.iteration;
  j["p"] = std::vector<double>(c.p.data(), c.p.data() + c.p.size());
  for (const FitStageReport& s : c.done) j["done"].push_back(stage_report_json(s));
  write_text_atomically(path, j.dump(1));
}

std::optional<Checkpoint> load_checkpoint(const std::filesystem::path& path, const std::string& fingerprint) {
  if (path.empty() || !std::filesystem::exists(path)) return std::nullopt;
  try {
    std::ifstream in(path);
    const nlohmann::json j = nlohmann::json::parse(in);
    if (j.at("fingerprint").get<std::string>() != fingerprint) {
      logger()->warn("fit: checkpoint {} belongs to a different fit; starting over", path.string());
      return std::nullopt;
    }
    Checkpoint c;
    c.finished = j.value("finished", false);
    c.stage = j.at("stage").get<int>();
    c.iteration = j.at("iteration").get<int>();
    const auto p = j.at("p").get<std::vector<double>>();
    c.p = Eigen::Map<const Eigen::VectorXd>(p.data(), static_cast<Eigen::Index>(p.size()));
    if (j.contains("done"))
      for (const auto& s : j["done"]) {
        FitStageReport r = stage_report_from_json(s);
        r.resumed = true;
        c.done.push_back(r);
      }
    return c;
  } catch (const std::exception& e) {
    logger()->warn("fit: checkpoint {} is unreadable ({}); starting over", path.string(), e.what());
    return std::nullopt;
  }
}

}  // namespace sflsh::reduced
