// sflsh motion list | export
#include "commands.hpp"

#include <sflsh/body/motion.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/core/xdmf_series.hpp>

#include <chrono>
#include <iostream>
#include <optional>

namespace sflsh::app {

namespace {

struct MotionExportOptions {
  SubjectOptions subject;
  std::string motion;
  int frames = 0;
  double fps = 60.0;
  std::string out;
  std::string format = "vtk";         ///< vtk: body.pvd + body_NNNNNN.vtp (the export's contract) | xdmf
  std::string precision = "float32";  ///< of an xdmf series (the .vtp frames are Float64)
  std::string compression;            ///< zlib | none (xdmf, default zlib); zlib | lz4 | none (vtk, default zlib)
};

void run_motion_export(const MotionExportOptions& opt, const Invocation& invocation) {
  const auto t0 = std::chrono::steady_clock::now();
  require(opt.fps > 0.0, "--fps must be positive, got {}", opt.fps);
  require(opt.frames >= 0, "--frames must be non-negative, got {}", opt.frames);
  const body::BodyModel model = load_selected_body(opt.subject);
  std::string subject_label;
  const body::Betas beta = selected_betas(opt.subject, subject_label, "motion export");
  const body::Motion motion = body::load_motion(opt.motion, opt.fps, opt.frames);
  motion.validate();

  const body::Poser poser(model, beta);
  const Eigen::MatrixXd labels = dominant_joint(model);
  vtk::Cells faces = model.faces;

  const bool xdmf = opt.format == "xdmf";
  const vtk::Compression compression =
      opt.compression.empty() ? vtk::Compression::zlib : vtk::parse_compression(opt.compression, "--compression");
  require(!xdmf || compression != vtk::Compression::lz4,
          "--compression lz4: HDF5 has no LZ4 filter here (expected zlib or none for --format xdmf)");
  RunFolder run(opt.out);
  // vtk: one .vtp per frame listed in body.pvd; xdmf: body.xmf + body.h5, the triangles and skin_weights_argmax once.
  std::optional<vtk::PvdSeries> series;
  std::optional<xdmf::Series> compact;
  if (xdmf) {
    run.stage("body.h5");
    compact.emplace(run.stage("body.xmf"), faces, xdmf::parse_precision(opt.precision, "--precision"), compression);
    vtk::Fields fixed;
    fixed.point_data.push_back({"skin_weights_argmax", labels, true});
    compact->set_static(fixed);
  } else {
    series.emplace(run.stage("body.pvd"));
  }
  Progress progress("posing frames", motion.num_frames());
  body::RowMatrixX3d previous;
  for (std::size_t t = 0; t < motion.num_frames(); ++t) {
    body::RowMatrixX3d posed = poser.pose(motion.poses[t], motion.trans[t]);
    posed = (posed * motion.world_from_body.transpose()).eval();
    require(posed.allFinite(), "frame {}: posed body has non-finite coordinates", t);
    vtk::Fields fields;
    fields.point_data.push_back({"displacement", posed - poser.shaped(), false});
    Eigen::MatrixXd velocity = Eigen::MatrixXd::Zero(posed.rows(), 3);
    if (t > 0) velocity = (posed - previous) * motion.fps;
    fields.point_data.push_back({"velocity", velocity, false});
    if (xdmf) {
      fields.point_data.push_back({"Normals", vtk::vertex_normals(posed, faces), false});  // the .vtp frames' too
      compact->write(motion.time(t), posed, fields);
    } else {
      fields.point_data.push_back({"skin_weights_argmax", labels, true});
      fields.field_data.push_back({"TimeValue", Eigen::MatrixXd::Constant(1, 1, motion.time(t)), false});
      const std::string name = fmt::format("body_{:06d}.vtp", t);
      vtk::write_surface(run.stage(name), posed, faces, fields, compression);
      series->add(motion.time(t), name);
    }
    previous = std::move(posed);
    progress.advance();
  }
  progress.finish();
  if (xdmf)
    compact->close();
  else
    series->write();

  nlohmann::json summary = summary_header("motion export", invocation.argc, invocation.argv);
  summary["body"] = body::body_label(opt.subject);
  summary["subject"] = subject_label;
  summary["beta"] = std::vector<double>(beta.data(), beta.data() + beta.size());
  summary["motion"] = {{"name", motion.name},
                       {"source", motion.source},
                       {"fps", motion.fps},
                       {"frames", motion.num_frames()},
                       {"duration_s", motion.duration()}};
  summary["vertices"] = model.num_vertices();
  summary["faces"] = model.num_faces();
  summary["series"] = xdmf ? "body.xmf" : "body.pvd";
  summary["frame_files"] =
      xdmf ? std::string("body.h5") : fmt::format("body_000000.vtp … body_{:06d}.vtp", motion.num_frames() - 1);
  summary["point_data"] = {"displacement", "velocity", "skin_weights_argmax"};
  summary["output"] = {{"format", opt.format},
                       {"precision", xdmf ? opt.precision : "float64"},
                       {"compression", vtk::to_string(compression)}};
  write_summary(run, summary, seconds_since(t0), {.wall_time_s = true});
  run.commit();
  logger()->info("wrote {} frames of '{}' for {} to {}/{}", motion.num_frames(), motion.name, subject_label, opt.out,
                 xdmf ? "body.xmf" : "body.pvd");
}

}  // namespace

void register_motion_commands(CLI::App& app, const Invocation& invocation) {
  CLI::App* motion = app.add_subcommand("motion", "Motions: procedural DYNA-like motions and AMASS files");
  motion->require_subcommand(1);

  CLI::App* list = motion->add_subcommand("list", "List the procedural motions");
  auto json = std::make_shared<bool>(false);
  list->add_flag("--json", *json, "Print as JSON");
  list->callback([json] {
    // The five DYNA-like motions (in DYNA order), then the showcase motions (dance).
    std::vector<std::string> names = body::procedural_motion_names();
    for (const std::string& name : body::showcase_motion_names()) names.push_back(name);
    if (*json) {
      nlohmann::json out = nlohmann::json::array();
      for (const std::string& name : names)
        out.push_back({{"name", name}, {"description", body::procedural_motion_description(name)}});
      std::cout << out.dump(2) << "\n";
      return;
    }
    for (const std::string& name : names)
      std::cout << fmt::format("{:<18} {}\n", name, body::procedural_motion_description(name));
  });

  auto opt = std::make_shared<MotionExportOptions>();
  CLI::App* exp = motion->add_subcommand(
      "export",
      "Pose a body along a motion and write a ParaView series (one .vtp per frame + body.pvd, or body.xmf + body.h5 "
      "with --format xdmf)");
  add_body_option(*exp, opt->subject);
  exp->add_option("--motion", opt->motion, "Procedural motion name (see `motion list`) or an AMASS .npz")->required();
  add_subject_options(*exp, opt->subject);
  exp->add_option("--frames", opt->frames, "Number of frames (default: the motion's own length)");
  exp->add_option("--fps", opt->fps, "Frame rate of the output [1/s]")->capture_default_str();
  exp->add_option("--format", opt->format,
                  "Time series: vtk (body.pvd of one .vtp per frame, Float64) | xdmf (body.xmf + body.h5: triangles "
                  "and skin_weights_argmax once, the positions, displacement and velocity per frame; docs/output.md)")
      ->check(CLI::IsMember({"vtk", "xdmf"}))
      ->capture_default_str();
  exp->add_option("--precision", opt->precision, "Floating-point precision of an xdmf series: float32 | float64")
      ->check(CLI::IsMember({"float64", "float32"}))
      ->capture_default_str();
  exp->add_option("--compression", opt->compression, "Compression: zlib (default) | none, or lz4 for vtk frames")
      ->check(CLI::IsMember({"lz4", "zlib", "none"}));
  exp->add_option("--out", opt->out, "Output folder")->required();
  exp->callback([opt, invocation] { run_motion_export(*opt, invocation); });
}

}  // namespace sflsh::app
