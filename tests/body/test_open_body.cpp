// The shipped open body (data/open_body.npz, what users get): SMPL layout, a clean human surface
// over the shape space, skinning weights, joints inside the body, left/right symmetry, PCA ordering,
// and its named subjects. That the shipped file is what the generator produces is checked in
// test_open_body_generator.cpp.
#include <sflsh/body/body_io.hpp>
#include <sflsh/body/open_body.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/body/surface_checks.hpp>
#include <sflsh/core/error.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>
#include <set>

using namespace sflsh::body;

namespace {

const BodyModel& model() {
  static const BodyModel body = load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  return body;
}

const std::vector<Subject>& open_subjects() {
  static const std::vector<Subject> subjects =
      load_subjects(std::filesystem::path(SFLSH_DATA_DIR) / "open_body_subjects.toml");
  return subjects;
}

Betas unit_beta(int component, double value) {
  Betas b = Betas::Zero();
  b(component) = value;
  return b;
}

/// Generalised winding number of a closed, outward-oriented surface around p (1 inside, 0 outside).
double winding_number(const RowMatrixX3d& v, const RowMatrixX3i& f, const Eigen::Vector3d& p) {
  double total = 0.0;
  for (Eigen::Index t = 0; t < f.rows(); ++t) {
    const Eigen::Vector3d a = v.row(f(t, 0)).transpose() - p;
    const Eigen::Vector3d b = v.row(f(t, 1)).transpose() - p;
    const Eigen::Vector3d c = v.row(f(t, 2)).transpose() - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    // Van Oosterom–Strackee solid angle of the triangle seen from p.
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2.0 * std::atan2(numerator, denominator);
  }
  return total / (4.0 * std::numbers::pi);
}

/// Distance from p to triangle (a, b, c) (Ericson, Real-Time Collision Detection §5.1.5).
double point_triangle_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                               const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * vb * denom + ac * vc * denom)).norm();
}

void expect_clean_surface(const Betas& beta, const std::string& label) {
  const RowMatrixX3d shaped = shaped_template(model(), beta);
  const SurfaceReport report = check_surface(shaped, model().faces);
  EXPECT_TRUE(report.ok()) << label << ": " << report.summary();
  EXPECT_EQ(report.euler_characteristic, 2) << label;
}

}  // namespace

TEST(OpenBody, HasSmplLayout) {
  const BodyModel& m = model();
  EXPECT_NO_THROW(m.validate());
  const Eigen::Index n = m.num_vertices();
  EXPECT_GE(n, 6000);
  EXPECT_LE(n, 10000);
  EXPECT_EQ(m.faces.cols(), 3);
  EXPECT_EQ(m.num_faces(), 2 * n - 4);  // closed genus-0 triangle surface
  EXPECT_EQ(m.shapedirs.rows(), 3 * n);
  EXPECT_EQ(m.shapedirs.cols(), kNumBetas);
  EXPECT_FALSE(m.has_pose_correctives());
  EXPECT_EQ(m.joint_regressor.rows(), kNumJoints);
  EXPECT_EQ(m.joint_regressor.cols(), n);
  EXPECT_EQ(m.weights.rows(), n);
  EXPECT_EQ(m.weights.cols(), kNumJoints);
  EXPECT_EQ(m.parents, kJointParents);
  EXPECT_EQ(open_subjects().size(), 12u);  // 5 train, 7 test (6 and 7: locality probes)
}

TEST(OpenBody, SurfaceIsCleanAtTheMean) { expect_clean_surface(Betas::Zero(), "β = 0"); }

TEST(OpenBody, SurfaceIsCleanAtEachComponentPlusMinusThree) {
  for (int m = 0; m < kNumBetas; ++m)
    for (double value : {-3.0, 3.0}) expect_clean_surface(unit_beta(m, value), fmt::format("β{} = {}", m + 1, value));
}

TEST(OpenBody, SurfaceIsCleanOverTheBetaBox) {
  // Random points of [-3, 3]^10 and a few corners.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  for (int k = 0; k < 10; ++k) {
    Betas b;
    for (int i = 0; i < kNumBetas; ++i) b(i) = uniform(rng);
    expect_clean_surface(b, fmt::format("random β #{}", k));
  }
  expect_clean_surface(Betas::Constant(2.0), "β = 2·1");
  expect_clean_surface(Betas::Constant(-2.0), "β = −2·1");
  Betas alternating;
  for (int i = 0; i < kNumBetas; ++i) alternating(i) = i % 2 == 0 ? 2.5 : -2.5;
  expect_clean_surface(alternating, "β = ±2.5 alternating");
}

