#include "report.hpp"

#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/chart.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/meshing/layer_mesh.hpp>
#include <sflsh/reduced/shape_model_file.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace sflsh::validate {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string key_of(const std::string& fit, const std::string& subject, const std::string& motion) {
  return fit + "|" + subject + "|" + motion;
}

/// Region field (R) → one value per body vertex (0 outside the region).
Eigen::MatrixXd on_body(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                        const Eigen::VectorXd& region_values) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(model.num_vertices(), 1);
  const std::vector<int>& region = mesh.region_surface.vertices;
  for (std::size_t r = 0; r < region.size(); ++r) out(region[r], 0) = region_values[static_cast<Eigen::Index>(r)];
  return out;
}

}  // namespace

const GroundTruthCase* Report::truth_of(const std::string& subject, const std::string& motion) const {
  const auto it = truth->find(subject + "_" + motion);
  return it == truth->end() ? nullptr : &it->second;
}

std::vector<std::string> Report::evaluated_subjects(const std::string& fit) const {
  if (fit.rfind("independent/", 0) == 0) return {fit.substr(12)};
  if (fit.rfind("cv/", 0) == 0) return {fit.substr(fit.rfind('/') + 1)};
  std::vector<std::string> all = config.train_subjects;
  all.insert(all.end(), config.test_subjects.begin(), config.test_subjects.end());
  return all;
}

void Report::evaluate(reduced::SimulationPool& pool, const reduced::ReducedModel& reduced_model,
                      const reduced::ReducedOptions& options,
                      const std::map<std::string, std::unique_ptr<reduced::DynamicsCase>>& cases) {
  std::vector<const reduced::DynamicsCase*> case_list;
  std::map<std::string, int> case_index;
  for (const auto& [key, c] : cases) {
    case_index[key] = static_cast<int>(case_list.size());
    case_list.push_back(c.get());
  }
  std::vector<reduced::SimulationJob> jobs;
  std::vector<std::string> job_keys, job_truth;
  std::vector<std::string> motions = config.train_motions;
  motions.insert(motions.end(), config.test_motions.begin(), config.test_motions.end());
  for (const auto& [name, fit] : fits)
    for (const std::string& s : evaluated_subjects(name))
      for (const std::string& m : motions) {
        const std::string k = key_of(name, s, m);
        if (evaluations.count(k)) continue;
        const reduced::DynamicsCase& c = *cases.at(s + "_" + m);
        jobs.push_back({case_index.at(s + "_" + m), fit.kappa(c.beta(), bounds)});
        job_keys.push_back(k);
        job_truth.push_back(s + "_" + m);
      }
  if (jobs.empty()) return;
  logger()->info("validate: evaluating {} (fit, subject, motion) simulations", jobs.size());
  const std::vector<Eigen::VectorXd> sigma = pool.run(case_list, jobs, *parameterization, reduced_model, options);
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    const auto R = sigma[j].size() / 2;
    Evaluation e;
    e.sigma = (sigma[j].head(R).array().square() + sigma[j].tail(R).array().square()).sqrt().matrix();
    e.mean_sigma = e.sigma.mean();
    const auto t = truth->find(job_truth[j]);
    if (t == truth->end()) {
      e.rms_error = kNaN;  // no truth for this subject (a test subject of DYNA data)
    } else {
      const Eigen::VectorXd ts =
          (t->second.sigma_normal.array().square() + t->second.sigma_tangent.array().square()).sqrt().matrix();
      e.rms_error = std::sqrt((e.sigma - ts).squaredNorm() / static_cast<double>(R));
    }
    evaluations.emplace(job_keys[j], std::move(e));
  }
}

double Report::motion_mean(const std::string& fit, const std::string& subject, const std::vector<std::string>& motions,
                           double Evaluation::*value) const {
  std::vector<double> v;
  for (const std::string& m : motions) {
    const auto it = evaluations.find(key_of(fit, subject, m));
    v.push_back(it == evaluations.end() ? kNaN : it->second.*value);
  }
  return mean_of_finite(v);
}

double Report::table_entry(const std::string& fit, const std::string& subject,
                           const std::vector<std::string>& motions) const {
  return motion_mean(fit, subject, motions, &Evaluation::mean_sigma);
}

double Report::table_error(const std::string& fit, const std::string& subject,
                           const std::vector<std::string>& motions) const {
  return motion_mean(fit, subject, motions, &Evaluation::rms_error);
}

