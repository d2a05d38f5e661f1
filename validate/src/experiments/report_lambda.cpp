// The report's λ sweep (report.hpp): the leave-one-out scores per λ, λ chosen from them, and cross_validation.csv,
// lambda_sweep.csv and lambda_sweep.png (Fig. 5).
#include "report.hpp"

#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/chart.hpp>
#include <sflsh/core/log.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <sstream>

namespace sflsh::validate {

std::vector<LambdaScore> Report::lambda_scores(const std::string& tag) const {
  std::vector<double> grid = config.lambdas_for(tag);
  std::sort(grid.begin(), grid.end());
  std::vector<LambdaScore> sweep;
  for (double lambda : grid) {
    LambdaScore score{lambda, {}};
    for (const std::string& s : config.train_subjects)
      score.fold_errors.push_back(table_error(fmt::format("cv/{}/{:g}/{}", tag, lambda, s), s, config.train_motions));
    sweep.push_back(std::move(score));
  }
  return sweep;
}

LambdaChoice Report::choose_lambda(const std::string& tag) const {
  return validate::choose_lambda(lambda_scores(tag), config.lambda_rule, fmt::format("validate: regularizer {}", tag));
}

/// cross_validation.csv, lambda_sweep.csv and .png (Fig. 5) of the leave-one-out fits.
void Report::write_lambda_sweep(RunFolder& run, nlohmann::json& summary) const {
  std::ostringstream cv, sweep;
  cv << "regularizer,lambda,left_out,train_motions_rms_error_mm,test_motions_rms_error_mm,train_motions_mean_sigma_"
        "mm,"
        "test_motions_mean_sigma_mm\n";
  // cv_train_motions_standard_error_mm: over the left-out subjects, of the mean; chosen: 1 for the λ the rule took.
  sweep << "regularizer,lambda,cv_train_motions_rms_error_mm,cv_test_motions_rms_error_mm,"
           "cv_train_motions_standard_error_mm,chosen\n";
  chart::Chart chart;
  chart.title = "Cross-validation error vs lambda";
  chart.x_label = "lambda";
  chart.y_label = "RMS error of sigma on left-out subjects [mm]";
  chart.log_x = true;
  nlohmann::json sweep_json = nlohmann::json::array();
  std::size_t colour = 0;
  nlohmann::json bracketed = nlohmann::json::object();
  for (const std::string tag : {"l2", "ours"}) {
    chart::Series series, lower, upper;  // the mean and ± one standard error of it (Fig. 5)
    series.label = tag == std::string("l2") ? "L2" : "ours";
    series.line = chart::Line::solid;
    series.color = lower.color = upper.color = chart::palette(colour++);
    lower.label = series.label + " - standard error";
    upper.label = series.label + " + standard error";
    lower.line = upper.line = chart::Line::dashed;
    lower.marker = upper.marker = chart::Marker::none;
    std::vector<double> grid = config.lambdas_for(tag);
    std::sort(grid.begin(), grid.end());
    std::vector<double> means;
    for (double lambda : grid) {
      std::vector<double> tr, te;
      for (const std::string& s : config.train_subjects) {
        const std::string fit = fmt::format("cv/{}/{:g}/{}", tag, lambda, s);
        tr.push_back(table_error(fit, s, config.train_motions));
        te.push_back(table_error(fit, s, config.test_motions));
        cv << tag << "," << lambda << "," << s << "," << cell(tr.back()) << "," << cell(te.back()) << ","
           << cell(table_entry(fit, s, config.train_motions)) << "," << cell(table_entry(fit, s, config.test_motions))
           << "\n";
      }
      const bool chosen = best.count(tag) && best.at(tag) == lambda;
      sweep << tag << "," << lambda << "," << cell(mean_of_finite(tr)) << "," << cell(mean_of_finite(te)) << ","
            << cell(standard_error_of_mean(tr)) << "," << (chosen ? 1 : 0) << "\n";
      series.x.push_back(lambda);
      series.y.push_back(mean_of_finite(tr));
      lower.x.push_back(lambda);
      lower.y.push_back(mean_of_finite(tr) - standard_error_of_mean(tr));
      upper.x.push_back(lambda);
      upper.y.push_back(mean_of_finite(tr) + standard_error_of_mean(tr));
      means.push_back(mean_of_finite(tr));
      sweep_json.push_back({{"regularizer", tag},
                            {"lambda", lambda},
                            {"train_motions", mean_of_finite(tr)},
                            {"test_motions", mean_of_finite(te)}});
    }
    chart.series.push_back(series);
    if (grid.size() > 1) {
      chart.series.push_back(lower);
      chart.series.push_back(upper);
    }
    // Does the CV curve rise on both sides of its least λ? If not, the grid has not found the minimum.
    const auto least = static_cast<std::size_t>(std::min_element(means.begin(), means.end()) - means.begin());
    bracketed[tag] = least > 0 && least + 1 < means.size();
    if (!bracketed[tag].get<bool>())
      logger()->warn(
          "validate: the cross-validation error of {} does not rise on both sides of its least λ = {:g} "
          "(grid {:g} … {:g}): widen --lambdas-{} or raise --lambda-extensions",
          tag, grid[least], grid.front(), grid.back(), tag);
  }
  summary["lambda_sweep_bracketed"] = bracketed;
  write_text_atomically(run.stage("cross_validation.csv"), cv.str());
  write_text_atomically(run.stage("lambda_sweep.csv"), sweep.str());
  summary["lambda_sweep"] = sweep_json;
  summary["lambda"] = best;
  summary["lambda_rule"] = lambda_rule_name(config.lambda_rule);
  nlohmann::json choice_json = nlohmann::json::object();
  for (const auto& [tag, c] : choices)
    choice_json[tag] = {{"lambda", c.lambda},
                        {"least_lambda", c.least_lambda},
                        {"least_error_mm", c.least_error},
                        {"standard_error_mm", c.standard_error},
                        {"threshold_mm", c.threshold}};
  summary["lambda_choice"] = choice_json;
  try {
    chart::write_chart_png(run.stage("lambda_sweep.png"), chart);
  } catch (const Error& e) {
    logger()->warn("validate: lambda_sweep.png not written ({})", e.what());
  }
}

}  // namespace sflsh::validate
