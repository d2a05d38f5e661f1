// Benchmark: cost per tet of the orthotropic StVK–Fung element kernels (energy, gradient, Hessian with each
// PSD projection) on one thread, for deformations of a given strain size (random F = I + ε G). These are the
// inner loops of both solvers' assembly; the table says what a Newton iteration costs per element.
// Usage: bench_element [--tets 20000] [--strain 0.05] [--repeat 5] [--out bench_element.json]
#include "bench_options.hpp"

#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/material/skin_material.hpp>
#include <sflsh/material/tet_element.hpp>

#include <fmt/format.h>

#include <chrono>
#include <iostream>
#include <optional>
#include <random>
#include <string>

namespace {

struct ElementOptions {
  int count = 20000, repeat = 5;
  double strain = 0.05;
  std::string out = "bench_element.json";
};

/// Reads the command line into `o`; nothing to run, otherwise the exit status (bench_options.hpp).
std::optional<int> parse_options(int argc, char** argv, ElementOptions& o) {
  CLI::App app{
      "Cost per tet of the orthotropic StVK–Fung element kernels (energy, gradient, Hessian with each PSD "
      "projection) on one thread, for random deformations F = I + ε G.",
      "bench_element"};
  sflsh::bench::use_bench_defaults(app);
  app.add_option("--tets", o.count, "Random deformed tets each kernel runs over");
  app.add_option("--strain", o.strain, "Strain size ε of the deformations (G has standard normal entries)");
  app.add_option("--repeat", o.repeat, "Passes over the tets per kernel; the fastest is reported");
  app.add_option("--out", o.out, "JSON file of the results");
  return sflsh::bench::parse_command_line(app, argc, argv);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace sflsh::material;
  ElementOptions o;
  if (const std::optional<int> status = parse_options(argc, argv, o)) return *status;
  const int count = o.count, repeat = o.repeat;
  const double strain = o.strain;
  const std::string& out = o.out;
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  TetNodes rest_nodes;
  rest_nodes << 0, 0.01, 0, 0, 0, 0, 0.01, 0, 0, 0, 0, 0.01;
  const TetRest rest = make_tet_rest(rest_nodes);
  SkinMaterial skin;
  skin.young_tangent = 5000.0;
  skin.young_normal = 2000.0;
  const OrthotropicFung material = make_orthotropic_fung(skin, Eigen::Vector3d(0.3, 0.4, 0.866).normalized());
  std::vector<TetNodes> states(static_cast<std::size_t>(count));
  for (TetNodes& x : states) {
    Eigen::Matrix3d G;
    for (int k = 0; k < 9; ++k) G(k / 3, k % 3) = normal(rng);
    x = (Eigen::Matrix3d::Identity() + strain * G) * rest_nodes;
  }
  using Clock = std::chrono::steady_clock;
  double sink = 0.0;
  auto time_kernel = [&](const char* name, auto&& kernel) {
    double best = 1e300;
    for (int r = 0; r < repeat; ++r) {
      const auto t0 = Clock::now();
      for (const TetNodes& x : states) sink += kernel(x);
      best = std::min(best, sflsh::seconds_since(t0));
    }
    const double us = 1e6 * best / count;
    std::cout << fmt::format("{:<34} {:>10.3f} µs/tet\n", name, us);
    return nlohmann::json{{"kernel", name}, {"microseconds_per_tet", us}};
  };
  nlohmann::json rows = nlohmann::json::array();
  rows.push_back(time_kernel("energy", [&](const TetNodes& x) { return tet_elastic_energy(rest, x, material); }));
  rows.push_back(time_kernel("gradient", [&](const TetNodes& x) { return tet_elastic_dq(rest, x, material)[0]; }));
  rows.push_back(time_kernel("hessian exact", [&](const TetNodes& x) {
    return tet_elastic_dq2(rest, x, material, HessianProjection::kNone)(0, 0);
  }));
  rows.push_back(time_kernel("hessian projected dP/dF (default)", [&](const TetNodes& x) {
    return tet_elastic_dq2(rest, x, material, HessianProjection::kStressDerivative)(0, 0);
  }));
  rows.push_back(time_kernel("hessian projected element", [&](const TetNodes& x) {
    return tet_elastic_dq2(rest, x, material, HessianProjection::kElement)(0, 0);
  }));
  sflsh::write_json(
      out, {{"benchmark", "element"}, {"tets", count}, {"strain", strain}, {"results", rows}, {"checksum", sink}});
  std::cout << "wrote " << out << "\n";
  return 0;
}
