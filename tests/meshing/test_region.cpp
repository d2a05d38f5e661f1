// The layer's region on the open body's skin and its skeleton correspondence.
#include "error_of.hpp"
#include "layer_fixture.hpp"

#include <sflsh/body/skinning.hpp>
#include <sflsh/meshing/correspondence.hpp>
#include <sflsh/meshing/region.hpp>

#include <gmock/gmock.h>

#include <cmath>
#include <map>
#include <set>

namespace sflsh {

using sflsh::testing::error_of;
using sflsh::testing::open_body;
using ::testing::HasSubstr;

namespace {

std::map<std::pair<int, int>, int> edge_use(const meshing::RowMatrixX3i& faces) {
  std::map<std::pair<int, int>, int> use;
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int e = 0; e < 3; ++e) {
      int a = faces(f, e), b = faces(f, (e + 1) % 3);
      if (a > b) std::swap(a, b);
      ++use[{a, b}];
    }
  return use;
}

Eigen::Vector3d loop_centroid(const meshing::Region& region, const body::BodyModel& model,
                              const std::vector<int>& loop) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int v : loop) c += model.v_template.row(region.vertices[v]).transpose();
  return c / static_cast<double>(loop.size());
}

}  // namespace

TEST(Region, DefaultRegionIsOnePieceWithFiveCleanBoundaryLoops) {
  const auto& model = open_body();
  const meshing::Region region = meshing::select_region(model, meshing::default_region_names());
  // Neck, two elbows, two knees: the torso, upper arms and thighs form one surface with five holes.
  ASSERT_EQ(region.boundary_loops.size(), 5u);
  // No one-triangle teeth: no region face has two or three boundary edges.
  const auto use = edge_use(region.faces);
  for (Eigen::Index f = 0; f < region.faces.rows(); ++f) {
    int boundary = 0;
    for (int e = 0; e < 3; ++e) {
      int a = region.faces(f, e), b = region.faces(f, (e + 1) % 3);
      if (a > b) std::swap(a, b);
      boundary += use.at({a, b}) == 1;
    }
    EXPECT_LE(boundary, 1) << "face " << f << " is a tooth of the boundary";
  }
  // Each loop is near its joint: neck loop near the neck joint, limb loops near elbows and knees.
  const body::JointPositions joints = body::regress_joints(model, model.v_template);
  std::set<std::string> matched;
  for (const auto& loop : region.boundary_loops) {
    const Eigen::Vector3d c = loop_centroid(region, model, loop);
    std::string best;
    double best_distance = 1e9;
    for (const char* joint : {"neck", "left_elbow", "right_elbow", "left_knee", "right_knee"}) {
      const double d = (c - joints.row(body::joint_index(joint)).transpose()).norm();
      if (d < best_distance) {
        best_distance = d;
        best = joint;
      }
    }
    // 12 cm: the weight transition of a joint spans about ±10 cm of skin around it.
    EXPECT_LT(best_distance, 0.12) << best;
    matched.insert(best);
  }
  EXPECT_EQ(matched.size(), 5u);
}

// Total absolute turning of a closed polyline over 2π (1 for a convex planar curve).
double turning_number(const std::vector<Eigen::Vector3d>& points) {
  const std::size_t n = points.size();
  double turning = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d u = (points[k] - points[(k + n - 1) % n]).normalized();
    const Eigen::Vector3d w = (points[(k + 1) % n] - points[k]).normalized();
    turning += std::acos(std::clamp(u.dot(w), -1.0, 1.0));
  }
  return turning / (2.0 * M_PI);
}

TEST(Region, BoundaryCurvesAreSmooth) {
  const auto& model = open_body();
  const meshing::Region region = meshing::select_region(model, meshing::default_region_names());
  for (const auto& loop : region.boundary_loops) {
    // The boundary follows mesh edges, so at the scale of one edge it alternates by ~±30° (turning
    // ≈ 2). Above that scale it must be smooth: after a 3-vertex moving average (which removes the
    // one-edge alternation but keeps the sharp turns of any notch or tooth two or more triangles wide)
    // the loop turns less than 1.35 × 2π; the open body's loops measure 1.07–1.17.
    const std::size_t n = loop.size();
    std::vector<Eigen::Vector3d> points, averaged;
    for (int v : loop) points.push_back(model.v_template.row(region.vertices[v]).transpose());
    for (std::size_t k = 0; k < n; ++k)
      averaged.push_back((points[(k + n - 1) % n] + points[k] + points[(k + 1) % n]) / 3.0);
    EXPECT_LT(turning_number(averaged), 1.35) << "loop of " << n << " vertices";
  }
}

