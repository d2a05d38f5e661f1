#include <sflsh/body/body_io.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/npz.hpp>

#include <cmath>
#include <cstdlib>

#ifndef SFLSH_DATA_DIR
#define SFLSH_DATA_DIR "data"
#endif

namespace sflsh::body {

namespace {

/// Checks shape (0 = any extent) and dtype kind of a member: floats (f2/f4/f8) or integers.
const npz::Array& checked(const npz::Array& a, const std::string& file, const std::string& key,
                          std::vector<std::size_t> expected, const std::string& expected_text, bool want_float) {
  bool ok = a.shape.size() == expected.size();
  for (std::size_t d = 0; ok && d < expected.size(); ++d)
    if (expected[d] != 0 && a.shape[d] != expected[d]) ok = false;
  require(ok, "{}: {}: shape {}, expected {}", file, key, a.shape_string(), expected_text);
  if (want_float) {
    require(a.kind == 'f', "{}: {}: dtype {}, expected a float array (<f8, <f4 or <f2)", file, key, a.dtype());
  } else {
    require(a.kind == 'i' || a.kind == 'u', "{}: {}: dtype {}, expected an integer array", file, key, a.dtype());
  }
  return a;
}

/// The doubles of a float member, each finite and within ±bound.
std::vector<double> bounded_values(const npz::Array& a, const std::string& file, const std::string& key, double bound,
                                   const char* meaning) {
  std::vector<double> values = a.to_doubles();
  for (std::size_t i = 0; i < values.size(); ++i)
    require(std::isfinite(values[i]) && std::abs(values[i]) <= bound,
            "{}: {}: element {} is {}, expected finite {} within ±{:g}", file, key, i, values[i], meaning, bound);
  return values;
}

npz::Array read_key(const npz::Reader& reader, const std::string& key) {
  require(reader.has(key),
          "{}: missing key '{}' (a SMPL-layout body model needs v_template, f, shapedirs, "
          "J_regressor, weights, kintree_table)",
          reader.path().string(), key);
  return reader.read(key);
}

}  // namespace

BodyModel load_body(const std::filesystem::path& path) {
  const npz::Reader reader(path);
  const std::string file = path.string();
  BodyModel model;
  model.name = path.stem().string();

  const npz::Array v = read_key(reader, "v_template");
  checked(v, file, "v_template", {0, 3}, "(n, 3)", true);
  require(v.shape[0] >= 4 && v.shape[0] <= kMaxBodyVertices, "{}: v_template: {} vertices, expected 4..{}", file,
          v.shape[0], kMaxBodyVertices);
  const auto n = static_cast<Eigen::Index>(v.shape[0]);
  const std::string ns = std::to_string(n);
  const std::vector<double> vv = bounded_values(v, file, "v_template", kMaxBodyMetres, "positions [m]");
  model.v_template = Eigen::Map<const RowMatrixX3d>(vv.data(), n, 3);

  const npz::Array f = read_key(reader, "f");
  checked(f, file, "f", {0, 3}, "(m, 3)", false);
  require(f.shape[0] >= 4 && f.shape[0] <= kMaxBodyFaces, "{}: f: {} faces, expected 4..{}", file, f.shape[0],
          kMaxBodyFaces);
  const std::vector<std::int64_t> ff = f.to_int64();
  model.faces.resize(static_cast<Eigen::Index>(f.shape[0]), 3);
  for (std::size_t i = 0; i < ff.size(); ++i) {
    require(ff[i] >= 0 && ff[i] < n, "{}: f: face {} indexes vertex {}, expected 0..{}", file, i / 3, ff[i], n - 1);
    model.faces(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3)) = static_cast<int>(ff[i]);
  }

  const npz::Array s = read_key(reader, "shapedirs");
  checked(s, file, "shapedirs", {v.shape[0], 3, 0}, "(" + ns + ", 3, >=10)", true);
  require(s.shape[2] >= kNumBetas && s.shape[2] <= kMaxShapeComponents,
          "{}: shapedirs: shape {}, expected ({}, 3, >={}) with at most {} shape components", file, s.shape_string(), n,
          kNumBetas, kMaxShapeComponents);
  {
    const std::vector<double> sv = bounded_values(s, file, "shapedirs", kMaxBodyMetres, "displacements [m]");
    const auto b = static_cast<Eigen::Index>(s.shape[2]);
    model.shapedirs.resize(3 * n, b);
    for (Eigen::Index r = 0; r < 3 * n; ++r)
      for (Eigen::Index c = 0; c < b; ++c) model.shapedirs(r, c) = sv[static_cast<std::size_t>(r * b + c)];
  }