TEST(OpenBody, PaperTableOneBetasGiveCleanSurfaces) {
  const auto subjects = load_subjects(std::filesystem::path(SFLSH_DATA_DIR) / "subjects.toml");
  ASSERT_EQ(subjects.size(), 10u);
  for (const Subject& s : subjects) expect_clean_surface(s.beta, s.name);
}

TEST(OpenBody, WeightsArePartitionOfUnityOnFourBones) {
  const Eigen::MatrixXd& w = model().weights;
  EXPECT_GE(w.minCoeff(), 0.0);
  for (Eigen::Index v = 0; v < w.rows(); ++v) {
    EXPECT_NEAR(w.row(v).sum(), 1.0, 1e-12) << "vertex " << v;
    EXPECT_LE((w.row(v).array() > 0.0).count(), 4) << "vertex " << v;
  }
  // Every bone dominates some part of the surface.
  for (int k = 0; k < kNumJoints; ++k)
    EXPECT_GT((w.col(k).array() > 0.5).count(), 0) << kJointNames[static_cast<std::size_t>(k)];
}

TEST(OpenBody, WeightsDoNotBleedAcrossCrotchOrArmpit) {
  // No vertex is moved by both hips' children, or by an arm bone and the opposite side.
  const Eigen::MatrixXd& w = model().weights;
  const RowMatrixX3d& v = model().v_template;
  for (Eigen::Index i = 0; i < w.rows(); ++i) {
    EXPECT_FALSE(w(i, 4) > 0.0 && w(i, 5) > 0.0) << "vertex " << i << " on both knees";
    EXPECT_FALSE(w(i, 1) > 0.0 && v(i, 0) < -0.03) << "vertex " << i << " at x = " << v(i, 0) << " on left_hip";
    EXPECT_FALSE(w(i, 2) > 0.0 && v(i, 0) > 0.03) << "vertex " << i << " at x = " << v(i, 0) << " on right_hip";
  }
  // Upper arm and forearm bones only move the arms (outside the chest).
  const JointPositions joints = regress_joints(model(), v);
  for (Eigen::Index i = 0; i < w.rows(); ++i)
    for (int k : {18, 19, 20, 21, 22, 23})
      if (w(i, k) > 0.0) {
        EXPECT_GT(std::abs(v(i, 0)), std::abs(joints(16, 0))) << "vertex " << i << " bone " << k;
      }
}

TEST(OpenBody, JointsStayInsideTheBody) {
  std::vector<std::pair<std::string, Betas>> shapes = {{"β = 0", Betas::Zero()}};
  for (int m = 0; m < kNumBetas; ++m)
    for (double value : {-3.0, 3.0}) shapes.push_back({fmt::format("β{} = {}", m + 1, value), unit_beta(m, value)});
  for (const auto& [label, beta] : shapes) {
    const RowMatrixX3d shaped = shaped_template(model(), beta);
    const JointPositions joints = regress_joints(model(), shaped);
    for (int k = 0; k < kNumJoints; ++k)
      EXPECT_GT(winding_number(shaped, model().faces, joints.row(k).transpose()), 0.5)
          << label << ": joint " << kJointNames[static_cast<std::size_t>(k)] << " is outside";
  }
}

