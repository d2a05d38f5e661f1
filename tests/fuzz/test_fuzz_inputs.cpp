// Fuzzing the command line with mutated inputs of every kind a user hands to sflsh (label `fuzz`): body and
// AMASS .npz, DYNA .h5, material, scene and shape-model TOML, OBJ obstacles, gmsh .msh + verify TOML. Each
// case mutates a valid file the test writes itself (seeded, so a failure is reproduced by its seed), runs
// the CLI as a process, and asserts the rules for bad input (fuzz_harness.hpp). SFLSH_FUZZ_CASES sets the
// number of cases per kind (default 10; `ctest --preset long` runs fuzz.many_cases with 80).
#include "fuzz_harness.hpp"
#include "mutators.hpp"
#include "scratch_dir.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/body_model.hpp>
#include <sflsh/core/npz.hpp>
#include <sflsh/fullspace/msh_reader.hpp>
#include <sflsh/validate/dyna_file.hpp>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <iostream>

namespace sflsh::testing::fuzz {
namespace {

namespace fs = std::filesystem;

/// One input kind: how to write the mutated file, and the command that reads it.
struct Kind {
  std::string name;
  std::string file_name;  ///< the input's name in the work folder
  std::function<std::string(const fs::path& input, const fs::path& out)> arguments;
  std::function<std::string(Random&, const fs::path& input)> mutate;  ///< writes the mutated input, returns what it did
  std::function<void(const fs::path& workdir)> prepare;               ///< files the command needs beside the input
};

/// Runs `cases` mutations of one kind, each in a fresh work folder, and reports them.
void fuzz_kind(const Kind& kind, int cases, std::uint64_t seed, const fs::path& root, Tally& tally) {
  for (int k = 0; k < cases; ++k) {
    const fs::path workdir = root / fmt::format("case{:03d}", k);
    fs::create_directories(workdir);
    if (kind.prepare) kind.prepare(workdir);
    Random random(seed * 1000003ull + static_cast<std::uint64_t>(k));
    const fs::path input = workdir / kind.file_name;
    Case c;
    c.kind = kind.name;
    c.input = input;
    c.mutation = fmt::format("seed {} case {}: {}", seed, k, kind.mutate(random, input));
    c.out = workdir / "run";
    c.arguments = kind.arguments(input, c.out);
    tally.add(run_case(c, workdir));
  }
}

void expect_no_failures(const Tally& tally) {
  std::cout << tally.cases() << tally.table();
  for (const Outcome& o : tally.failures())
    ADD_FAILURE() << verdict_name(o.verdict) << " [" << o.c.kind << "] " << o.c.mutation << "\n  sflsh "
                  << o.c.arguments << "\n  " << o.detail;
}

// ---- Binary inputs: byte mutations and array mutations through the npz writer --------------------------------

/// A float16 copy of a float array (IEEE half, round to nearest), as numpy.float16 stores it.
npz::Array to_float16(const npz::Array& a) {
  npz::Array h;
  h.kind = 'f';
  h.itemsize = 2;
  h.shape = a.shape;
  const std::vector<double> values = a.to_doubles();
  h.bytes.resize(values.size() * 2);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const float f = static_cast<float>(values[i]);
    std::uint32_t bits = 0;
    std::memcpy(&bits, &f, 4);
    const std::uint32_t sign = (bits >> 16) & 0x8000u;
    const int exponent = static_cast<int>((bits >> 23) & 0xff) - 127 + 15;
    std::uint16_t half = static_cast<std::uint16_t>(sign);
    if (exponent >= 31)
      half = static_cast<std::uint16_t>(sign | 0x7c00u);
    else if (exponent > 0)
      half = static_cast<std::uint16_t>(sign | (static_cast<unsigned>(exponent) << 10) | ((bits >> 13) & 0x3ffu));
    std::memcpy(&h.bytes[2 * i], &half, 2);
  }
  return h;
}

/// One structural mutation of an .npz: a member replaced by a hostile array, or removed.
std::string mutate_npz_members(const fs::path& base, const fs::path& target, Random& random) {
  npz::Reader reader(base);
  std::vector<std::pair<std::string, npz::Array>> members;
  for (const std::string& key : reader.keys()) members.emplace_back(key, reader.read(key));
  const std::size_t victim = std::uniform_int_distribution<std::size_t>(0, members.size() - 1)(random);
  auto& [key, array] = members[victim];
  const int choice = std::uniform_int_distribution<int>(0, 7)(random);
  std::string what;
  if (choice == 0 && array.is_numeric()) {
    std::vector<double> v = array.to_doubles();
    if (!v.empty()) v[v.size() / 2] = std::nan("");
    array = npz::make_f64(array.shape, v);
    what = "one value NaN";
  } else if (choice == 1 && array.is_numeric()) {
    std::vector<double> v = array.to_doubles();
    for (double& x : v) x = 1e300;
    array = npz::make_f64(array.shape, v);
    what = "every value 1e300";
  } else if (choice == 2 && array.kind == 'f') {
    array = to_float16(array);
    what = "stored as float16";
  } else if (choice == 3 && array.is_numeric()) {
    array.kind = 'b';
    array.itemsize = 1;
    array.bytes.assign(array.size(), 1);
    what = "stored as bool";
  } else if (choice == 4 && array.shape.size() >= 1 && array.shape.back() > 1) {
    std::vector<std::size_t> shape = array.shape;
    shape.back() -= 1;
    std::size_t n = 1;
    for (std::size_t s : shape) n *= s;
    array = npz::make_f64(shape, std::vector<double>(n, 0.5));
    what = "last axis one shorter";
  } else if (choice == 5 && (array.kind == 'i' || array.kind == 'u')) {
    std::vector<std::int64_t> v = array.to_int64();
    if (!v.empty()) v[v.size() / 3] = 1'000'000'007;
    array = npz::make_i64(array.shape, v);
    what = "an index far out of range";
  } else if (choice == 6) {
    array = npz::make_string("not an array");
    what = "replaced by a string";
  } else {
    members.erase(members.begin() + static_cast<std::ptrdiff_t>(victim));
    npz::write(target, members);
    return "member '" + reader.keys()[victim] + "' removed";
  }
  npz::write(target, members);
  return "member '" + key + "': " + what;
}

std::string mutate_binary_file(const fs::path& base, const fs::path& target, Random& random) {
  std::string what;
  write_bytes(target, mutate_bytes(read_bytes(base), random, what));
  return what;
}

/// Half the cases mutate arrays through the writer (meaningful files), half mutate bytes (broken files);
/// one case is a folder where the file belongs.
std::string mutate_npz(const fs::path& base, const fs::path& target, Random& random) {
  const int choice = std::uniform_int_distribution<int>(0, 20)(random);
  if (choice == 0) {
    fs::create_directories(target);
    return "a folder in place of the file";
  }
  if (choice <= 10) return mutate_npz_members(base, target, random);
  return mutate_binary_file(base, target, random);
}

fs::path write_amass_base(const fs::path& dir) {
  const fs::path path = dir / "amass_base.npz";
  const int frames = 4;
  std::vector<double> poses(frames * 156, 0.0), trans(frames * 3, 0.0);
  for (int t = 0; t < frames; ++t) {
    poses[t * 156 + 3 * 16 + 2] = 0.3 * t;  // left shoulder
    trans[t * 3 + 1] = 0.01 * t;
  }
  npz::write(path, {{"poses", npz::make_f64({frames, 156}, poses)},
                    {"trans", npz::make_f64({frames, 3}, trans)},
                    {"betas", npz::make_f64({16}, std::vector<double>(16, 0.0))},
                    {"mocap_framerate", npz::make_scalar(60.0)},
                    {"gender", npz::make_string("neutral")}});
  return path;
}

TEST(Fuzz, BodyNpz) {
  const fs::path base = fs::path(SFLSH_DATA_DIR) / "open_body.npz";
  Kind kind{"body .npz", "body.npz",
            [](const fs::path& in, const fs::path&) { return fmt::format("-q body info --body '{}'", in.string()); },
            [&](Random& r, const fs::path& in) { return mutate_npz(base, in, r); }, nullptr};
  Tally tally;
  fuzz_kind(kind, cases_per_kind(), 11, scratch_dir(), tally);
  expect_no_failures(tally);
}

TEST(Fuzz, AmassNpz) {
  const fs::path root = scratch_dir();
  const fs::path base = write_amass_base(root);
  Kind kind{"AMASS .npz", "motion.npz",
            [](const fs::path& in, const fs::path& out) {
              return fmt::format("-q motion export --subject OPEN_TRAIN_1 --motion '{}' --out '{}'", in.string(),
                                 out.string());
            },
            [&](Random& r, const fs::path& in) { return mutate_npz(base, in, r); }, nullptr};
  Tally tally;
  fuzz_kind(kind, cases_per_kind(), 12, root, tally);
  expect_no_failures(tally);
}

// ---- DYNA registrations ----------------------------------------------------------------------------------------

TEST(Fuzz, DynaH5) {
  const fs::path dir = scratch_dir();
  const body::BodyModel model = body::load_body(fs::path(SFLSH_DATA_DIR) / "open_body.npz");
  validate::RowMatrixX3i faces = model.faces.cast<int>();
  std::vector<validate::RowMatrixX3d> frames;
  for (int t = 0; t < 3; ++t) {
    validate::RowMatrixX3d v = model.v_template;
    v.col(1).array() += 0.002 * t;
    frames.push_back(v);
  }
  const fs::path base = dir / "dyna_base.h5";
  validate::write_dyna_file(base, faces, {validate::DynaSequence{"50004_jiggle", frames, {}, 60.0}});
  auto mutate = [&](Random& r, const fs::path& in) -> std::string {
    const int choice = std::uniform_int_distribution<int>(0, 9)(r);
    std::vector<validate::RowMatrixX3d> f = frames;
    std::string what;
    if (choice == 0) {
      for (auto& x : f) x.setZero();
      what = "every registration at the origin";
    } else if (choice == 1) {
      for (auto& x : f) x *= 1e300;
      what = "registrations scaled by 1e300";
    } else if (choice == 2) {
      f[1](10, 0) = std::nan("");
      what = "one coordinate NaN";
    } else if (choice == 3) {
      for (auto& x : f) x.conservativeResize(x.rows() / 2, 3);
      what = "half the vertices";
    } else if (choice == 4) {
      validate::write_dyna_file(in, faces, {validate::DynaSequence{"50004_other", f, {}, 60.0}});
      return "the requested sequence absent";
    } else {
      return mutate_binary_file(base, in, r);
    }
    try {
      validate::write_dyna_file(in, faces, {validate::DynaSequence{"50004_jiggle", f, {}, 60.0}});
    } catch (const std::exception&) {  // the writer refuses some of these itself: mutate the bytes instead
      return mutate_binary_file(base, in, r);
    }
    return what;
  };
  Kind kind{"DYNA .h5", "dyna.h5",
            [](const fs::path& in, const fs::path& out) {
              return fmt::format("-q metrics --dyna '{}' --sequence 50004_jiggle --betas 0 --frames 2 --out '{}'",
                                 in.string(), out.string());
            },
            mutate, nullptr};
  Tally tally;
  fuzz_kind(kind, cases_per_kind(), 13, dir, tally);
  expect_no_failures(tally);
}

}  // namespace
}  // namespace sflsh::testing::fuzz