  if (reader.has("posedirs")) {
    const npz::Array p = reader.read("posedirs");
    checked(p, file, "posedirs", {v.shape[0], 3, static_cast<std::size_t>(kNumPoseFeatures)}, "(" + ns + ", 3, 207)",
            true);
    const std::vector<double> pv = bounded_values(p, file, "posedirs", kMaxBodyMetres, "displacements [m]");
    model.posedirs = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        pv.data(), 3 * n, kNumPoseFeatures);
  }

  const npz::Array j = read_key(reader, "J_regressor");
  checked(j, file, "J_regressor", {static_cast<std::size_t>(kNumJoints), v.shape[0]}, "(24, " + ns + ")", true);
  {
    const std::vector<double> jv = bounded_values(j, file, "J_regressor", 1e3, "regression weights");
    std::vector<Eigen::Triplet<double>> triplets;
    for (Eigen::Index r = 0; r < kNumJoints; ++r)
      for (Eigen::Index c = 0; c < n; ++c) {
        const double w = jv[static_cast<std::size_t>(r * n + c)];
        if (w != 0.0) triplets.emplace_back(static_cast<int>(r), static_cast<int>(c), w);
      }
    model.joint_regressor.resize(kNumJoints, n);
    model.joint_regressor.setFromTriplets(triplets.begin(), triplets.end());
  }

  const npz::Array w = read_key(reader, "weights");
  checked(w, file, "weights", {v.shape[0], static_cast<std::size_t>(kNumJoints)}, "(" + ns + ", 24)", true);
  const std::vector<double> wv = bounded_values(w, file, "weights", 1e3, "skinning weights");
  model.weights = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(wv.data(), n,
                                                                                                           kNumJoints);

  const npz::Array k = read_key(reader, "kintree_table");
  checked(k, file, "kintree_table", {2, static_cast<std::size_t>(kNumJoints)}, "(2, 24)", false);
  const std::vector<std::int64_t> kv = k.to_int64();
  for (int c = 0; c < kNumJoints; ++c) {
    const std::int64_t parent = kv[static_cast<std::size_t>(c)];
    const bool root = parent == -1 || parent == 4294967295LL;
    require(root || (parent >= 0 && parent < c), "{}: kintree_table[0, {}]: parent {}, expected {}", file, c, parent,
            c == 0 ? std::string("the root marker (-1 or 4294967295)") : fmt::format("a parent index in 0..{}", c - 1));
    model.parents[static_cast<std::size_t>(c)] = root ? -1 : static_cast<int>(parent);
  }

  model.validate(file);
  return model;
}

void save_body(const std::filesystem::path& path, const BodyModel& model) {
  model.validate();
  const Eigen::Index n = model.num_vertices();
  const auto nu = static_cast<std::size_t>(n);
  std::vector<std::pair<std::string, npz::Array>> members;
  members.emplace_back("v_template", npz::make_f64(model.v_template));
  std::vector<std::int64_t> f(static_cast<std::size_t>(model.faces.size()));
  for (Eigen::Index i = 0; i < model.faces.rows(); ++i)
    for (int c = 0; c < 3; ++c) f[static_cast<std::size_t>(3 * i + c)] = model.faces(i, c);
  members.emplace_back("f", npz::make_i64({static_cast<std::size_t>(model.faces.rows()), 3}, f));
  const auto b = static_cast<std::size_t>(model.shapedirs.cols());
  std::vector<double> s(3 * nu * b);
  for (std::size_t r = 0; r < 3 * nu; ++r)
    for (std::size_t c = 0; c < b; ++c)
      s[r * b + c] = model.shapedirs(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c));
  members.emplace_back("shapedirs", npz::make_f64({nu, 3, b}, s));
  if (model.has_pose_correctives()) {
    std::vector<double> p(3 * nu * kNumPoseFeatures);
    for (std::size_t r = 0; r < 3 * nu; ++r)
      for (std::size_t c = 0; c < kNumPoseFeatures; ++c)
        p[r * kNumPoseFeatures + c] = model.posedirs(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c));
    members.emplace_back("posedirs", npz::make_f64({nu, 3, kNumPoseFeatures}, p));
  }
  members.emplace_back("J_regressor", npz::make_f64(Eigen::MatrixXd(model.joint_regressor)));
  members.emplace_back("weights", npz::make_f64(model.weights));
  std::vector<std::int64_t> kin(2 * kNumJoints);
  for (int c = 0; c < kNumJoints; ++c) {
    kin[static_cast<std::size_t>(c)] = model.parents[static_cast<std::size_t>(c)];
    kin[static_cast<std::size_t>(kNumJoints + c)] = c;
  }
  members.emplace_back("kintree_table", npz::make_i64({2, kNumJoints}, kin));
  npz::write(path, members);
}

std::filesystem::path data_dir() {
  if (const char* env = std::getenv("SFLSH_DATA"); env && *env) return env;
  return SFLSH_DATA_DIR;
}

std::filesystem::path default_body_path() { return data_dir() / "open_body.npz"; }

}  // namespace sflsh::body
