#include <sflsh/core/error.hpp>
#include <sflsh/reduced/rotation_vector.hpp>
#include <sflsh/reduced/skeleton_deviation.hpp>

#include <algorithm>
#include <array>

namespace sflsh::reduced {

namespace {

/// One level of a chain as 4×4 homogeneous factors: the map A = [R | c − Rc + τ], its derivatives in the level's
/// coordinates (θ then τ for the root, φ for a joint) and the second derivatives in the rotation (those in τ vanish).
struct Level {
  Eigen::Matrix4d map = Eigen::Matrix4d::Identity();
  std::array<Eigen::Matrix4d, 6> first{};
  std::array<std::array<Eigen::Matrix4d, 3>, 3> second{};
  int count = 3;  ///< coordinates: 6 for the root, 3 for a joint
};

Level make_level(const Eigen::Vector3d& rotation, const Eigen::Vector3d& centre, const Eigen::Vector3d* translation,
                 bool second) {
  const RotationVectorDerivatives d = rotation_vector_derivatives(rotation);
  Level level;
  level.map.topLeftCorner<3, 3>() = d.R;
  level.map.topRightCorner<3, 1>() = centre - d.R * centre + (translation ? *translation : Eigen::Vector3d::Zero());
  for (int k = 0; k < 3; ++k) {
    Eigen::Matrix4d f = Eigen::Matrix4d::Zero();
    f.topLeftCorner<3, 3>() = d.dR[static_cast<std::size_t>(k)];
    f.topRightCorner<3, 1>() = -d.dR[static_cast<std::size_t>(k)] * centre;
    level.first[static_cast<std::size_t>(k)] = f;
  }
  if (translation) {
    level.count = 6;
    for (int k = 0; k < 3; ++k) {
      Eigen::Matrix4d f = Eigen::Matrix4d::Zero();
      f(k, 3) = 1.0;
      level.first[static_cast<std::size_t>(3 + k)] = f;
    }
  }
  if (!second) return level;
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l) {
      const Eigen::Matrix3d& d2 = d.d2R[static_cast<std::size_t>(k)][static_cast<std::size_t>(l)];
      Eigen::Matrix4d s = Eigen::Matrix4d::Zero();
      s.topLeftCorner<3, 3>() = d2;
      s.topRightCorner<3, 1>() = -d2 * centre;
      level.second[static_cast<std::size_t>(k)][static_cast<std::size_t>(l)] = s;
    }
  return level;
}

Eigen::Vector4d homogeneous(const Eigen::Vector3d& p) { return Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0); }

/// D_b and its derivatives for the chain of levels (root first).
void compose(const std::vector<const Level*>& levels, const std::vector<int>& first_coordinate, bool second,
             BoneDeviation& bone) {
  const std::size_t m = levels.size();
  std::vector<Eigen::Matrix4d> prefix(m + 1), suffix(m);
  prefix[0].setIdentity();
  for (std::size_t l = 0; l < m; ++l) prefix[l + 1] = prefix[l] * levels[l]->map;
  suffix[m - 1].setIdentity();
  for (std::size_t l = m - 1; l > 0; --l) suffix[l - 1] = levels[l]->map * suffix[l];
  bone.map = prefix[m].topRows<3>();
  bone.coordinates.clear();
  bone.first.clear();
  std::vector<std::pair<std::size_t, int>> where;  // per coordinate of the bone: its level and its index there
  for (std::size_t l = 0; l < m; ++l)
    for (int k = 0; k < levels[l]->count; ++k) {
      bone.coordinates.push_back(first_coordinate[l] + k);
      where.emplace_back(l, k);
      bone.first.push_back((prefix[l] * levels[l]->first[static_cast<std::size_t>(k)] * suffix[l]).topRows<3>());
    }
  bone.second.clear();
  if (!second) return;
  const std::size_t n = where.size();
  bone.second.assign(n * n, Matrix34d::Zero());
  for (std::size_t a = 0; a < n; ++a) {
    const auto [la, ka] = where[a];
    Eigen::Matrix4d left = prefix[la] * levels[la]->first[static_cast<std::size_t>(ka)];
    Eigen::Matrix4d middle = Eigen::Matrix4d::Identity();  // A_{la+1} ⋯ A_{lb−1}
    std::size_t level_of_middle = la + 1;
    for (std::size_t b = a; b < n; ++b) {
      const auto [lb, kb] = where[b];
      Matrix34d value = Matrix34d::Zero();
      if (lb == la) {
        if (ka < 3 && kb < 3)  // second derivatives in τ vanish
          value =
              (prefix[la] * levels[la]->second[static_cast<std::size_t>(ka)][static_cast<std::size_t>(kb)] * suffix[la])
                  .topRows<3>();
      } else {
        while (level_of_middle < lb) middle = middle * levels[level_of_middle++]->map;
        value = (left * middle * levels[lb]->first[static_cast<std::size_t>(kb)] * suffix[lb]).topRows<3>();
      }
      bone.second[a * n + b] = value;
      bone.second[b * n + a] = value;
    }
  }
}

}  // namespace

