#pragma once
// Evaluations of fitted models and the report files of `sflsh validate` (Table 2, cross-validation and λ
// sweep, parameter covariance, parameter recovery, dynamics fields). Private to the experiments.
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/reduced/elasticity_fit.hpp>
#include <sflsh/validate/experiments.hpp>
#include <sflsh/validate/ground_truth.hpp>

#include <fmt/format.h>

#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <tuple>

namespace sflsh::validate {

/// A table cell of the report's CSV and Markdown: the value with 3 decimals, empty when not finite.
inline std::string cell(double v) { return std::isfinite(v) ? fmt::format("{:.3f}", v) : ""; }

struct Evaluation {
  Eigen::VectorXd sigma;    ///< per region vertex [mm]
  double mean_sigma = 0.0;  ///< [mm]
  double rms_error = 0.0;   ///< RMS over region vertices of σ − σ* [mm]
};

struct Report {
  ValidateConfig config;
  material::ParameterBounds bounds;
  const body::BodyModel* model = nullptr;
  const reduced::LayerParameterization* parameterization = nullptr;  ///< of the final stage
  const std::map<std::string, GroundTruthCase>* truth = nullptr;     ///< key "<subject>_<motion>"
  std::map<std::string, reduced::FitResult> fits;  ///< "independent/S", "cv/<reg>/<λ>/S", "full/<reg>"
  std::map<std::string, double> best;              ///< λ chosen per regularizer tag
  std::map<std::string, LambdaChoice> choices;     ///< how it was chosen (cross-validation runs only)
  std::map<std::string, body::Betas> betas;        ///< every subject's β
  bool true_parameters = true;                     ///< the truth carries κ (synthetic); DYNA does not
  double poisson = 0.2, saturation = 4.0;          ///< uniform ν and s of the layers (SFLSH §3)
  std::string region;                              ///< the layer region the control points lie on

  const GroundTruthCase* truth_of(const std::string& subject, const std::string& motion) const;
  std::map<std::string, Evaluation> evaluations;  ///< "<fit>|<subject>|<motion>"

  /// Simulates every (fit, subject, motion) the report needs and has not evaluated yet.
  void evaluate(reduced::SimulationPool& pool, const reduced::ReducedModel& reduced_model,
                const reduced::ReducedOptions& options,
                const std::map<std::string, std::unique_ptr<reduced::DynamicsCase>>& cases);
  /// λ for "l2" / "ours" by config.lambda_rule from the cross-validation errors (train motions of the left-out
  /// subjects), one fold per train subject.
  LambdaChoice choose_lambda(const std::string& tag) const;
  /// The leave-one-out errors of "l2" / "ours" per λ of its grid, in ascending λ.
  std::vector<LambdaScore> lambda_scores(const std::string& tag) const;
  /// Writes every report file into the run folder and adds their key numbers to `summary`.
  void write(RunFolder& run, nlohmann::json& summary) const;

  /// Subjects a fit is evaluated on.
  std::vector<std::string> evaluated_subjects(const std::string& fit) const;
  /// Mean of the per-motion mean σ over `motions` (a Table 2 entry) [mm]; NaN when missing.
  double table_entry(const std::string& fit, const std::string& subject, const std::vector<std::string>& motions) const;
  double table_error(const std::string& fit, const std::string& subject, const std::vector<std::string>& motions) const;
  double truth_entry(const std::string& subject, const std::vector<std::string>& motions) const;
  /// Mean over `motions` of one Evaluation member; NaN entries (missing) are skipped.
  double motion_mean(const std::string& fit, const std::string& subject, const std::vector<std::string>& motions,
                     double Evaluation::*value) const;

 private:
  /// A row of Table 2: its label, subjects, and the σ entry and its error for (subject, motions).
  struct Table2Row {
    std::string label;
    std::vector<std::string> subjects;
    std::function<double(const std::string&, const std::vector<std::string>&)> value;
    std::function<double(const std::string&, const std::vector<std::string>&)> error;
  };
  std::vector<Table2Row> table2_rows() const;
  /// Table 2 (σ, or its error when `error`) as CSV, Markdown and JSON.
  std::tuple<std::string, std::string, nlohmann::json> table2_text(const std::vector<Table2Row>& rows,
                                                                   bool error) const;
  std::string lambda_text(const std::string& tag) const;  ///< the chosen λ of "l2" / "ours" as "{:g}"
  material::KappaMatrix normalized_truth(const std::string& subject) const;  ///< κ̂* per region vertex
  void write_table2(RunFolder& run, nlohmann::json& summary) const;
  void write_lambda_sweep(RunFolder& run, nlohmann::json& summary) const;
  vtk::Fields write_covariance(RunFolder& run, nlohmann::json& summary) const;
  void write_parameter_error(RunFolder& run, nlohmann::json& summary) const;
  void write_dynamics_fields(RunFolder& run, vtk::Fields fields) const;
  void write_fits_and_materials(RunFolder& run, nlohmann::json& summary) const;
};

/// regularizer_comparison.csv (the full fits L² and ours paired on every test subject × motion: relative σ error
/// overall and per body part, the winner) and shape_dependence_error.csv (κ̂(β) − κ̂(β̄) against the truth's), with
/// win counts, sign tests and means in `summary` (regularizer_comparison.cpp).
void write_regularizer_comparison(const Report& report, RunFolder& run, nlohmann::json& summary);

}  // namespace sflsh::validate
