// Benchmark: the crowd scene of SFLSH Fig. 1 (data/scenes/crowd.toml: 25 avatars with random shapes, each its
// own shape-dependent material from the shipped shape model, dancing with per-avatar time offsets, reduced
// solver) run by the scene runner, parallel over bodies: frames per second of the whole crowd without writing
// on 1 and T threads and with writing every frame on T threads (into a scratch folder, removed afterwards),
// against the paper's 1.2 fps single-threaded, with the breakdown of a frame's wall time: stepping the
// bodies, posing the written surfaces, the rest of the output on the stepping thread (σ, queueing, waiting for
// the writer) and the overhead; the background writer's own busy time is listed beside it.
// Usage: bench_crowd [--scene data/scenes/crowd.toml] [--frames 60] [--threads 2] [--every 1] [--format vtk|xdmf]
//                    [--out bench_crowd.json]
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/xdmf_series.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/scene/scene_file.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <string>

int main(int argc, char** argv) {
  using namespace sflsh;
  std::string scene_path = std::string(SFLSH_DATA_DIR) + "/scenes/crowd.toml", out = "bench_crowd.json";
  std::string format;  // empty: the scene's [output] format
  int frames = 60, threads = 2, every = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i];
    if (key == "--scene")
      scene_path = argv[i + 1];
    else if (key == "--frames")
      frames = std::stoi(argv[i + 1]);
    else if (key == "--threads")
      threads = std::stoi(argv[i + 1]);
    else if (key == "--every")
      every = std::stoi(argv[i + 1]);
    else if (key == "--out")
      out = argv[i + 1];
    else if (key == "--format")
      format = argv[i + 1];
    else {
      std::cerr << "bench_crowd: unknown option " << key << "\n";
      return 2;
    }
  }
  if (frames < 2 || threads < 1 || every < 1) {
    std::cerr << "bench_crowd: --frames must be ≥ 2, --threads and --every ≥ 1\n";
    return 2;
  }
  const std::filesystem::path scratch =
      std::filesystem::temp_directory_path() / fmt::format("bench_crowd_{}", getpid());
  try {
    logger()->set_level(spdlog::level::warn);
    scene::Scene scene = scene::load_scene(scene_path);
    if (!format.empty()) {  // as sflsh simulate --format: the scene's compression, lz4 refused for xdmf
      model::check_output_format(format, "--format");
      scene.output.format = format;
      require(format != "xdmf" || scene.output.series_compression != vtk::Compression::lz4,
              "--format xdmf: the scene's compression lz4 is not available for HDF5 datasets");
    }
    const bool xdmf = scene.output.format == "xdmf";
    const std::string written =
        xdmf ? fmt::format("xdmf series ({}, {})",
                           scene.output.precision == xdmf::Precision::float32 ? "Float32" : "Float64",
                           vtk::to_string(scene.output.series_compression))
             : fmt::format("vtk frame files (Float64, {})", vtk::to_string(scene.output.compression));
    struct Run {
      int threads;
      bool write;
    };
    std::vector<Run> runs = {{1, false}, {threads, false}, {threads, true}};
    if (threads == 1) runs.erase(runs.begin());
    nlohmann::json rows = nlohmann::json::array();
    std::cout << fmt::format("crowd scene {}: {} frames at {} fps; writing: every {} frame(s), {}\n\n", scene_path,
                             frames, scene.fps, every, written);
    std::cout << fmt::format("{:<8} {:<8} {:>8} {:>8} {:>10} | {:>9} {:>9} {:>9} {:>9} | {:>9} {:>11} {:>9} {:>9}\n",
                             "threads", "writing", "avatars", "fps", "ms/frame", "step", "posing", "output", "overhead",
                             "solve cpu", "writer busy", "setup [s]", "vs 1.2");
    for (const Run& r : runs) {
      scene::SceneRunOptions options;
      options.frames = frames;
      options.threads = r.threads;
      options.write_frames = r.write;
      options.every = every;
      if (r.write) options.out = scratch;
      const nlohmann::json s = scene::run_scene(scene, options);
      if (r.write) std::filesystem::remove_all(scratch);
      const nlohmann::json& t = s["timings"];
      const double loop = t["loop_seconds"].get<double>(), fps = (frames - 1) / loop;
      const double step = t["step_seconds"].get<double>(), posing = t["posing_seconds"].get<double>();
      const double output = t["output_seconds"].get<double>() - posing;
      const double overhead = loop - step - t["output_seconds"].get<double>();
      const double writer = t.value("writer_seconds", 0.0);
      double solve = 0.0;  // summed over the bodies (CPU seconds on all threads)
      for (const auto& e : s["effects"])
        if (e["name"] != "skinning") solve += e["seconds"].get<double>();
      const auto avatars = s["bodies"].size();
      const double n = frames - 1;
      auto ms = [&](double seconds) { return 1e3 * seconds / n; };
      std::cout << fmt::format(
          "{:<8} {:<8} {:>8} {:>8.2f} {:>10.1f} | {:>9.1f} {:>9.1f} {:>9.1f} {:>9.1f} | {:>9.1f} {:>11.1f} {:>9.1f} "
          "{:>8.1f}×\n",
          r.threads, r.write ? "yes" : "no", avatars, fps, ms(loop), ms(step), ms(posing), ms(output), ms(overhead),
          ms(solve), ms(writer), t["setup_seconds"].get<double>(), fps / 1.2);
      rows.push_back({{"threads", r.threads},
                      {"writing", r.write},
                      {"every", every},
                      {"output", r.write ? written : std::string("none")},
                      {"avatars", avatars},
                      {"fps", fps},
                      {"ms_per_frame", ms(loop)},
                      {"step_ms", ms(step)},
                      {"posing_ms", ms(posing)},
                      {"output_ms", ms(output)},
                      {"overhead_ms", ms(overhead)},
                      {"solve_cpu_ms", ms(solve)},
                      {"writer_busy_ms", ms(writer)},
                      {"writer_wait_ms", ms(t.value("writer_wait_seconds", 0.0))},
                      {"setup_seconds", t["setup_seconds"]},
                      {"effects", s["effects"]},
                      {"paper_fps_single_thread", 1.2}});
    }
    std::cout << "\n(ms per crowd frame, wall: step = stepping all bodies, posing = posing the written surfaces, "
                 "output = the rest of "
                 "the output on the stepping thread (σ, queueing, waiting for the writer); solve cpu = the bodies' "
                 "solves summed over "
                 "threads; writer busy = the background writer's time, overlapping the others)\n";
    write_json(out, {{"benchmark", "crowd"},
                     {"scene", scene_path},
                     {"frames", frames},
                     {"rows", rows},
                     {"output", written},
                     {"goal_fps_without_writing", 120},
                     {"goal_fps_writing", 30}});
    std::cout << "wrote " << out << "\n";
  } catch (const std::exception& e) {
    std::filesystem::remove_all(scratch);
    std::cerr << "bench_crowd: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