TEST(OpenBody, RestPoseFollowsSmplConventions) {
  const RowMatrixX3d& v = model().v_template;
  const JointPositions j = regress_joints(model(), v);
  const double stature = v.col(1).maxCoeff() - v.col(1).minCoeff();
  EXPECT_GT(stature, 1.6);
  EXPECT_LT(stature, 1.8);
  EXPECT_LT(j.row(0).norm(), 0.05) << "pelvis joint near the origin";
  EXPECT_GT(j(1, 0), 0.0) << "left hip at +x";
  EXPECT_GT(j(16, 0), 0.0) << "left shoulder at +x";
  EXPECT_GT(j(15, 1), j(12, 1));
  EXPECT_GT(j(12, 1), j(9, 1));
  EXPECT_GT(j(10, 2), j(7, 2)) << "feet point to +z";
  for (int side : {0, 1}) {
    const Eigen::Vector3d arm = (j.row(20 + side) - j.row(16 + side)).transpose();
    const double drop = std::atan2(-arm.y(), std::abs(arm.x())) * 180.0 / std::numbers::pi;
    EXPECT_GT(drop, 8.0);
    EXPECT_LT(drop, 17.0);
  }
  // Legs slightly apart: ankles wider than hips.
  EXPECT_GT(j(7, 0) - j(8, 0), j(1, 0) - j(2, 0));
  // The face is at +z: the nose tip is the most forward point of the head.
  Eigen::Index front = 0;
  double best = -1e9;
  for (Eigen::Index i = 0; i < v.rows(); ++i)
    if (v(i, 1) > j(12, 1) && v(i, 2) > best) {
      best = v(i, 2);
      front = i;
    }
  EXPECT_LT(std::abs(v(front, 0)), 0.01) << "nose tip on the mid-plane";
}

TEST(OpenBody, LeftRightSymmetric) {
  const RowMatrixX3d& v = model().v_template;
  const RowMatrixX3i& f = model().faces;
  // Faces around each vertex, to measure point-to-surface distances locally.
  std::vector<std::vector<int>> incident(static_cast<std::size_t>(v.rows()));
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    for (int k = 0; k < 3; ++k) incident[static_cast<std::size_t>(f(t, k))].push_back(static_cast<int>(t));
  double worst = 0.0;
  for (Eigen::Index i = 0; i < v.rows(); ++i) {
    const Eigen::Vector3d mirrored(-v(i, 0), v(i, 1), v(i, 2));
    Eigen::Index nearest = 0;
    (v.rowwise() - mirrored.transpose()).rowwise().squaredNorm().minCoeff(&nearest);
    double d = (v.row(nearest).transpose() - mirrored).norm();
    for (int t : incident[static_cast<std::size_t>(nearest)])
      d = std::min(d, point_triangle_distance(mirrored, v.row(f(t, 0)).transpose(), v.row(f(t, 1)).transpose(),
                                              v.row(f(t, 2)).transpose()));
    worst = std::max(worst, d);
  }
  EXPECT_LT(worst, 0.004) << "mirror image of the template is " << worst << " m off its surface";

  const JointPositions j = regress_joints(model(), v);
  for (int k = 0; k < kNumJoints; ++k) {
    const std::string name = kJointNames[static_cast<std::size_t>(k)];
    int partner = k;
    if (name.rfind("left_", 0) == 0) partner = joint_index("right_" + name.substr(5));
    if (name.rfind("right_", 0) == 0) partner = joint_index("left_" + name.substr(6));
    EXPECT_NEAR(j(k, 0), -j(partner, 0), 0.003) << name;
    EXPECT_NEAR(j(k, 1), j(partner, 1), 0.003) << name;
    EXPECT_NEAR(j(k, 2), j(partner, 2), 0.003) << name;
  }
}

TEST(OpenBody, ComponentsAreOrderedByVariance) {
  // shapedirs are √λ-scaled orthogonal directions: SᵀS = diag(λ), λ decreasing (as SMPL's β).
  const Eigen::MatrixXd gram = model().shapedirs.transpose() * model().shapedirs;
  const Eigen::VectorXd lambda = gram.diagonal();
  for (Eigen::Index m = 0; m + 1 < lambda.size(); ++m) EXPECT_GE(lambda(m), lambda(m + 1));
  EXPECT_GT(lambda(0) / lambda.sum(), 0.3);
  EXPECT_GT(lambda.head(3).sum() / lambda.sum(), 0.8);
  EXPECT_GT(lambda.minCoeff(), 0.0);
  for (int a = 0; a < kNumBetas; ++a)
    for (int b = 0; b < a; ++b) EXPECT_NEAR(gram(a, b) / std::sqrt(gram(a, a) * gram(b, b)), 0.0, 1e-9);
}

