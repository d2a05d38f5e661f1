// sflsh render --run DIR --out FILE.png: a picture of a simulation's result, the posed body of one frame coloured
// by its soft-tissue motion (σ per vertex, or the frame's soft-tissue displacement), drawn offscreen; with
// --strip N, evenly spaced frames of a scene run side by side (every body and object of scene.pvd). Every picture
// has a colour bar with the quantity and its unit, a perceptually uniform map (viridis by default, cividis; rainbow
// on request: --colormap) and the subject, motion and time in its title (from the run's summary.json).
#include "commands.hpp"

#include <sflsh/core/array_units.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/render.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/core/xdmf_reader.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
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
  int strip = 0;                     ///< > 0: a strip of that many frames of a scene run
  std::string map;                   ///< a .vtp surface whose point arrays are drawn side by side
  std::vector<std::string> fields;   ///< with map: the arrays, one panel each
  std::string label = "sigma";       ///< with map: what the arrays are, for the title
  double max = 0.0;                  ///< with map: top of the colour scale (0: the 99th percentile of all panels)
  std::string colormap = "viridis";  ///< viridis | cividis | rainbow
  std::string out;
};

/// "t = 0 to 2.00 s" over `frames` frames at `fps`.
std::string time_span(double frames, double fps) {
  return fps > 0.0 && frames > 1.0 ? fmt::format("t = 0 to {:.2f} s", (frames - 1.0) / fps) : std::string("t = 0 s");
}

/// What a run folder's summary.json says about its subjects, motions and time, for a picture's title:
/// "OPEN_TRAIN_1 | jiggle_on_toes | t = 0 to 2.00 s" (`sflsh simulate`, `compare`), the bodies of a scene, or
/// `sflsh validate`'s subjects and motions; empty without a summary.
std::string run_description(const fs::path& folder) {
  if (!fs::exists(folder / "summary.json")) return "";
  const nlohmann::json s = read_json(folder / "summary.json");
  const auto text = [](const nlohmann::json& j, const char* key) {
    return j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : std::string();
  };
  const auto join = [](const nlohmann::json& list) {
    std::string out;
    if (list.is_array())
      for (const auto& item : list)
        if (item.is_string()) out += (out.empty() ? "" : ", ") + item.get<std::string>();
    return out;
  };
  if (s.contains("scene") && s["scene"].is_object() && s.contains("bodies") && s["bodies"].is_array()) {
    std::string bodies;
    for (const auto& b : s["bodies"])
      bodies +=
          fmt::format("{}{}: {} ({})", bodies.empty() ? "" : ", ", text(b, "name"),
                      text(b, "subject").empty() ? std::string("mean shape") : text(b, "subject"), text(b, "motion"));
    return bodies;
  }
  if (s.contains("config") && s["config"].is_object()) {  // sflsh validate
    const nlohmann::json& c = s["config"];
    return fmt::format("subjects {} | mean over the motions {} | {} frames each",
                       join(c.value("train_subjects", nlohmann::json())),
                       join(c.value("train_motions", nlohmann::json())), c.value("frames", 0));
  }
  std::string motion = text(s, "motion");
  double frames = 0.0, fps = 0.0;
  if (s.contains("motion") && s["motion"].is_object()) {
    motion = text(s["motion"], "name");
    frames = s["motion"].value("frames", 0.0);
    fps = s["motion"].value("fps", 0.0);
  }
  if (motion.empty() && text(s, "subject").empty()) return "";
  return fmt::format("{} | {} | {}", text(s, "subject"), motion, time_span(frames, fps));
}

