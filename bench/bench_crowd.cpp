// Benchmark: the crowd scene of SFLSH Fig. 1 (data/scenes/crowd.toml: 25 avatars with random shapes, each its
// own shape-dependent material from the shipped shape model, dancing with per-avatar time offsets, reduced
// solver) run by the scene runner on 1 and T threads (parallel over bodies), without output: frames per
// second of the whole crowd against the paper's 1.2 fps single-threaded.
// Usage: bench_crowd [--scene data/scenes/crowd.toml] [--frames 60] [--threads 2] [--out bench_crowd.json]
#include <sflsh/core/log.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/scene/scene_file.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <fmt/format.h>

#include <cstring>
#include <iostream>
#include <string>

int main(int argc, char** argv) {
  using namespace sflsh;
  std::string scene_path = std::string(SFLSH_DATA_DIR) + "/scenes/crowd.toml", out = "bench_crowd.json";
  int frames = 60, threads = 2;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i];
    if (key == "--scene") scene_path = argv[i + 1];
    else if (key == "--frames") frames = std::stoi(argv[i + 1]);
    else if (key == "--threads") threads = std::stoi(argv[i + 1]);
    else if (key == "--out") out = argv[i + 1];
    else {
      std::cerr << "bench_crowd: unknown option " << key << "\n";
      return 2;
    }
  }
  try {
    logger()->set_level(spdlog::level::warn);
    const scene::Scene scene = scene::load_scene(scene_path);
    nlohmann::json rows = nlohmann::json::array();
    std::cout << fmt::format("crowd scene {}: {} frames at {} fps, no output\n\n", scene_path, frames, scene.fps);
    std::cout << fmt::format("{:<10} {:>8} {:>10} {:>12} {:>12} {:>14} {:>10}\n", "threads", "avatars", "fps", "ms/frame",
                             "setup [s]", "elastic+inert", "vs 1.2 fps");
    for (int t : {1, threads}) {
      scene::SceneRunOptions options;
      options.frames = frames;
      options.threads = t;
      options.write_frames = false;
      const nlohmann::json s = scene::run_scene(scene, options);
      const double fps = s["timings"]["frames_per_second"].get<double>();
      double solve = 0.0;
      for (const auto& e : s["effects"]) solve += e["seconds"].get<double>();
      const auto avatars = s["bodies"].size();
      std::cout << fmt::format("{:<10} {:>8} {:>10.2f} {:>12.1f} {:>12.1f} {:>14.2f} {:>9.1f}×\n", t, avatars, fps, 1e3 / fps,
                               s["timings"]["setup_seconds"].get<double>(), solve, fps / 1.2);
      rows.push_back({{"threads", t}, {"avatars", avatars}, {"fps", fps}, {"ms_per_frame", 1e3 / fps},
                      {"setup_seconds", s["timings"]["setup_seconds"]}, {"effects", s["effects"]}, {"paper_fps_single_thread", 1.2}});
      if (t == threads) break;
    }
    write_json(out, {{"benchmark", "crowd"}, {"scene", scene_path}, {"frames", frames}, {"rows", rows}});
    std::cout << "wrote " << out << "\n";
  } catch (const std::exception& e) {
    std::cerr << "bench_crowd: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