TEST(Region, PartsAndSymmetry) {
  const auto& model = open_body();
  const meshing::Region region = meshing::select_region(model, meshing::default_region_names());
  std::map<meshing::Part, int> count;
  for (auto p : region.part) ++count[p];
  ASSERT_EQ(count.size(), 5u);
  EXPECT_GT(count[meshing::Part::torso], count[meshing::Part::left_thigh]);
  // The open body is left/right symmetric, so the parts are within 5% of each other.
  EXPECT_NEAR(count[meshing::Part::left_upper_arm], count[meshing::Part::right_upper_arm],
              0.05 * count[meshing::Part::left_upper_arm]);
  EXPECT_NEAR(count[meshing::Part::left_thigh], count[meshing::Part::right_thigh],
              0.05 * count[meshing::Part::left_thigh]);
  for (std::size_t i = 0; i < region.vertices.size(); ++i)
    EXPECT_EQ(region.local_of[region.vertices[i]], static_cast<int>(i));
}

TEST(Region, SeparatePartsKeepTheirOwnPieces) {
  const meshing::Region thighs = meshing::select_region(open_body(), {"thighs"});
  std::set<meshing::Part> parts(thighs.part.begin(), thighs.part.end());
  EXPECT_EQ(parts, (std::set<meshing::Part>{meshing::Part::left_thigh, meshing::Part::right_thigh}));
  // The two thighs meet at the crotch: one piece like a pair of shorts, with a waist loop and two knee loops.
  EXPECT_EQ(thighs.boundary_loops.size(), 3u);
}

TEST(Region, UnknownNamesAreRejected) {
  EXPECT_THAT(error_of([] { meshing::parse_region_names("torso,tail"); }), HasSubstr("unknown name 'tail'"));
  EXPECT_THAT(error_of([] { meshing::parse_region_names(" , "); }), HasSubstr("empty list"));
  EXPECT_EQ(meshing::parse_region_names("thighs, torso,thighs"), (std::vector<std::string>{"thighs", "torso"}));
  EXPECT_EQ(meshing::region_key({"thighs", "torso"}), "thighs+torso");
}

TEST(Correspondence, AffineInJointsSmoothAndInsideTheBody) {
  const auto& model = open_body();
  const meshing::Region region = meshing::select_region(model, meshing::default_region_names());
  const meshing::SkeletonCorrespondence corr = meshing::skeleton_correspondence(model, region);
  const Eigen::VectorXd row_sums = corr.joint_weights * Eigen::VectorXd::Ones(body::kNumJoints);
  EXPECT_LT((row_sums.array() - 1.0).abs().maxCoeff(), 1e-12);
  // Follows the skeleton of any shape exactly: a pure translation of all joints translates c.
  body::JointPositions joints = body::regress_joints(model, model.v_template);
  const meshing::RowMatrixX3d c0 = corr.points(joints);
  joints.rowwise() += Eigen::RowVector3d(0.1, -0.2, 0.3);
  EXPECT_LT(((corr.points(joints) - c0).rowwise() - Eigen::RowVector3d(0.1, -0.2, 0.3)).cwiseAbs().maxCoeff(), 1e-12);

  const meshing::LayerGeometry geometry = meshing::layer_geometry(
      model, region, corr, body::Betas::Zero(), Eigen::VectorXd::Constant(region.num_vertices(), 0.5));
  const Eigen::VectorXd max_thickness = geometry.max_thickness();
  // Arms and thighs: skin-to-bone distance of an adult limb, 2–15 cm (the hip flesh over the femur head is the
  // thickest); torso up to ~25 cm (belly to spine).
  for (int v = 0; v < region.num_vertices(); ++v) {
    EXPECT_GT(max_thickness(v), 0.005);
    EXPECT_LT(max_thickness(v), region.part[v] == meshing::Part::torso ? 0.30 : 0.16);
  }
  // Smooth: neighbouring skin points (≤ 4 cm apart) have correspondences at most 6 cm apart.
  double worst = 0.0;
  for (Eigen::Index f = 0; f < region.faces.rows(); ++f)
    for (int e = 0; e < 3; ++e)
      worst = std::max(
          worst,
          (geometry.skeleton.row(region.faces(f, e)) - geometry.skeleton.row(region.faces(f, (e + 1) % 3))).norm());
  EXPECT_LT(worst, 0.06);
}

TEST(Correspondence, ThicknessFieldIsValidated) {
  const auto& model = open_body();
  const meshing::Region region = meshing::select_region(model, {"left_thigh"});
  const auto corr = meshing::skeleton_correspondence(model, region);
  Eigen::VectorXd h = Eigen::VectorXd::Constant(region.num_vertices(), 0.5);
  h(3) = 1.0;
  EXPECT_THAT(error_of([&] { meshing::layer_geometry(model, region, corr, body::Betas::Zero(), h); }),
              HasSubstr("h = 1 at region vertex 3; expected 0 < h < 1"));
  h(3) = std::nan("");
  EXPECT_THAT(error_of([&] { meshing::layer_geometry(model, region, corr, body::Betas::Zero(), h); }),
              HasSubstr("region vertex 3"));
  EXPECT_THAT(
      error_of([&] { meshing::layer_geometry(model, region, corr, body::Betas::Zero(), Eigen::VectorXd::Ones(2)); }),
      HasSubstr("expected one per region vertex"));
}

}  // namespace sflsh