double Report::truth_entry(const std::string& subject, const std::vector<std::string>& motions) const {
  std::vector<double> v;
  for (const std::string& m : motions) {
    const GroundTruthCase* t = truth_of(subject, m);
    v.push_back(t ? t->mean_sigma() : kNaN);
  }
  return mean_of_finite(v);
}

std::string Report::lambda_text(const std::string& tag) const {
  return fmt::format("{:g}", best.count(tag) ? best.at(tag) : config.lambdas_for(tag).front());
}

material::KappaMatrix Report::normalized_truth(const std::string& subject) const {
  const GroundTruthCase& t = truth->at(subject + "_" + config.train_motions.front());
  return material::normalize(t.kappa, bounds);
}

std::vector<Report::Table2Row> Report::table2_rows() const {
  auto fit_row = [&](const std::string& label, std::function<std::string(const std::string&)> fit_of,
                     const std::vector<std::string>& subjects) {
    return Table2Row{label, subjects,
                     [this, fit_of](const std::string& s, const std::vector<std::string>& m) {
                       return table_entry(fit_of(s), s, m);
                     },
                     [this, fit_of](const std::string& s, const std::vector<std::string>& m) {
                       return table_error(fit_of(s), s, m);
                     }};
  };
  const std::string l2 = lambda_text("l2"), ours = lambda_text("ours");
  std::vector<Table2Row> rows;
  rows.push_back({"Ground truth", config.train_subjects,
                  [this](const std::string& s, const std::vector<std::string>& m) { return truth_entry(s, m); },
                  [](const std::string&, const std::vector<std::string>&) { return 0.0; }});
  rows.push_back(fit_row(
      "Independent", [](const std::string& s) { return "independent/" + s; }, config.train_subjects));
  if (config.cross_validation) {
    rows.push_back(fit_row(
        "Cross-val. L2", [l2](const std::string& s) { return "cv/l2/" + l2 + "/" + s; }, config.train_subjects));
    rows.push_back(fit_row(
        "Cross-val. ours", [ours](const std::string& s) { return "cv/ours/" + ours + "/" + s; },
        config.train_subjects));
  }
  rows.push_back(fit_row(
      "Full opt. L2", [](const std::string&) { return std::string("full/l2"); }, config.train_subjects));
  rows.push_back(fit_row(
      "Full opt. ours", [](const std::string&) { return std::string("full/ours"); }, config.train_subjects));
  if (!config.test_subjects.empty()) {
    rows.push_back(fit_row(
        "Generaliz. L2", [](const std::string&) { return std::string("full/l2"); }, config.test_subjects));
    rows.push_back(fit_row(
        "Generaliz. ours", [](const std::string&) { return std::string("full/ours"); }, config.test_subjects));
    rows.push_back({"Ground truth (test subjects)", config.test_subjects,
                    [this](const std::string& s, const std::vector<std::string>& m) { return truth_entry(s, m); },
                    [](const std::string&, const std::vector<std::string>&) { return 0.0; }});
  }
  return rows;
}

std::tuple<std::string, std::string, nlohmann::json> Report::table2_text(const std::vector<Table2Row>& rows,
                                                                         bool error) const {
  const std::size_t columns = std::max(config.train_subjects.size(), config.test_subjects.size());
  std::ostringstream csv;
  csv << "row,subjects";
  for (const char* split : {"train_motions", "test_motions"}) {
    for (std::size_t c = 0; c < columns; ++c) csv << "," << split << "_subject_" << c + 1;
    csv << "," << split << "_avg";
  }
  csv << "\n";
  std::ostringstream md;
  md << "| " << (error ? "RMS error of σ vs ground truth [mm]" : "σ [mm]") << " | subjects |";
  for (const char* split : {"train", "test"}) {
    for (std::size_t c = 0; c < columns; ++c) md << " " << split << " " << c + 1 << " |";
    md << " " << split << " avg |";
  }
  md << "\n|---|---|";
  for (std::size_t c = 0; c < 2 * (columns + 1); ++c) md << "---|";
  md << "\n";
  nlohmann::json rows_json = nlohmann::json::array();
  for (const Table2Row& row : rows) {
    std::string names;
    for (const std::string& s : row.subjects) names += (names.empty() ? "" : ";") + s;
    csv << '"' << row.label << "\"," << names;
    md << "| " << row.label << " | " << names << " |";
    nlohmann::json rj = {{"row", row.label}, {"subjects", row.subjects}};
    for (const auto* motions : {&config.train_motions, &config.test_motions}) {
      std::vector<double> values;
      for (std::size_t c = 0; c < columns; ++c) {
        const double v = c < row.subjects.size()
                             ? (error ? row.error(row.subjects[c], *motions) : row.value(row.subjects[c], *motions))
                             : kNaN;
        if (c < row.subjects.size()) values.push_back(v);
        csv << "," << cell(v);
        md << " " << cell(v) << " |";
      }
      const double avg = mean_of_finite(values);
      csv << "," << cell(avg);
      md << " **" << cell(avg) << "** |";
      rj[motions == &config.train_motions ? "train_motions" : "test_motions"] = {{"values", values}, {"avg", avg}};
    }
    csv << "\n";
    md << "\n";
    rows_json.push_back(rj);
  }
  return std::make_tuple(csv.str(), md.str(), rows_json);
}

