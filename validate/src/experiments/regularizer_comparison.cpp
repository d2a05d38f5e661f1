// Telling the regularizers apart (docs/fit.md): the full fits with L² and with the local regularizer, paired on
// every test subject × motion that has a truth (relative σ error overall and per body part, win counts, a two-sided
// sign test), and the error of the shape-dependent part of the recovered parameters, κ̂(β) − κ̂(β̄).
#include "report.hpp"

#include <sflsh/core/atomic_file.hpp>
#include <sflsh/meshing/layer_mesh.hpp>

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <sstream>

namespace sflsh::validate {

namespace {

/// Body parts of the region by the dominant skinning joint of each vertex (the open body's and SMPL's joints).
struct BodyPart {
  const char* name;
  std::vector<std::string> joints;
};
const std::array<BodyPart, 5>& body_parts() {
  static const std::array<BodyPart, 5> parts = {{
      {"chest", {"spine2", "spine3", "left_collar", "right_collar"}},
      {"belly", {"spine1"}},
      {"hips", {"pelvis"}},
      {"thighs", {"left_hip", "right_hip", "left_knee", "right_knee"}},
      {"upper_arms", {"left_shoulder", "right_shoulder", "left_elbow", "right_elbow"}},
  }};
  return parts;
}

/// Per region vertex the index of its body part in body_parts(), −1 for none.
std::vector<int> part_of_vertices(const body::BodyModel& model, const std::vector<int>& region) {
  std::vector<int> out(region.size(), -1);
  for (std::size_t r = 0; r < region.size(); ++r) {
    Eigen::Index joint = 0;
    model.weights.row(region[r]).maxCoeff(&joint);
    const std::string name = body::kJointNames[static_cast<std::size_t>(joint)];
    for (std::size_t p = 0; p < body_parts().size(); ++p)
      for (const std::string& j : body_parts()[p].joints)
        if (j == name) out[r] = static_cast<int>(p);
  }
  return out;
}

/// Two-sided sign test of `wins` against `losses` (ties dropped): P(a split at least this uneven | p = ½).
double sign_test_p(int wins, int losses) {
  const int n = wins + losses;
  if (n == 0) return 1.0;
  const int k = std::min(wins, losses);
  double tail = 0.0;
  for (int i = 0; i <= k; ++i)
    tail += std::exp(std::lgamma(n + 1.0) - std::lgamma(i + 1.0) - std::lgamma(n - i + 1.0) - n * std::log(2.0));
  return std::min(1.0, 2.0 * tail);
}

/// RMS over the vertices in `mask` (all when empty) of a − b, divided by the RMS of b there.
double relative_rms(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const std::vector<int>& part, int only) {
  double d = 0.0, n = 0.0;
  for (Eigen::Index r = 0; r < a.size(); ++r) {
    if (only >= 0 && part[static_cast<std::size_t>(r)] != only) continue;
    d += (a[r] - b[r]) * (a[r] - b[r]);
    n += b[r] * b[r];
  }
  return n > 0.0 ? std::sqrt(d / n) : std::nan("");
}

}  // namespace

void write_regularizer_comparison(const Report& report, RunFolder& run, nlohmann::json& summary) {
  const meshing::LayerMesh& mesh = report.parameterization->mesh();
  const std::vector<int> part = part_of_vertices(*report.model, mesh.region_surface.vertices);
  std::vector<std::string> motions = report.config.train_motions;
  motions.insert(motions.end(), report.config.test_motions.begin(), report.config.test_motions.end());

  // ---- Paired relative σ errors on the test subjects -------------------------------------------------------
  std::ostringstream csv;
  // error_*: RMS over the region's vertices of σ_fit − σ*, divided by the RMS of σ* (dimensionless); per part the
  // same over that part's vertices.
  csv << "subject,motion,error_l2,error_ours,winner";
  for (const BodyPart& p : body_parts()) csv << ",error_l2_" << p.name << ",error_ours_" << p.name;
  csv << "\n";
  int wins_ours = 0, wins_l2 = 0, ties = 0;
  std::vector<int> part_wins_ours(body_parts().size(), 0), part_wins_l2(body_parts().size(), 0);
  for (const std::string& s : report.config.test_subjects)
    for (const std::string& m : motions) {
      const GroundTruthCase* truth = report.truth_of(s, m);
      const auto l2 = report.evaluations.find("full/l2|" + s + "|" + m);
      const auto ours = report.evaluations.find("full/ours|" + s + "|" + m);
      if (!truth || l2 == report.evaluations.end() || ours == report.evaluations.end()) continue;
      const Eigen::VectorXd target =
          (truth->sigma_normal.array().square() + truth->sigma_tangent.array().square()).sqrt().matrix();
      const double e_l2 = relative_rms(l2->second.sigma, target, part, -1);
      const double e_ours = relative_rms(ours->second.sigma, target, part, -1);
      const char* winner = e_ours < e_l2 ? "ours" : e_l2 < e_ours ? "l2" : "tie";
      wins_ours += e_ours < e_l2;
      wins_l2 += e_l2 < e_ours;
      ties += e_l2 == e_ours;
      csv << s << "," << m << fmt::format(",{:.5f},{:.5f},", e_l2, e_ours) << winner;
      for (std::size_t p = 0; p < body_parts().size(); ++p) {
        const double pl = relative_rms(l2->second.sigma, target, part, static_cast<int>(p));
        const double po = relative_rms(ours->second.sigma, target, part, static_cast<int>(p));
        csv << (std::isfinite(pl) ? fmt::format(",{:.5f},{:.5f}", pl, po) : std::string(",,"));
        if (std::isfinite(pl) && std::isfinite(po)) {
          part_wins_ours[p] += po < pl;
          part_wins_l2[p] += pl < po;
        }
      }
      csv << "\n";
    }
  write_text_atomically(run.stage("regularizer_comparison.csv"), csv.str());
  nlohmann::json per_part = nlohmann::json::object();
  for (std::size_t p = 0; p < body_parts().size(); ++p)
    per_part[body_parts()[p].name] = {{"wins_ours", part_wins_ours[p]},
                                      {"wins_l2", part_wins_l2[p]},
                                      {"sign_test_p", sign_test_p(part_wins_ours[p], part_wins_l2[p])}};
  summary["regularizer_comparison"] = {{"pairs", wins_ours + wins_l2 + ties},
                                       {"wins_ours", wins_ours},
                                       {"wins_l2", wins_l2},
                                       {"ties", ties},
                                       {"sign_test_p", sign_test_p(wins_ours, wins_l2)},
                                       {"per_body_part", per_part}};

  // ---- The shape-dependent part of the parameters: κ̂(β) − κ̂(β̄), β̄ the train subjects' mean ---------------
  if (!report.true_parameters) return;
  body::Betas mean_beta = body::Betas::Zero();
  for (const std::string& s : report.config.train_subjects) mean_beta += report.betas.at(s);
  mean_beta /= static_cast<double>(report.config.train_subjects.size());
  const TrueMaterial truth_material =
      report.config.truth_model.empty() ? TrueMaterial() : TrueMaterial::from_shape_model(report.config.truth_model);
  const material::KappaMatrix truth_at_mean =
      material::normalize(truth_material.kappa_field(*report.model, mesh, mean_beta, report.bounds), report.bounds);
  std::ostringstream pe;
  // *_rms: RMS over the region of (κ̂_fit(β) − κ̂_fit(β̄)) − (κ̂*(β) − κ̂*(β̄)), κ̂ = κ / κ_max (dimensionless);
  // truth_*_rms: RMS of κ̂*(β) − κ̂*(β̄), the size of what there is to recover.
  pe << "method,subject,split,thickness_rms,young_tangent_rms,young_normal_rms,truth_thickness_rms,"
        "truth_young_tangent_rms,truth_young_normal_rms\n";
  nlohmann::json means = nlohmann::json::object();
  for (const std::string tag : {"l2", "ours"}) {
    const reduced::FitResult& fit = report.fits.at("full/" + tag);
    const material::KappaMatrix fit_at_mean =
        report.parameterization->field(fit.kappa_normalized(mean_beta, report.bounds));
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    int count = 0;
    for (const auto* split : {&report.config.train_subjects, &report.config.test_subjects})
      for (const std::string& s : *split) {
        const GroundTruthCase* t = report.truth_of(s, report.config.train_motions.front());
        if (!t) continue;
        const material::KappaMatrix fitted =
            report.parameterization->field(fit.kappa_normalized(t->beta, report.bounds)) - fit_at_mean;
        const material::KappaMatrix truth = material::normalize(t->kappa, report.bounds) - truth_at_mean;
        const auto R = static_cast<double>(truth.rows());
        const Eigen::RowVector3d err = ((fitted - truth).array().square().colwise().sum() / R).sqrt().matrix();
        const Eigen::RowVector3d size = (truth.array().square().colwise().sum() / R).sqrt().matrix();
        pe << tag << "," << s << "," << (split == &report.config.train_subjects ? "train" : "test")
           << fmt::format(",{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f}\n", err[0], err[1], err[2], size[0], size[1],
                          size[2]);
        sum += err;
        ++count;
      }
    if (count > 0) sum /= count;
    means[tag] = {{"thickness_rms", sum[0]}, {"young_tangent_rms", sum[1]}, {"young_normal_rms", sum[2]}};
  }
  write_text_atomically(run.stage("shape_dependence_error.csv"), pe.str());
  summary["shape_dependence_error"] = means;
}

}  // namespace sflsh::validate
