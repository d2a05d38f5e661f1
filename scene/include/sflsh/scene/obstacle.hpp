#pragma once
// Rigid obstacle shapes with a signed distance φ (negative inside), its gradient ∇φ and Hessian ∇²φ,
// each defined in the shape's local frame and placed in the world by a rigid pose
//   p = R q + t   (q local, p world),   φ_world(p) = φ(q),  ∇φ_world = R ∇φ,  ∇²φ_world = R ∇²φ Rᵀ.
// φ is a true (1-Lipschitz) distance for every shape, so |∇φ| = 1 and ∇²φ ∇φ = 0 wherever φ is smooth.
// Where it is not smooth (medial axes inside, the surface of a mesh at a vertex/edge, the axis of a
// capsule, the centre of a sphere) each shape returns one of the one-sided values and says which below.
#include <sflsh/meshing/types.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <limits>
#include <memory>
#include <vector>

namespace sflsh::scene {

using meshing::RowMatrixX3d;
using meshing::RowMatrixX3i;

/// A rigid placement local → world: p = rotation · q + translation.
struct Pose {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< orthonormal, det = +1
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();   ///< [m]

  Eigen::Vector3d to_world(const Eigen::Vector3d& q) const { return rotation * q + translation; }
  Eigen::Vector3d to_local(const Eigen::Vector3d& p) const { return rotation.transpose() * (p - translation); }
};

/// An axis-aligned box [lower, upper]; an empty box has lower > upper, an unbounded one infinite entries.
struct Aabb {
  Eigen::Vector3d lower = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d upper = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());

  void extend(const Eigen::Vector3d& p) {
    lower = lower.cwiseMin(p);
    upper = upper.cwiseMax(p);
  }
  bool empty() const { return (lower.array() > upper.array()).any(); }
  /// Euclidean distance from p to the box [m]; 0 inside (and for an unbounded box along that axis).
  double distance(const Eigen::Vector3d& p) const;
  /// Distance between two boxes [m] (0 when they overlap).
  double distance(const Aabb& other) const;
};

/// A triangulated surface: vertices (V×3) and outward-oriented triangles (F×3).
struct Surface {
  RowMatrixX3d vertices;
  RowMatrixX3i triangles;
};

/// A rigid shape. φ/∇φ/∇²φ are given in the local frame by the shapes; distance() applies the pose.
class Obstacle {
 public:
  virtual ~Obstacle() = default;

  void set_pose(const Pose& pose) { pose_ = pose; }
  const Pose& pose() const { return pose_; }

  /// φ at the world point p [m]; ∇φ (unit) and ∇²φ [1/m] in the world frame when not null.
  double distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient = nullptr,
                  Eigen::Matrix3d* hessian = nullptr) const;
  /// The same in the local frame (q = pose().to_local(p)).
  virtual double local_distance(const Eigen::Vector3d& q, Eigen::Vector3d* gradient,
                                Eigen::Matrix3d* hessian) const = 0;

  /// World-space bounding box of the shape (unbounded along the axes a half-space extends to).
  Aabb bounds() const;
  /// Bounding box in the local frame.
  virtual Aabb local_bounds() const = 0;

  /// A closed (for the half-space: a finite square patch) outward triangulated surface in the world
  /// frame for output; `n_segments` ≥ 3 sets the resolution of curved parts (ignored by flat shapes).
  Surface surface(int n_segments = 32) const;
  virtual Surface local_surface(int n_segments) const = 0;

 private:
  Pose pose_;
};