void Report::write_table2(RunFolder& run, nlohmann::json& summary) const {
  const std::vector<Table2Row> rows = table2_rows();
  const std::string l2 = lambda_text("l2"), ours = lambda_text("ours");
  const auto [csv, md, js] = table2_text(rows, false);
  write_text_atomically(run.stage("table2.csv"), csv);
  std::ostringstream doc;
  doc << "# Table 2: standard deviation of per-vertex dynamics [mm]\n\n"
      << "Mean over the soft region's skin vertices of σ_i (docs/physics.md §4), averaged over the motions of each "
         "split.\n"
      << "Train motions: ";
  for (const auto& m : config.train_motions) doc << m << " ";
  doc << "· test motions: ";
  for (const auto& m : config.test_motions) doc << m << " ";
  doc << "· λ (L2) = " << l2 << ", λ (ours) = " << ours
      << (config.cross_validation
              ? fmt::format(" (chosen by cross-validation, rule {}: docs/fit.md, \"Choosing λ\").\n\n",
                            lambda_rule_name(config.lambda_rule))
              : std::string(" (the first of the λ values: no cross-validation).\n\n"))
      << md;
  const auto [csv_e, md_e, js_e] = table2_text(rows, true);
  doc << "\n## RMS error of the per-vertex σ against the ground truth [mm]\n\n" << md_e;
  write_text_atomically(run.stage("table2.md"), doc.str());
  write_text_atomically(run.stage("table2_error.csv"), csv_e);
  summary["table2"] = js;
  summary["table2_error"] = js_e;
}

/// covariance.csv (Fig. 7): per control point the norm of the covariance over subjects of each method's κ̂; the
/// fields for dynamics.vtp.
vtk::Fields Report::write_covariance(RunFolder& run, nlohmann::json& summary) const {
  const int N = parameterization->num_controls();
  const meshing::LayerMesh& mesh = parameterization->mesh();
  vtk::Fields cov_fields;
  std::ostringstream cov_csv;
  cov_csv << "control_point,vertex,covariance_truth,covariance_independent,covariance_l2,covariance_ours\n";
  std::map<std::string, Eigen::VectorXd> cov_norm;
  auto covariance_norms = [&](const std::vector<material::KappaMatrix>& per_subject) {
    Eigen::VectorXd norms(N);
    for (int i = 0; i < N; ++i) {
      Eigen::MatrixXd pts(static_cast<Eigen::Index>(per_subject.size()), 3);
      for (std::size_t s = 0; s < per_subject.size(); ++s)
        pts.row(static_cast<Eigen::Index>(s)) = per_subject[s].row(i);
      const Eigen::MatrixXd centred = pts.rowwise() - pts.colwise().mean();
      norms[i] = (centred.transpose() * centred / static_cast<double>(pts.rows())).norm();
    }
    return norms;
  };
  {
    std::vector<material::KappaMatrix> truth_k, indep_k, l2_k, ours_k;
    for (const std::string& s : config.train_subjects) {
      if (true_parameters) {
        const material::KappaMatrix t = normalized_truth(s);
        material::KappaMatrix at_controls(N, 3);
        for (int i = 0; i < N; ++i)
          at_controls.row(i) = t.row(parameterization->control_region_vertices()[static_cast<std::size_t>(i)]);
        truth_k.push_back(at_controls);
      }
      const body::Betas& beta = betas.at(s);
      indep_k.push_back(fits.at("independent/" + s).kappa_normalized(beta, bounds));
      l2_k.push_back(fits.at("full/l2").kappa_normalized(beta, bounds));
      ours_k.push_back(fits.at("full/ours").kappa_normalized(beta, bounds));
    }
    if (true_parameters) cov_norm["truth"] = covariance_norms(truth_k);
    cov_norm["independent"] = covariance_norms(indep_k);
    cov_norm["l2"] = covariance_norms(l2_k);
    cov_norm["ours"] = covariance_norms(ours_k);
    for (int i = 0; i < N; ++i)
      cov_csv << i << "," << parameterization->control_vertices()[static_cast<std::size_t>(i)] << ","
              << (true_parameters ? fmt::format("{:.6g}", cov_norm.at("truth")[i]) : std::string())
              << fmt::format(",{:.6g},{:.6g},{:.6g}", cov_norm["independent"][i], cov_norm["l2"][i],
                             cov_norm["ours"][i])
              << "\n";
    for (const auto& [tag, norms] : cov_norm)
      cov_fields.point_data.push_back({"covariance_" + tag, on_body(*model, mesh, parameterization->phi() * norms)});
    write_text_atomically(run.stage("covariance.csv"), cov_csv.str());
    summary["covariance_mean"] = {{"truth", true_parameters ? cov_norm.at("truth").mean() : kNaN},
                                  {"independent", cov_norm["independent"].mean()},
                                  {"l2", cov_norm["l2"].mean()},
                                  {"ours", cov_norm["ours"].mean()}};
  }
  return cov_fields;
}