SkeletonDeviation::SkeletonDeviation(const JointTrackingSetup& setup) : tracked_(setup.joints) {
  const auto joints = static_cast<int>(setup.parents.size());
  require(std::is_sorted(tracked_.begin(), tracked_.end()), "tracking skeleton: the tracked joints must be ascending");
  std::vector<int> tracked_index(static_cast<std::size_t>(joints), -1);
  for (std::size_t j = 0; j < tracked_.size(); ++j) {
    const int joint = tracked_[j];
    require(joint > 0 && joint < joints && setup.parents[static_cast<std::size_t>(joint)] >= 0,
            "tracking skeleton: joint {} cannot be tracked (the root has its own six coordinates)", joint);
    tracked_index[static_cast<std::size_t>(joint)] = static_cast<int>(j);
  }
  // The bone of a joint: its nearest tracked ancestor-or-self (parents come before children).
  bone_of_joint_.assign(static_cast<std::size_t>(joints), 0);
  for (int k = 0; k < joints; ++k) {
    const int parent = setup.parents[static_cast<std::size_t>(k)];
    require(parent < k, "tracking skeleton: joint {} comes before its parent {}", k, parent);
    const int own = tracked_index[static_cast<std::size_t>(k)];
    bone_of_joint_[static_cast<std::size_t>(k)] =
        own >= 0 ? 1 + own : (parent >= 0 ? bone_of_joint_[static_cast<std::size_t>(parent)] : 0);
  }
  chains_.assign(tracked_.size() + 1, {});
  for (std::size_t j = 0; j < tracked_.size(); ++j) {
    const int parent = setup.parents[static_cast<std::size_t>(tracked_[j])];
    const int parent_bone = bone_of_joint_[static_cast<std::size_t>(parent)];
    chains_[j + 1] = chains_[static_cast<std::size_t>(parent_bone)];
    chains_[j + 1].push_back(static_cast<int>(j));
  }
  node_blends_.reserve(setup.node_weights.size());
  for (const JointBlend& w : setup.node_weights) node_blends_.push_back(bone_blend(w));
}

JointBlend SkeletonDeviation::bone_blend(const JointBlend& joint_weights) const {
  if (tracked_.empty()) return root_blend_;
  JointBlend blend;
  for (const auto& [joint, weight] : joint_weights) {
    require(joint >= 0 && static_cast<std::size_t>(joint) < bone_of_joint_.size(),
            "tracking skeleton: skinning weight of joint {} outside the skeleton", joint);
    const int bone = bone_of_joint_[static_cast<std::size_t>(joint)];
    const auto it = std::find_if(blend.begin(), blend.end(), [bone](const auto& e) { return e.first == bone; });
    if (it == blend.end())
      blend.emplace_back(bone, weight);
    else
      it->second += weight;
  }
  if (blend.empty()) return root_blend_;
  return blend;
}

const JointBlend& SkeletonDeviation::node_blend(int node) const {
  if (node_blends_.empty()) return root_blend_;
  return node_blends_.at(static_cast<std::size_t>(node));
}

