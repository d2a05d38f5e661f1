// sflsh body info | generate | export | render
#include "commands.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/open_body.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/body/surface_checks.hpp>
#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/render.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>

#include <chrono>
#include <iostream>
#include <sstream>

namespace sflsh::app {

namespace {

std::vector<double> to_vector(const body::Betas& beta) { return {beta.data(), beta.data() + beta.size()}; }

void run_info(const SubjectOptions& opt, bool json) {
  const body::BodyModel model = load_selected_body(opt);
  std::string label;
  const body::Betas beta = selected_betas(opt, label);
  const body::RowMatrixX3d shaped = body::shaped_template(model, beta);
  const body::JointPositions joints = body::regress_joints(model, shaped);
  // Self-intersection tests need a closed manifold; check the topology first.
  body::SurfaceReport report = body::check_surface(shaped, model.faces, false);
  if (report.closed && report.edge_manifold && report.vertex_manifold)
    report = body::check_surface(shaped, model.faces, true);
  const Eigen::RowVector3d lo = shaped.colwise().minCoeff(), hi = shaped.colwise().maxCoeff();
  nlohmann::json out;
  out["name"] = model.name;
  out["vertices"] = model.num_vertices();
  out["faces"] = model.num_faces();
  out["shape_components"] = model.shapedirs.cols();
  out["pose_correctives"] = model.has_pose_correctives();
  out["subject"] = label;
  out["beta"] = to_vector(beta);
  out["stature_m"] = hi(1) - lo(1);
  out["bounding_box_m"] = {{lo(0), lo(1), lo(2)}, {hi(0), hi(1), hi(2)}};
  out["surface"] = {{"ok", report.ok()},
                    {"closed", report.closed},
                    {"manifold", report.edge_manifold && report.vertex_manifold},
                    {"self_intersections", report.self_intersections},
                    {"components", report.connected_components},
                    {"volume_m3", report.volume},
                    {"area_m2", report.area}};
  nlohmann::json joint_list = nlohmann::json::array();
  for (int k = 0; k < body::kNumJoints; ++k)
    joint_list.push_back({{"index", k},
                          {"name", body::kJointNames[static_cast<std::size_t>(k)]},
                          {"parent", model.parents[static_cast<std::size_t>(k)]},
                          {"position_m", {joints(k, 0), joints(k, 1), joints(k, 2)}}});
  out["joints"] = joint_list;
  if (json) {
    std::cout << out.dump(2) << "\n";
    return;
  }
  std::cout << fmt::format("body        {}\n", model.name)
            << fmt::format("vertices    {}\nfaces       {}\n", model.num_vertices(), model.num_faces())
            << fmt::format("shape dirs  {}   pose correctives: {}\n", model.shapedirs.cols(),
                           model.has_pose_correctives() ? "yes" : "no")
            << fmt::format("subject     {}  β = [{:.2f}]\n", label, fmt::join(to_vector(beta), ", "))
            << fmt::format("stature     {:.3f} m   volume {:.4f} m³   area {:.3f} m²\n", hi(1) - lo(1), report.volume,
                           report.area)
            << fmt::format("surface     {}\n", report.summary());
  for (int k = 0; k < body::kNumJoints; ++k)
    std::cout << fmt::format("  joint {:2d} {:<15} parent {:2d}  ({:+.3f}, {:+.3f}, {:+.3f})\n", k,
                             body::kJointNames[static_cast<std::size_t>(k)], model.parents[static_cast<std::size_t>(k)],
                             joints(k, 0), joints(k, 1), joints(k, 2));
}

struct GenerateOptions {
  std::string out;
  body::OpenBodyOptions generator;
};

void run_generate(const GenerateOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::filesystem::path out = opt.out.empty() ? body::default_body_path() : std::filesystem::path(opt.out);
  require(opt.generator.population >= 20, "--population must be at least 20, got {}", opt.generator.population);
  require(opt.generator.target_vertices >= 1000 && opt.generator.target_vertices <= 50000,
          "--vertices must be in 1000..50000, got {}", opt.generator.target_vertices);
  body::OpenBodyResult result = body::generate_open_body(opt.generator);
  result.model.name = "sflsh-open-body";
  std::vector<body::Subject> subjects;
  for (const body::OpenBodySubject& s : result.subjects)
    subjects.push_back({s.name, s.split, "open", s.description, s.beta});
  if (!out.parent_path().empty()) ensure_directory(out.parent_path());
  const std::filesystem::path subjects_path = out.parent_path() / (out.stem().string() + "_subjects.toml");
  body::save_body(out, result.model);
  std::ostringstream header;
  header << "Subjects of the open body (" << out.filename().string() << "), written by `sflsh body generate`.\n"
         << "Each is defined by anthropometric factors; beta is its projection on the body's PCA shape basis.";
  body::save_subjects(subjects_path, subjects, header.str());
  std::string variance;
  for (Eigen::Index i = 0; i < result.explained_variance.size(); ++i)
    variance += fmt::format("{}{:.3f}", i ? " " : "", result.explained_variance(i));
  logger()->info("wrote {} ({} vertices, {} faces) and {} in {:.1f} s; explained variance per component: {}",
                 out.string(), result.model.num_vertices(), result.model.num_faces(), subjects_path.string(),
                 seconds_since(t0), variance);
}

struct ExportOptions {
  SubjectOptions subject;
  std::string out;
};

void run_export(const ExportOptions& opt, const Invocation& invocation) {
  const auto t0 = std::chrono::steady_clock::now();
  const body::BodyModel model = load_selected_body(opt.subject);
  std::string label;
  const body::Betas beta = selected_betas(opt.subject, label);
  const body::RowMatrixX3d shaped = body::shaped_template(model, beta);
  const body::JointPositions joints = body::regress_joints(model, shaped);
  vtk::Fields fields;
  fields.point_data.push_back({"shape_offset", shaped - model.v_template, false});
  fields.point_data.push_back({"skin_weights", model.weights, false});
  fields.point_data.push_back({"skin_weights_argmax", dominant_joint(model), true});
  RunFolder run(opt.out);
  vtk::write_surface(run.stage("body.vtp"), shaped, vtk::Cells(model.faces), fields);
  nlohmann::json summary = summary_header("body export", invocation.argc, invocation.argv);
  summary["subject"] = label;
  summary["beta"] = to_vector(beta);
  summary["files"] = {"body.vtp"};
  summary["point_data"] = {"shape_offset", "skin_weights", "skin_weights_argmax"};
  nlohmann::json jl = nlohmann::json::object();
  for (int k = 0; k < body::kNumJoints; ++k)
    jl[body::kJointNames[static_cast<std::size_t>(k)]] = {joints(k, 0), joints(k, 1), joints(k, 2)};
  summary["joints_m"] = jl;
  write_summary(run, summary, seconds_since(t0));
  run.commit();
  logger()->info("wrote {}/body.vtp ({})", opt.out, label);
}

struct RenderOptions {
  SubjectOptions subject;
  std::string subjects = "";
  std::string views = "front,side";
  std::string motion;
  double time = 1.0;
  std::string out;
  int width = 700;
  int height = 900;
};

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> items;
  std::string item;
  std::istringstream in(text);
  while (std::getline(in, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

void run_render(const RenderOptions& opt, const Invocation& invocation) {
  const auto t0 = std::chrono::steady_clock::now();
  const body::BodyModel model = load_selected_body(opt.subject);
  std::vector<std::pair<std::string, body::Betas>> bodies;
  if (!opt.subjects.empty()) {
    const auto all = body::default_subjects();
    for (const std::string& name : split_list(opt.subjects)) {
      if (name == "all" || name == "open" || name == "paper") {
        for (const body::Subject& s : all)
          if (name == "all" || (name == "open") == (s.body == "open")) bodies.emplace_back(s.name, s.beta);
      } else {
        bodies.emplace_back(name, body::find_subject(all, name).beta);
      }
    }
  } else {
    std::string label;
    bodies.emplace_back("", selected_betas(opt.subject, label));
    bodies.back().first = label;
  }
  const std::vector<std::string> views = split_list(opt.views);
  require(!views.empty(), "--views: expected a comma-separated list such as front,side");
  std::optional<body::Motion> motion;
  if (!opt.motion.empty()) motion = body::load_motion(opt.motion, 60.0, 0);

  RunFolder run(opt.out);
  nlohmann::json files = nlohmann::json::array();
  std::vector<render::Surface> lineup;
  double x = 0.0;
  for (const auto& [name, beta] : bodies) {
    const body::Poser poser(model, beta);
    render::Surface surface;
    surface.triangles = model.faces;
    if (motion) {
      const auto frame = static_cast<std::size_t>(
          std::clamp(opt.time * motion->fps, 0.0, static_cast<double>(motion->num_frames() - 1)));
      surface.points = (poser.pose(motion->poses[frame], motion->trans[frame]) * motion->world_from_body.transpose());
    } else {
      surface.points = poser.shaped();
    }
    for (const std::string& view : views) {
      const std::string file = fmt::format("{}_{}.png", name, view);
      render::View v;
      v.name = view;
      v.width = opt.width;
      v.height = opt.height;
      v.title = motion ? fmt::format("{}  {} t={:.2f}s", name, motion->name, opt.time) : name;
      render::render_png(run.stage(file), {surface}, v);
      files.push_back(file);
    }
    const double width = surface.points.col(0).maxCoeff() - surface.points.col(0).minCoeff();
    surface.offset.x() = x + 0.5 * width;
    x += width + 0.15;
    lineup.push_back(std::move(surface));
  }
  if (lineup.size() > 1) {
    const double total = x;
    for (auto& s : lineup) s.offset.x() -= 0.5 * total;
    render::View v;
    v.name = "front";
    v.width = std::min(4000, 260 * static_cast<int>(lineup.size()) + 200);
    v.height = opt.height;
    v.title = "line-up";
    render::render_png(run.stage("lineup_front.png"), lineup, v);
    files.push_back("lineup_front.png");
  }
  nlohmann::json summary = summary_header("body render", invocation.argc, invocation.argv);
  summary["files"] = files;
  write_summary(run, summary, seconds_since(t0));
  run.commit();
  logger()->info("wrote {} pictures to {}", files.size(), opt.out);
}

}  // namespace

void register_body_commands(CLI::App& app, const Invocation& invocation) {
  CLI::App* body_cmd = app.add_subcommand("body", "The parametric body: inspect, generate, export, render");
  body_cmd->require_subcommand(1);

  auto info_opt = std::make_shared<SubjectOptions>();
  auto info_json = std::make_shared<bool>(false);
  CLI::App* info = body_cmd->add_subcommand("info", "Print a body model's arrays, joints and surface checks");
  add_body_option(*info, *info_opt);
  add_subject_options(*info, *info_opt);
  info->add_flag("--json", *info_json, "Print as JSON");
  info->callback([info_opt, info_json] { run_info(*info_opt, *info_json); });

  auto gen = std::make_shared<GenerateOptions>();
  CLI::App* generate = body_cmd->add_subcommand(
      "generate", "Generate the open body (data/open_body.npz and data/open_body_subjects.toml)");
  generate->add_option("--out", gen->out, "Output .npz (default: data/open_body.npz)");
  generate->add_option("--population", gen->generator.population, "Sampled bodies for the shape PCA")
      ->capture_default_str();
  generate->add_option("--seed", gen->generator.seed, "Population seed")->capture_default_str();
  generate->add_option("--vertices", gen->generator.target_vertices, "Approximate vertex count")->capture_default_str();
  generate->callback([gen] { run_generate(*gen); });

  auto exp_opt = std::make_shared<ExportOptions>();
  CLI::App* exp = body_cmd->add_subcommand("export", "Write the shaped rest body as .vtp with skinning weights");
  add_body_option(*exp, exp_opt->subject);
  add_subject_options(*exp, exp_opt->subject);
  exp->add_option("--out", exp_opt->out, "Output folder")->required();
  exp->callback([exp_opt, invocation] { run_export(*exp_opt, invocation); });

  auto ren = std::make_shared<RenderOptions>();
  CLI::App* rend =
      body_cmd->add_subcommand("render", "Render bodies to PNG offscreen (needs an X display: run under xvfb-run -a)");
  add_body_option(*rend, ren->subject);
  add_subject_options(*rend, ren->subject);
  rend->add_option("--subjects", ren->subjects, "Comma-separated subject names, or all | open | paper");
  rend->add_option("--views", ren->views, "Comma-separated views: front, side, back, three_quarter, top")
      ->capture_default_str();
  rend->add_option("--motion", ren->motion, "Pose the bodies along this motion (name or AMASS .npz)");
  rend->add_option("--time", ren->time, "Time in the motion [s]")->capture_default_str();
  rend->add_option("--width", ren->width, "Picture width [px]")->capture_default_str();
  rend->add_option("--height", ren->height, "Picture height [px]")->capture_default_str();
  rend->add_option("--out", ren->out, "Output folder")->required();
  rend->callback([ren, invocation] { run_render(*ren, invocation); });
}

}  // namespace sflsh::app