/// parameter_error.csv: the fitted field φ κ̂ against the true κ̂ on the region vertices, and the truth's
/// shape-dependent part beside the independent fits' error (truth_identifiability).
void Report::write_parameter_error(RunFolder& run, nlohmann::json& summary) const {
  std::ostringstream pe;
  pe << "method,subject,split,thickness_rms,young_tangent_rms,young_normal_rms,young_tangent_log_rms,young_normal_"
        "log_rms\n";
  nlohmann::json pj = nlohmann::json::array();
  auto add = [&](const std::string& method, const std::string& fit, const std::string& subject,
                 const std::string& split) {
    const GroundTruthCase& t = truth->at(subject + "_" + config.train_motions.front());
    const material::KappaMatrix fitted = parameterization->field(fits.at(fit).kappa(t.beta, bounds));
    const material::KappaMatrix fn = material::normalize(fitted, bounds), tn = material::normalize(t.kappa, bounds);
    const auto R = static_cast<double>(fn.rows());
    const Eigen::RowVector3d rms = ((fn - tn).array().square().colwise().sum() / R).sqrt().matrix();
    const double lt = std::sqrt((fitted.col(1).array() / t.kappa.col(1).array()).log().square().mean());
    const double ln = std::sqrt((fitted.col(2).array() / t.kappa.col(2).array()).log().square().mean());
    pe << method << "," << subject << "," << split
       << fmt::format(",{:.4f},{:.4f},{:.4f},{:.4f},{:.4f}\n", rms[0], rms[1], rms[2], lt, ln);
    pj.push_back({{"method", method},
                  {"subject", subject},
                  {"split", split},
                  {"thickness_rms", rms[0]},
                  {"young_tangent_rms", rms[1]},
                  {"young_normal_rms", rms[2]},
                  {"young_tangent_log_rms", lt},
                  {"young_normal_log_rms", ln}});
  };
  // The truth's shape-dependent part: per subject, RMS over the region of κ̂*(β_s) minus the train subjects' mean
  // κ̂*. The independent fits must recover it to within about half of it for the study to tell regularizers
  // apart (docs/fit.md, "A truth the data can identify").
  material::KappaMatrix truth_mean;
  for (const std::string& s : config.train_subjects) {
    const material::KappaMatrix tn = normalized_truth(s);
    truth_mean = truth_mean.size() ? material::KappaMatrix(truth_mean + tn) : tn;
  }
  truth_mean /= static_cast<double>(config.train_subjects.size());
  Eigen::RowVector3d signal = Eigen::RowVector3d::Zero(), independent = Eigen::RowVector3d::Zero();
  auto shape_part = [&](const std::string& subject, const std::string& split) {
    const material::KappaMatrix d = normalized_truth(subject) - truth_mean;
    const Eigen::RowVector3d rms = (d.array().square().colwise().sum() / static_cast<double>(d.rows())).sqrt().matrix();
    pe << "Truth shape dependence," << subject << "," << split
       << fmt::format(",{:.4f},{:.4f},{:.4f},,\n", rms[0], rms[1], rms[2]);
    pj.push_back({{"method", "Truth shape dependence"},
                  {"subject", subject},
                  {"split", split},
                  {"thickness_rms", rms[0]},
                  {"young_tangent_rms", rms[1]},
                  {"young_normal_rms", rms[2]}});
    return rms;
  };
  for (const std::string& s : config.train_subjects) signal += shape_part(s, "train");
  signal /= static_cast<double>(config.train_subjects.size());
  for (const std::string& s : config.train_subjects) {
    add("Independent", "independent/" + s, s, "train");
    const nlohmann::json& row = pj.back();
    independent += Eigen::RowVector3d(row["thickness_rms"].get<double>(), row["young_tangent_rms"].get<double>(),
                                      row["young_normal_rms"].get<double>());
    add("Full opt. L2", "full/l2", s, "train");
    add("Full opt. ours", "full/ours", s, "train");
  }
  for (const std::string& s : config.test_subjects) {
    add("Generaliz. L2", "full/l2", s, "test");
    add("Generaliz. ours", "full/ours", s, "test");
  }
  independent /= static_cast<double>(config.train_subjects.size());
  write_text_atomically(run.stage("parameter_error.csv"), pe.str());
  summary["parameter_error"] = pj;
  nlohmann::json identifiable;
  for (int c = 0; c < material::kNumKappa; ++c)
    identifiable[std::string(material::kKappaNames[static_cast<std::size_t>(c)])] = {
        {"truth_shape_rms", signal[c]},
        {"independent_error_rms", independent[c]},
        {"ratio", independent[c] / signal[c]},
        {"recovered_within_half", independent[c] <= 0.5 * signal[c]}};
  summary["truth_identifiability"] = identifiable;
}