DeviationFrame SkeletonDeviation::frame(const Eigen::VectorXd& x, Eigen::Index offset, const Eigen::Vector3d& pivot,
                                        const std::vector<Eigen::Vector3d>& centres, bool second) const {
  require(centres.size() == tracked_.size(), "tracking skeleton: {} joint centres for {} tracked joints",
          centres.size(), tracked_.size());
  DeviationFrame frame;
  frame.offset = offset;
  frame.size = size();
  frame.skeleton = this;
  const Eigen::Vector3d translation = x.segment<3>(offset + 3);
  std::vector<Level> levels;
  levels.reserve(tracked_.size() + 1);
  levels.push_back(make_level(x.segment<3>(offset), pivot, &translation, second));
  for (std::size_t j = 0; j < tracked_.size(); ++j)
    levels.push_back(
        make_level(x.segment<3>(offset + 6 + 3 * static_cast<Eigen::Index>(j)), centres[j], nullptr, second));
  frame.bones.resize(chains_.size());
  for (std::size_t b = 0; b < chains_.size(); ++b) {
    std::vector<const Level*> chain{&levels[0]};
    std::vector<int> first_coordinate{0};
    for (int j : chains_[b]) {
      chain.push_back(&levels[static_cast<std::size_t>(j) + 1]);
      first_coordinate.push_back(6 + 3 * j);
    }
    compose(chain, first_coordinate, second, frame.bones[b]);
  }
  return frame;
}

const JointBlend& DeviationFrame::blend(int node) const { return skeleton->node_blend(node); }

Eigen::Vector3d DeviationFrame::apply_blend(const JointBlend& blend, const Eigen::Vector3d& p) const {
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  const Eigen::Vector4d ph = homogeneous(p);
  for (const auto& [b, w] : blend) y += w * bones[static_cast<std::size_t>(b)].map * ph;
  return y;
}

Eigen::Matrix3d DeviationFrame::linear_blend(const JointBlend& blend) const {
  Eigen::Matrix3d L = Eigen::Matrix3d::Zero();
  for (const auto& [b, w] : blend) L += w * bones[static_cast<std::size_t>(b)].map.leftCols<3>();
  return L;
}

Matrix34d DeviationFrame::map_blend(const JointBlend& blend) const {
  Matrix34d M = Matrix34d::Zero();
  for (const auto& [b, w] : blend) M += w * bones[static_cast<std::size_t>(b)].map;
  return M;
}

void DeviationFrame::jacobian(int node, const Eigen::Vector3d& p, Eigen::Matrix<double, 3, Eigen::Dynamic>& J) const {
  J.setZero(3, size);
  const Eigen::Vector4d ph = homogeneous(p);
  for (const auto& [b, w] : blend(node)) {
    const BoneDeviation& bone = bones[static_cast<std::size_t>(b)];
    for (std::size_t k = 0; k < bone.coordinates.size(); ++k) J.col(bone.coordinates[k]) += w * bone.first[k] * ph;
  }
}

void DeviationFrame::linear_derivatives(int node, std::vector<Eigen::Matrix3d>& dL) const {
  dL.assign(static_cast<std::size_t>(size), Eigen::Matrix3d::Zero());
  for (const auto& [b, w] : blend(node)) {
    const BoneDeviation& bone = bones[static_cast<std::size_t>(b)];
    for (std::size_t k = 0; k < bone.coordinates.size(); ++k)
      dL[static_cast<std::size_t>(bone.coordinates[k])] += w * bone.first[k].leftCols<3>();
  }
}

void DeviationFrame::add_second(int node, const Eigen::Vector3d& p, const Eigen::Vector3d& g, double scale,
                                Eigen::Ref<Eigen::MatrixXd> block) const {
  const Eigen::Vector4d ph = homogeneous(p);
  for (const auto& [b, w] : blend(node)) {
    const BoneDeviation& bone = bones[static_cast<std::size_t>(b)];
    require(!bone.second.empty() || bone.coordinates.empty(), "tracking skeleton: second derivatives not evaluated");
    const std::size_t n = bone.coordinates.size();
    for (std::size_t k = 0; k < n; ++k)
      for (std::size_t l = 0; l < n; ++l)
        block(bone.coordinates[k], bone.coordinates[l]) += scale * w * g.dot(bone.second[k * n + l] * ph);
  }
}

}  // namespace sflsh::reduced