/// The written body frames of a `sflsh simulate` run folder, in frame order: body.xmf + body.h5 (--format xdmf) or
/// body_000000.vtp, … (--format vtk).
class BodyFrames {
 public:
  explicit BodyFrames(const fs::path& run) {
    const std::regex pattern(R"(body_\d{6}\.vtp)");
    for (const auto& entry : fs::directory_iterator(run))
      if (std::regex_match(entry.path().filename().string(), pattern)) vtp_.push_back(entry.path());
    std::sort(vtp_.begin(), vtp_.end());
    if (vtp_.empty() && fs::exists(run / "body.xmf")) xdmf_.emplace(run / "body.xmf");
  }
  std::size_t size() const { return xdmf_ ? xdmf_->steps() : vtp_.size(); }
  /// The file frame `i` is read from (for messages).
  std::string file(std::size_t i) const { return xdmf_ ? xdmf_->heavy_data().string() : vtp_[i].string(); }
  vtk::Points points(std::size_t i) const { return xdmf_ ? xdmf_->points(i) : vtk::read_points(vtp_[i]); }
  vtk::Cells triangles(std::size_t i) const { return xdmf_ ? xdmf_->cells() : vtk::read_cells(vtp_[i]); }
  /// The frame's time [s] (0 for a .vtp without TimeValue).
  double time(std::size_t i) const {
    if (xdmf_) return xdmf_->time(i);
    const std::vector<std::string> names = vtk::read_field_array_names(vtp_[i]);
    const bool timed = std::find(names.begin(), names.end(), "TimeValue") != names.end();
    return timed ? vtk::read_field_array(vtp_[i], "TimeValue")(0, 0) : 0.0;
  }
  /// posed − skinned per vertex [m].
  Eigen::MatrixXd soft_tissue_displacement(std::size_t i) const {
    return xdmf_ ? xdmf_->point_array(i, "soft_tissue_displacement")
                 : vtk::read_point_array(vtp_[i], "soft_tissue_displacement");
  }

 private:
  std::vector<fs::path> vtp_;
  std::optional<xdmf::SeriesReader> xdmf_;
};