/// dynamics.vtp (Figures 3, 4, 6, 8): σ of the truth and of each fit per subject on the template, with `fields`.
void Report::write_dynamics_fields(RunFolder& run, vtk::Fields fields) const {
  const meshing::LayerMesh& mesh = parameterization->mesh();
  const std::string l2 = lambda_text("l2"), ours = lambda_text("ours");
  auto motion_mean = [&](const std::string& fit, const std::string& subject) {
    Eigen::VectorXd sum;
    int n = 0;
    for (const std::string& m : config.train_motions) {
      const auto it = evaluations.find(key_of(fit, subject, m));
      if (it == evaluations.end()) continue;
      sum = n == 0 ? it->second.sigma : Eigen::VectorXd(sum + it->second.sigma);
      ++n;
    }
    return n ? Eigen::VectorXd(sum / n) : Eigen::VectorXd();
  };
  std::vector<std::string> all = config.train_subjects;
  all.insert(all.end(), config.test_subjects.begin(), config.test_subjects.end());
  for (const std::string& s : all) {
    if (const GroundTruthCase* first = truth_of(s, config.train_motions.front())) {
      Eigen::VectorXd t = Eigen::VectorXd::Zero(first->sigma_normal.size());
      for (const std::string& m : config.train_motions) {
        const GroundTruthCase& c = *truth_of(s, m);
        t += (c.sigma_normal.array().square() + c.sigma_tangent.array().square()).sqrt().matrix();
      }
      fields.point_data.push_back(
          {"sigma_truth_" + s, on_body(*model, mesh, t / static_cast<double>(config.train_motions.size()))});
    }
    std::vector<std::pair<std::string, std::string>> fit_list{{"full_l2", "full/l2"}, {"full_ours", "full/ours"}};
    if (fits.count("independent/" + s)) fit_list.emplace_back("independent", "independent/" + s);
    if (config.cross_validation && fits.count("cv/l2/" + l2 + "/" + s))
      fit_list.emplace_back("cv_l2", "cv/l2/" + l2 + "/" + s);
    if (config.cross_validation && fits.count("cv/ours/" + ours + "/" + s))
      fit_list.emplace_back("cv_ours", "cv/ours/" + ours + "/" + s);
    for (const auto& [tag, fit] : fit_list) {
      const Eigen::VectorXd v = motion_mean(fit, s);
      if (v.size()) fields.point_data.push_back({"sigma_" + tag + "_" + s, on_body(*model, mesh, v)});
    }
  }
  vtk::write_surface(run.stage("dynamics.vtp"), model->v_template, model->faces, fields);
}

