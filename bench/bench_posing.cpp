// Benchmark: posing the body along a motion (forward kinematics + linear blend skinning).
// Usage: bench_posing [--body PATH] [--out results.json]
// Prints a table and writes JSON (frames per second, per-frame time, vertices).
#include "bench_options.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>

#include <fmt/format.h>

#include <chrono>
#include <iostream>
#include <optional>
#include <string>

namespace {

struct PosingOptions {
  std::string body_path, out = "bench_posing.json";
};

/// Reads the command line into `o`; nothing to run, otherwise the exit status (bench_options.hpp).
std::optional<int> parse_options(int argc, char** argv, PosingOptions& o) {
  CLI::App app{"Posing the body along each procedural motion (forward kinematics + linear blend skinning), one thread.",
               "bench_posing"};
  sflsh::bench::use_bench_defaults(app);
  app.add_option("--body", o.body_path, "Body model .npz in SMPL layout (default: the open body, data/open_body.npz)");
  app.add_option("--out", o.out, "JSON file of the results");
  return sflsh::bench::parse_command_line(app, argc, argv);
}

}  // namespace

int main(int argc, char** argv) {
  PosingOptions o;
  if (const std::optional<int> status = parse_options(argc, argv, o)) return *status;
  const std::string &body_path = o.body_path, &out = o.out;
  try {
    using namespace sflsh;
    const body::BodyModel model =
        body::load_body(body_path.empty() ? body::default_body_path() : std::filesystem::path(body_path));
    nlohmann::json results = nlohmann::json::array();
    std::cout << fmt::format("{:<18} {:>8} {:>8} {:>12} {:>12}\n", "motion", "vertices", "frames", "ms/frame",
                             "frames/s");
    for (const std::string& name : body::procedural_motion_names()) {
      const body::Motion motion = body::make_procedural_motion(name, 60.0, 600);
      const body::Poser poser(model, body::Betas::Constant(0.5));
      double checksum = 0.0;
      const auto t0 = std::chrono::steady_clock::now();
      for (std::size_t t = 0; t < motion.num_frames(); ++t)
        checksum += poser.pose(motion.poses[t], motion.trans[t])(0, 1);
      const double seconds = sflsh::seconds_since(t0);
      const double per_frame = 1e3 * seconds / static_cast<double>(motion.num_frames());
      std::cout << fmt::format("{:<18} {:>8} {:>8} {:>12.3f} {:>12.0f}\n", name, model.num_vertices(),
                               motion.num_frames(), per_frame, 1e3 / per_frame);
      results.push_back({{"motion", name},
                         {"vertices", model.num_vertices()},
                         {"frames", motion.num_frames()},
                         {"ms_per_frame", per_frame},
                         {"frames_per_second", 1e3 / per_frame},
                         {"checksum", checksum}});
    }
    write_json(out, {{"benchmark", "posing"}, {"threads", 1}, {"results", results}});
    std::cout << "wrote " << out << "\n";
  } catch (const std::exception& e) {
    std::cerr << "bench_posing: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