void run_render(const RenderRunOptions& opt) {
  const fs::path run = opt.run;
  require(fs::is_directory(run), "--run {}: not a folder, expected the --out folder of `sflsh simulate`", opt.run);
  const BodyFrames frames(run);
  require(frames.size() > 0,
          "--run {}: no body.xmf and no body_NNNNNN.vtp frames, expected the --out folder of `sflsh simulate`",
          opt.run);
  require(fs::path(opt.out).extension() == ".png", "--out {}: expected a .png file", opt.out);

  // The frame: the one with the largest soft-tissue displacement, or the one asked for.
  std::size_t index = 0;
  if (opt.frame == "peak") {
    double best = -1.0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const double d = frames.soft_tissue_displacement(i).rowwise().norm().maxCoeff();
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
  surface.points = frames.points(index);
  surface.triangles = frames.triangles(index);
  require(surface.triangles.cols() == 3, "{}: expected a triangle surface", frames.file(index));
  const double time = frames.time(index);
  std::string legend, quantity;
  if (opt.color == "sigma") {
    const fs::path dynamics = run / "dynamics.vtp";
    require(fs::exists(dynamics), "--run {}: no dynamics.vtp, expected the σ map `sflsh simulate` writes", opt.run);
    const Eigen::MatrixXd sigma = vtk::read_point_array(dynamics, "sigma");
    require(sigma.rows() == surface.points.rows(), "{}: {} σ values for {} body vertices", dynamics.string(),
            sigma.rows(), surface.points.rows());
    surface.scalars = sigma.col(0);
    legend = "sigma [mm]";
    quantity = "coloured by sigma over the run (dynamics.vtp)";
  } else {
    const Eigen::MatrixXd u = frames.soft_tissue_displacement(index);
    surface.scalars = 1e3 * u.rowwise().norm();
    legend = "soft-tissue\ndisplacement\n[mm]";
    quantity = "coloured by the frame's |soft-tissue displacement|";
  }
  require(surface.scalars->allFinite(), "{}: non-finite {} values", frames.file(index), opt.color);

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
  view.colormap = opt.colormap;
  view.scalar_range = std::make_pair(0.0, std::max(surface.scalars->maxCoeff(), 1e-9));
  view.scalar_title = legend;
  view.title = fmt::format("{} | {} | t = {:.2f} s (frame {}{})\n{}", subject, motion, time, index,
                           opt.frame == "peak" ? ", the largest soft-tissue displacement" : "", quantity);
  render::render_png(opt.out, {surface}, view);
  logger()->info("render: frame {} of {} coloured by {} → {}", index, frames.size(), opt.color, opt.out);
}

/// One DataSet of a .pvd collection.
struct PvdEntry {
  double time = 0.0;
  std::string name;
  fs::path file;
};

/// The timed entries of scene.pvd (our own collection file: one DataSet per line), grouped by time in order.
std::vector<std::vector<PvdEntry>> scene_frames(const fs::path& pvd) {
  std::ifstream in(pvd);
  require(in.good(), "{}: cannot be read", pvd.string());
  std::vector<std::vector<PvdEntry>> frames;
  const std::regex timestep(R"re(timestep="([^"]+)")re"), name(R"re(name="([^"]*)")re"), file(R"re(file="([^"]+)")re");
  std::string line;
  while (std::getline(in, line)) {
    std::smatch t, n, f;
    if (!std::regex_search(line, t, timestep) || !std::regex_search(line, f, file)) continue;
    PvdEntry e;
    try {
      e.time = std::stod(t[1].str());
    } catch (const std::exception&) {
      throw_error("{}: timestep \"{}\" is not a number", pvd.string(), t[1].str());
    }
    if (std::regex_search(line, n, name)) e.name = n[1].str();
    e.file = pvd.parent_path() / f[1].str();
    if (frames.empty() || frames.back().front().time != e.time) frames.emplace_back();
    frames.back().push_back(e);
  }
  return frames;
}

/// A strip of `opt.strip` evenly spaced written frames of a scene run: every body and object of scene.pvd in the
/// world, bodies coloured by their soft-tissue displacement (mm; skinned bodies in skin tone), objects grey,
/// the time under each panel.
void run_render_strip(const RenderRunOptions& opt) {
  const fs::path run = opt.run;
  require(fs::is_directory(run), "--run {}: not a folder, expected the --out folder of `sflsh simulate --scene`",
          opt.run);
  const fs::path pvd = run / "scene.pvd";
  require(fs::exists(pvd),
          "--run {}: no scene.pvd, expected the --out folder of `sflsh simulate --scene` written with format vtk",
          opt.run);
  require(fs::path(opt.out).extension() == ".png", "--out {}: expected a .png file", opt.out);
  const std::vector<std::vector<PvdEntry>> frames = scene_frames(pvd);
  require(!frames.empty(), "{}: no timed frames", pvd.string());
  const auto count = std::min<std::size_t>(static_cast<std::size_t>(opt.strip), frames.size());
  std::vector<std::size_t> chosen;  // evenly spaced, first and last included
  for (std::size_t i = 0; i < count; ++i)
    chosen.push_back(count == 1 ? frames.size() - 1
                                : static_cast<std::size_t>(
                                      std::lround(static_cast<double>(i) * static_cast<double>(frames.size() - 1) /
                                                  static_cast<double>(count - 1))));
  std::vector<render::Panel> panels;
  double peak = 0.0;
  for (std::size_t index : chosen) {
    render::Panel panel;
    panel.caption = fmt::format("t = {:.2f} s", frames[index].front().time);
    for (const PvdEntry& e : frames[index]) {
      require(fs::exists(e.file), "{}: lists {}, which is missing", pvd.string(), e.file.string());
      render::Surface surface;
      surface.points = vtk::read_points(e.file);
      surface.triangles = vtk::read_cells(e.file);
      require(surface.triangles.cols() == 3, "{}: expected a triangle surface", e.file.string());
      if (e.name == "objects") {
        surface.color = {0.62, 0.64, 0.68};
        surface.framed = false;  // a floor would shrink the bodies to dots
      } else {
        const std::vector<std::string> arrays = vtk::read_point_array_names(e.file);
        if (std::find(arrays.begin(), arrays.end(), "soft_tissue_displacement") != arrays.end()) {
          const Eigen::MatrixXd u = vtk::read_point_array(e.file, "soft_tissue_displacement");
          surface.scalars = 1e3 * u.rowwise().norm();
          require(surface.scalars->allFinite(), "{}: non-finite soft_tissue_displacement", e.file.string());
          peak = std::max(peak, surface.scalars->maxCoeff());
        }
      }
      panel.surfaces.push_back(std::move(surface));
    }
    panels.push_back(std::move(panel));
  }
  std::string scene = run.filename().string();
  if (fs::exists(run / "summary.json")) {
    const nlohmann::json summary = read_json(run / "summary.json");
    if (summary.contains("scene") && summary["scene"].is_object()) scene = summary["scene"].value("name", scene);
  }
  render::View view;
  view.name = opt.view;
  view.width = opt.width;
  view.height = opt.height;
  view.colormap = opt.colormap;
  view.scalar_range = std::make_pair(0.0, std::max(peak, 1e-9));
  view.scalar_title = "soft-tissue\ndisplacement\n[mm]";
  const std::string bodies = run_description(run);
  view.title = fmt::format("{}{}{}\n|soft-tissue displacement|, the time under each panel", scene,
                           bodies.empty() ? "" : " | ", bodies);
  render::render_strip_png(opt.out, panels, view);
  logger()->info("render: {} of {} written frames of {} → {}", panels.size(), frames.size(), pvd.string(), opt.out);
}

/// Point arrays of one surface side by side (e.g. `sflsh validate`'s dynamics.vtp: σ of the truth and of each fit
/// per subject, the paper's Figs. 3, 4, 6, 8), one colour scale over every panel, each captioned with its array.
void run_render_map(const RenderRunOptions& opt) {
  const fs::path file = opt.map;
  require(fs::exists(file) && file.extension() == ".vtp", "--map {}: expected an existing .vtp surface", opt.map);
  require(!opt.fields.empty(), "--map {}: --fields is required (the point arrays to draw)", opt.map);
  require(fs::path(opt.out).extension() == ".png", "--out {}: expected a .png file", opt.out);
  const std::vector<std::string> arrays = vtk::read_point_array_names(file);
  render::Surface base;
  base.points = vtk::read_points(file);
  base.triangles = vtk::read_cells(file);
  require(base.triangles.cols() == 3, "{}: expected a triangle surface", file.string());
  std::vector<render::Panel> panels;
  std::vector<double> all;  // every panel's values, for the colour scale
  for (const std::string& name : opt.fields) {
    if (std::find(arrays.begin(), arrays.end(), name) == arrays.end()) {
      std::string list;
      for (const std::string& a : arrays) list += (list.empty() ? "" : ", ") + a;
      throw_error("--fields {}: {} has no such point array (it has {})", name, file.string(), list);
    }
    const Eigen::MatrixXd values = vtk::read_point_array(file, name);
    require(values.rows() == base.points.rows(), "{}: {} has {} values for {} points", file.string(), name,
            values.rows(), base.points.rows());
    render::Surface surface = base;
    surface.scalars = values.cols() == 1 ? Eigen::VectorXd(values.col(0)) : Eigen::VectorXd(values.rowwise().norm());
    // NaN marks vertices a field does not cover (outside the soft region): drawn at zero.
    surface.scalars = surface.scalars->unaryExpr([](double v) { return std::isfinite(v) ? v : 0.0; });
    all.insert(all.end(), surface.scalars->data(), surface.scalars->data() + surface.scalars->size());
    render::Panel panel;
    panel.caption = name;
    panel.surfaces.push_back(std::move(surface));
    panels.push_back(std::move(panel));
  }
  render::View view;
  view.name = opt.view;
  view.width = opt.width;
  view.height = opt.height;
  view.colormap = opt.colormap;
  // A few extreme vertices would wash out the maps: by default the scale ends at the 99th percentile (above
  // saturates: the top colour), or at --max.
  const auto rank = static_cast<std::ptrdiff_t>(0.99 * static_cast<double>(all.size() - 1));
  std::nth_element(all.begin(), all.begin() + rank, all.end());
  const double top = opt.max > 0.0 ? opt.max : all[static_cast<std::size_t>(rank)];
  view.scalar_range = std::make_pair(0.0, std::max(top, 1e-9));
  const std::string unit(units::of(opt.fields.front()));
  view.scalar_title = unit.empty() ? opt.label : fmt::format("{} [{}]", opt.label, unit);
  const std::string description = run_description(file.parent_path());
  view.title = fmt::format("{} of {}{}{}\nthe scale ends at {:.3g} {}: above it the colour saturates", opt.label,
                           file.filename().string(), description.empty() ? "" : " | ", description, top,
                           opt.max > 0.0 ? "(--max)" : "(the 99th percentile of all panels)");
  render::render_strip_png(opt.out, panels, view);
  logger()->info("render: {} arrays of {} → {}", panels.size(), file.string(), opt.out);
}

}  // namespace

void register_render_commands(CLI::App& app, const Invocation& /*invocation*/) {
  auto opt = std::make_shared<RenderRunOptions>();
  CLI::App* cmd = app.add_subcommand(
      "render", "A picture of a simulation: the posed body of one frame coloured by its soft-tissue motion (PNG)");
  CLI::Option* run = cmd->add_option("--run", opt->run, "The --out folder of `sflsh simulate` (vtk format)");
  CLI::Option* map =
      cmd->add_option("--map", opt->map,
                      "A .vtp surface (e.g. `sflsh validate`'s dynamics.vtp): its --fields side by side, one colour "
                      "scale (the paper's σ maps)");
  cmd->add_option("--fields", opt->fields, "With --map: the point arrays to draw, one panel each (comma-separated)")
      ->delimiter(',');
  cmd->add_option("--label", opt->label, "With --map: what the arrays are, for the title (default sigma)");
  cmd->add_option("--max", opt->max, "With --map: top of the colour scale (default: the 99th percentile of all panels)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--colormap", opt->colormap,
                  "Colour map: viridis (default) | cividis (both perceptually uniform) | rainbow (blue to red)")
      ->check(CLI::IsMember({"viridis", "cividis", "rainbow"}));
  cmd->add_option("--color", opt->color, "sigma (σ of the whole run, mm) | displacement (the frame's, mm)")
      ->check(CLI::IsMember({"sigma", "displacement"}));
  cmd->add_option("--frame", opt->frame, "peak (largest soft-tissue displacement) or a frame index");
  cmd->add_option("--view", opt->view, "front | back | side | three_quarter | top")
      ->check(CLI::IsMember({"front", "back", "side", "three_quarter", "top"}));
  CLI::Option* width = cmd->add_option("--width", opt->width, "Picture width [px] (with --strip: of each panel, 360)")
                           ->check(CLI::Range(64, 8000));
  CLI::Option* height =
      cmd->add_option("--height", opt->height, "Picture height [px] (with --strip: of each panel, 560)")
          ->check(CLI::Range(64, 8000));
  CLI::Option* strip =
      cmd->add_option("--strip", opt->strip,
                      "A scene run (`simulate --scene`): that many evenly spaced frames side by side, every body and "
                      "object, coloured by soft-tissue displacement (mm)")
          ->check(CLI::Range(1, 24));
  cmd->add_option("--out", opt->out, "The PNG to write")->required();
  cmd->callback([opt, width, height, strip, run, map, cmd] {
    require((run->count() > 0) != (map->count() > 0), "render: give either --run (a simulation) or --map (a surface)");
    if (map->count() > 0) {
      require(strip->count() == 0 && cmd->count("--frame") == 0 && cmd->count("--color") == 0,
              "--map: draws the --fields of one surface; leave out --strip, --frame and --color");
      if (width->count() == 0) opt->width = 360;
      if (height->count() == 0) opt->height = 560;
      return run_render_map(*opt);
    }
    if (strip->count() == 0) return run_render(*opt);
    require(cmd->count("--frame") == 0 && cmd->count("--color") == 0,
            "--strip: draws evenly spaced frames coloured by soft-tissue displacement; leave out --frame and --color");
    if (width->count() == 0) opt->width = 360;
    if (height->count() == 0) opt->height = 560;
    run_render_strip(*opt);
  });
}

}  // namespace sflsh::app