TEST(OpenBody, FirstComponentChangesStature) {
  const auto stature = [](const Betas& b) {
    const RowMatrixX3d s = shaped_template(model(), b);
    return s.col(1).maxCoeff() - s.col(1).minCoeff();
  };
  // Sign convention: +β₁ correlates with its dominant factor, stature.
  EXPECT_GT(stature(unit_beta(0, 3.0)), stature(Betas::Zero()) + 0.1);
  EXPECT_LT(stature(unit_beta(0, -3.0)), stature(Betas::Zero()) - 0.1);
}

TEST(OpenBody, SubjectsAreNamedAndProjected) {
  const auto& subjects = open_subjects();
  std::set<std::string> names;
  for (const Subject& s : subjects) {
    names.insert(s.name);
    EXPECT_TRUE(s.split == "train" || s.split == "test") << s.name;
    EXPECT_FALSE(s.description.empty()) << s.name;
    EXPECT_TRUE(s.beta.allFinite()) << s.name;
    EXPECT_LT(s.beta.norm(), 8.0) << s.name;
    expect_clean_surface(s.beta, s.name);
  }
  for (int k = 1; k <= 5; ++k) {
    EXPECT_TRUE(names.count(fmt::format("OPEN_TRAIN_{}", k))) << k;
    EXPECT_TRUE(names.count(fmt::format("OPEN_TEST_{}", k))) << k;
  }
  const auto stature = [](const Betas& b) {
    const RowMatrixX3d s = shaped_template(model(), b);
    return s.col(1).maxCoeff() - s.col(1).minCoeff();
  };
  const auto find = [&](const std::string& name) -> const Subject& { return find_subject(subjects, name); };
  EXPECT_GT(stature(find("OPEN_TRAIN_4").beta), stature(find("OPEN_TRAIN_1").beta) + 0.08) << "tall and thin";
  EXPECT_LT(stature(find("OPEN_TEST_4").beta), stature(find("OPEN_TRAIN_1").beta) - 0.08) << "short and thin";
}

// The locality probes (SFLSH's TEST 1 shares the upper body of DYNA 1): OPEN_TEST_6 keeps OPEN_TRAIN_3's chest,
// OPEN_TEST_7 OPEN_TRAIN_2's hips and thighs, while the rest of the body and β differ. Measured on the shaped
// templates, mean distance over the vertices each bone dominates: 0.0–0.1 mm on the shared part, 7–22 mm elsewhere.
TEST(OpenBody, LocalityProbesShareOneBodyPartWithATrainSubject) {
  const auto& subjects = open_subjects();
  const Eigen::MatrixXd& w = model().weights;
  auto mean_distance = [&](const std::string& a, const std::string& b, std::initializer_list<const char*> bones) {
    const RowMatrixX3d va = shaped_template(model(), find_subject(subjects, a).beta);
    const RowMatrixX3d vb = shaped_template(model(), find_subject(subjects, b).beta);
    double sum = 0.0;
    int count = 0;
    for (Eigen::Index v = 0; v < w.rows(); ++v) {
      Eigen::Index dominant = 0;
      w.row(v).maxCoeff(&dominant);
      for (const char* bone : bones)
        if (kJointNames[static_cast<std::size_t>(dominant)] == std::string(bone)) {
          sum += (va.row(v) - vb.row(v)).norm();
          ++count;
        }
    }
    EXPECT_GT(count, 50);
    return sum / count;
  };
  EXPECT_GE((find_subject(subjects, "OPEN_TEST_6").beta - find_subject(subjects, "OPEN_TRAIN_3").beta).norm(), 2.0);
  EXPECT_GE((find_subject(subjects, "OPEN_TEST_7").beta - find_subject(subjects, "OPEN_TRAIN_2").beta).norm(), 2.0);
  EXPECT_LT(mean_distance("OPEN_TEST_6", "OPEN_TRAIN_3", {"spine2", "spine3"}), 1e-3);
  EXPECT_GT(mean_distance("OPEN_TEST_6", "OPEN_TRAIN_3", {"pelvis", "left_hip", "right_hip"}), 5e-3);
  EXPECT_LT(mean_distance("OPEN_TEST_7", "OPEN_TRAIN_2", {"left_hip", "right_hip", "left_knee", "right_knee"}), 1e-3);
  EXPECT_GT(mean_distance("OPEN_TEST_7", "OPEN_TRAIN_2", {"spine2", "left_collar", "right_collar"}), 5e-3);
}