/// Half-space {q : n·q < offset}: φ = n·q − offset (n unit). Smooth everywhere (∇²φ = 0).
/// `display_size` [m] is the side of the square patch surface() draws around the point closest to the
/// origin.
class HalfSpace final : public Obstacle {
 public:
  HalfSpace(const Eigen::Vector3d& normal, double offset, double display_size = 1.0);
  double local_distance(const Eigen::Vector3d& q, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const override;
  Aabb local_bounds() const override;
  Surface local_surface(int n_segments) const override;
  const Eigen::Vector3d& normal() const { return normal_; }
  double offset() const { return offset_; }

 private:
  Eigen::Vector3d normal_;
  double offset_;
  double display_size_;
};

/// Ball of `radius` centred at the local origin: φ = |q| − r, ∇φ = q/|q|, ∇²φ = (I − ∇φ∇φᵀ)/|q|.
/// Not smooth at the centre only: there it returns ∇φ = e_z and ∇²φ = 0.
class Sphere final : public Obstacle {
 public:
  explicit Sphere(double radius);
  double local_distance(const Eigen::Vector3d& q, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const override;
  Aabb local_bounds() const override;
  Surface local_surface(int n_segments) const override;
  double radius() const { return radius_; }

 private:
  double radius_;
};

/// Box |q_i| ≤ half_extent_i. Outside: distance to the box (∇²φ = (P − ∇φ∇φᵀ)/φ with P the projector
/// on the axes where q is outside the slab: 0 in face regions, non-zero in edge and corner regions).
/// Inside: φ = max_i (|q_i| − a_i), ∇φ = ±e_i of the nearest face, ∇²φ = 0; not smooth on the inner
/// medial planes (ties go to the lowest axis) and ∇²φ jumps across the outer region boundaries (φ is C¹).
class Box final : public Obstacle {
 public:
  explicit Box(const Eigen::Vector3d& half_extent);
  double local_distance(const Eigen::Vector3d& q, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const override;
  Aabb local_bounds() const override;
  Surface local_surface(int n_segments) const override;
  const Eigen::Vector3d& half_extent() const { return half_extent_; }

 private:
  Eigen::Vector3d half_extent_;
};

/// Capsule: the points within `radius` of the segment from (0,0,−half_length) to (0,0,+half_length).
/// φ = |q − c(q)| − r with c(q) the closest point of the segment; ∇²φ = (P − ∇φ∇φᵀ)/|q − c| with
/// P = I − e_z e_zᵀ beside the segment and P = I beyond its ends. Not smooth on the segment itself
/// (returns ∇φ = e_x, ∇²φ = 0 there); ∇²φ jumps across the planes z = ±half_length (φ is C¹).
class Capsule final : public Obstacle {
 public:
  Capsule(double radius, double half_length);
  double local_distance(const Eigen::Vector3d& q, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const override;
  Aabb local_bounds() const override;
  Surface local_surface(int n_segments) const override;
  double radius() const { return radius_; }
  double half_length() const { return half_length_; }

 private:
  double radius_;
  double half_length_;
};

/// A triangle mesh, e.g. a loaded object or another body's posed skin. Distance to the closest point
/// (CGAL AABB tree), signed by the angle-weighted pseudonormal of the feature (face, edge or vertex) the
/// closest point lies on [Bærentzen and Aanæs 2005], which gives the correct sign for a closed,
/// consistently oriented (outward) mesh. For an open mesh the sign is only meaningful near the surface.
/// ∇φ = ±(q − c)/|q − c|; ∇²φ = 0 in face regions, ±(I − ∇φ∇φᵀ − e eᵀ)/|φ| in edge regions (e the unit
/// edge) and ±(I − ∇φ∇φᵀ)/|φ| in vertex regions. On the surface (|q − c| < 1e-12 m) ∇φ is the
/// normalised pseudonormal and ∇²φ = 0; ∇²φ jumps across region boundaries (φ is C¹ off the surface and
/// off the medial axis). Queries are const and thread-safe; set_vertices() is not.
class TriangleMesh final : public Obstacle {
 public:
  /// vertices (V×3) [m] in the local frame, triangles (F×3) oriented outward. Throws sflsh::Error on
  /// empty input, bad indices or degenerate (zero-area) triangles.
  TriangleMesh(const RowMatrixX3d& vertices, const RowMatrixX3i& triangles);
  ~TriangleMesh() override;
  TriangleMesh(const TriangleMesh&) = delete;
  TriangleMesh& operator=(const TriangleMesh&) = delete;

  /// Reads a .obj, .stl or .ply file with VTK's readers (polygons triangulated, coincident points
  /// merged so that the pseudonormals see the connectivity). `scale` multiplies the coordinates (e.g.
  /// 0.001 for a file in mm). Throws sflsh::Error naming the file when it cannot be read or has no
  /// triangles.
  static std::unique_ptr<TriangleMesh> load(const std::filesystem::path& path, double scale = 1.0);

  /// Moves the vertices (same count and topology), e.g. to the other body's posed skin of this step:
  /// refits the tree and the pseudonormals (cost O(F log F), measured in docs/contact.md).
  void set_vertices(const RowMatrixX3d& vertices);

  double local_distance(const Eigen::Vector3d& q, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const override;
  Aabb local_bounds() const override { return bounds_; }
  Surface local_surface(int n_segments) const override;

  const RowMatrixX3d& vertices() const { return vertices_; }
  const RowMatrixX3i& triangles() const { return triangles_; }
  /// True when every edge is shared by exactly two triangles with opposite orientations.
  bool closed() const { return closed_; }

 private:
  void rebuild();

  struct Tree;  // the CGAL AABB tree (kept out of this header)
  RowMatrixX3d vertices_;
  RowMatrixX3i triangles_;
  RowMatrixX3i triangle_edges_;                 ///< per triangle, the edge ids of (v0v1, v1v2, v2v0)
  std::vector<Eigen::Vector3d> face_normal_;    ///< unit
  std::vector<Eigen::Vector3d> edge_normal_;    ///< pseudonormal per edge (sum of the adjacent face normals)
  std::vector<Eigen::Vector3d> vertex_normal_;  ///< angle-weighted pseudonormal per vertex
  Aabb bounds_;
  bool closed_ = false;
  std::unique_ptr<Tree> tree_;
};

/// A closed surface of revolution about the local z axis from a profile of (radius, z) points that
/// starts and ends on the axis (radius 0): the poles; n_segments around. Used by the sphere and capsule.
Surface revolve_profile(const std::vector<Eigen::Vector2d>& profile, int n_segments);

}  // namespace sflsh::scene
