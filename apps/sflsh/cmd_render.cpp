// sflsh render --run DIR --out FILE.png: a picture of a simulation's result, the posed body of one frame coloured
// by its soft-tissue motion (σ per vertex, or the frame's soft-tissue displacement), drawn offscreen.
#include "commands.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/render.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>

#include <algorithm>
#include <filesystem>
#include <regex>

namespace sflsh::app {

namespace {

namespace fs = std::filesystem;

struct RenderRunOptions {
  std::string run;
  std::string color = "sigma";
  std::string frame = "peak";
  std::string view = "three_quarter";
  int width = 900;
  int height = 1000;
  std::string out;
};

/// The body frames of a run folder (body_000000.vtp, …), in frame order.
std::vector<fs::path> body_frames(const fs::path& run) {
  std::vector<fs::path> frames;
  const std::regex pattern(R"(body_\d{6}\.vtp)");
  for (const auto& entry : fs::directory_iterator(run))
    if (std::regex_match(entry.path().filename().string(), pattern)) frames.push_back(entry.path());
  std::sort(frames.begin(), frames.end());
  return frames;
}

/// Largest soft-tissue displacement of a frame [m].
double peak_displacement(const fs::path& frame) {
  const Eigen::MatrixXd u = vtk::read_point_array(frame, "soft_tissue_displacement");
  return u.rowwise().norm().maxCoeff();
}

void run_render(const RenderRunOptions& opt) {
  const fs::path run = opt.run;
  require(fs::is_directory(run), "--run {}: not a folder, expected the --out folder of `sflsh simulate`", opt.run);
  const std::vector<fs::path> frames = body_frames(run);
  require(!frames.empty(),
          "--run {}: no body_NNNNNN.vtp frames, expected a `sflsh simulate` run written with --format vtk", opt.run);
  require(fs::path(opt.out).extension() == ".png", "--out {}: expected a .png file", opt.out);

  // The frame: the one with the largest soft-tissue displacement, or the one asked for.
  std::size_t index = 0;
  if (opt.frame == "peak") {
    double best = -1.0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const double d = peak_displacement(frames[i]);
      if (d > best) best = d, index = i;
    }
  } else {
    std::size_t pos = 0;
    long asked = -1;
    try {
      asked = std::stol(opt.frame, &pos);
    } catch (const std::exception&) {
      pos = 0;
    }
    require(pos == opt.frame.size() && asked >= 0 && static_cast<std::size_t>(asked) < frames.size(),
            "--frame {}: expected peak or a written frame index in [0, {})", opt.frame, frames.size());
    index = static_cast<std::size_t>(asked);
  }

  render::Surface surface;
  surface.points = vtk::read_points(frames[index]);
  surface.triangles = vtk::read_cells(frames[index]);
  require(surface.triangles.cols() == 3, "{}: expected a triangle surface", frames[index].string());
  const std::vector<std::string> field_names = vtk::read_field_array_names(frames[index]);
  const bool timed = std::find(field_names.begin(), field_names.end(), "TimeValue") != field_names.end();
  const double time = timed ? vtk::read_field_array(frames[index], "TimeValue")(0, 0) : 0.0;
  std::string legend;
  if (opt.color == "sigma") {
    const fs::path dynamics = run / "dynamics.vtp";
    require(fs::exists(dynamics), "--run {}: no dynamics.vtp, expected the σ map `sflsh simulate` writes", opt.run);
    const Eigen::MatrixXd sigma = vtk::read_point_array(dynamics, "sigma");
    require(sigma.rows() == surface.points.rows(), "{}: {} σ values for {} body vertices", dynamics.string(),
            sigma.rows(), surface.points.rows());
    surface.scalars = sigma.col(0);
    legend = "sigma";
  } else {
    const Eigen::MatrixXd u = vtk::read_point_array(frames[index], "soft_tissue_displacement");
    surface.scalars = 1e3 * u.rowwise().norm();
    legend = "|soft-tissue displacement|";
  }
  require(surface.scalars->allFinite(), "{}: non-finite {} values", frames[index].string(), opt.color);

  std::string subject = "body", motion;
  if (fs::exists(run / "summary.json")) {
    const nlohmann::json summary = read_json(run / "summary.json");
    subject = summary.value("subject", subject);
    if (summary.contains("motion") && summary["motion"].is_object()) motion = summary["motion"].value("name", "");
  }
  render::View view;
  view.name = opt.view;
  view.width = opt.width;
  view.height = opt.height;
  view.scalar_range = std::make_pair(0.0, std::max(surface.scalars->maxCoeff(), 1e-9));
  view.title = fmt::format("{} {} t={:.2f}s  {} 0-{:.2f} mm (blue-red)", subject, motion, time, legend,
                           view.scalar_range->second);
  render::render_png(opt.out, {surface}, view);
  logger()->info("render: frame {} of {} coloured by {} → {}", index, frames.size(), opt.color, opt.out);
}

}  // namespace

void register_render_commands(CLI::App& app, const Invocation& /*invocation*/) {
  auto opt = std::make_shared<RenderRunOptions>();
  CLI::App* cmd = app.add_subcommand(
      "render", "A picture of a simulation: the posed body of one frame coloured by its soft-tissue motion (PNG)");
  cmd->add_option("--run", opt->run, "The --out folder of `sflsh simulate` (vtk format)")->required();
  cmd->add_option("--color", opt->color, "sigma (σ of the whole run, mm) | displacement (the frame's, mm)")
      ->check(CLI::IsMember({"sigma", "displacement"}));
  cmd->add_option("--frame", opt->frame, "peak (largest soft-tissue displacement) or a frame index");
  cmd->add_option("--view", opt->view, "front | back | side | three_quarter | top")
      ->check(CLI::IsMember({"front", "back", "side", "three_quarter", "top"}));
  cmd->add_option("--width", opt->width, "Picture width [px]")->check(CLI::Range(64, 8000));
  cmd->add_option("--height", opt->height, "Picture height [px]")->check(CLI::Range(64, 8000));
  cmd->add_option("--out", opt->out, "The PNG to write")->required();
  cmd->callback([opt] { run_render(*opt); });
}

}  // namespace sflsh::app