/// fits.csv with the stages' stopping tests, the fitted materials of every subject and the shape models.
void Report::write_fits_and_materials(RunFolder& run, nlohmann::json& summary) const {
  const int N = parameterization->num_controls();
  std::ostringstream fc;
  fc << "fit,controls,iterations,loss_fit_mm2,loss_reg,simulations,jacobians,seconds,reason\n";
  nlohmann::json fj = nlohmann::json::array();
  for (const auto& [name, fit] : fits)
    for (const reduced::FitStageReport& s : fit.stages) {
      fc << name << "," << s.controls << "," << s.iterations << fmt::format(",{:.6g},{:.6g},", s.loss_fit, s.loss_reg)
         << s.simulations << "," << s.jacobians << fmt::format(",{:.2f},", s.seconds) << s.reason << "\n";
      nlohmann::json stage = reduced::stage_report_json(s);
      stage["fit"] = name;
      fj.push_back(std::move(stage));
    }
  write_text_atomically(run.stage("fits.csv"), fc.str());
  summary["fits"] = fj;
  // How the stages stopped: convergence tests, or the iteration cap (the safety net) when it was hit.
  nlohmann::json stops = nlohmann::json::object();
  for (const nlohmann::json& stage : fj) {
    const std::string reason = stage.at("reason");
    stops[reason] = stops.value(reason, 0) + 1;
  }
  summary["stage_stops"] = stops;
  std::vector<std::string> all = config.train_subjects;
  all.insert(all.end(), config.test_subjects.begin(), config.test_subjects.end());
  for (const std::string tag : {"l2", "ours"})
    for (const std::string& s : all) {
      material::MaterialFile file;
      file.body = model->name;
      file.subject = s;
      file.bounds = bounds;
      const material::KappaMatrix k = fits.at("full/" + tag).kappa(betas.at(s), bounds);
      for (int i = 0; i < N; ++i) {
        material::MaterialControlPoint cp;
        cp.vertex = parameterization->control_vertices()[static_cast<std::size_t>(i)];
        cp.kappa = material::from_row(k.row(i));
        file.control_points.push_back(cp);
      }
      material::save_material_file(
          run.stage("materials/" + tag + "/" + s + ".toml"), file,
          fmt::format("Fitted by sflsh validate (full optimization, {} regularizer, λ = {:g})",
                      tag == std::string("l2") ? "L2" : "local", best.count(tag) ? best.at(tag) : 0.0));
    }
  // The full fits themselves: κ̂(β) for any subject (shape_model_file.hpp; the crowd's materials).
  for (const std::string tag : {"l2", "ours"}) {
    reduced::ShapeModelFile file = reduced::make_shape_model_file(
        fits.at("full/" + tag).shape(), *model, parameterization->control_vertices(), bounds, poisson, saturation);
    file.region = region;
    file.mesh = meshing::size_preset_name(config.mesh);
    reduced::ShapeModelFit fit;
    fit.regularizer = tag == std::string("l2") ? reduced::Regularizer::l2 : reduced::Regularizer::local;
    fit.lambda = best.count(tag) ? best.at(tag) : 0.0;
    fit.subjects = config.train_subjects;
    fit.motions = config.train_motions;
    file.fit = fit;
    reduced::save_shape_model_file(
        run.stage("shape_models/" + tag + ".toml"), file,
        fmt::format("Fitted by sflsh validate --preset {} (full optimization, {} regularizer, "
                    "λ = {:g}, N = {})",
                    config.preset, tag == std::string("l2") ? "L2" : "local", fit.lambda, N));
  }
}

void Report::write(RunFolder& run, nlohmann::json& summary) const {
  write_table2(run, summary);
  if (config.cross_validation) write_lambda_sweep(run, summary);
  const vtk::Fields covariance = write_covariance(run, summary);
  if (true_parameters) write_parameter_error(run, summary);
  write_dynamics_fields(run, covariance);
  write_fits_and_materials(run, summary);
  write_regularizer_comparison(*this, run, summary);
}

}  // namespace sflsh::validate
