// Region selection on the skin (issue: region with a smooth, clean boundary curve).
#include <sflsh/core/error.hpp>
#include <sflsh/meshing/region.hpp>

#include <algorithm>
#include <map>
#include <numeric>
#include <queue>
#include <set>
#include <sstream>

namespace sflsh::meshing {
namespace {

struct PartJoints {
  const char* region;
  Part part;
  std::vector<const char*> joints;
};

// Which SMPL joints drive each part. The torso includes the collars (the shoulder girdle); an upper
// arm is driven by SMPL's "shoulder" joint and a thigh by its "hip" joint.
const std::vector<PartJoints>& part_table() {
  static const std::vector<PartJoints> table = {
      {"torso", Part::torso, {"pelvis", "spine1", "spine2", "spine3", "left_collar", "right_collar"}},
      {"left_upper_arm", Part::left_upper_arm, {"left_shoulder"}},
      {"right_upper_arm", Part::right_upper_arm, {"right_shoulder"}},
      {"left_thigh", Part::left_thigh, {"left_hip"}},
      {"right_thigh", Part::right_thigh, {"right_hip"}},
  };
  return table;
}

std::vector<Part> parts_of(const std::string& name) {
  if (name == "upper_arms") return {Part::left_upper_arm, Part::right_upper_arm};
  if (name == "thighs") return {Part::left_thigh, Part::right_thigh};
  for (const auto& entry : part_table())
    if (name == entry.region) return {entry.part};
  return {};
}

using Edge = std::pair<int, int>;
Edge undirected(int a, int b) { return a < b ? Edge{a, b} : Edge{b, a}; }

// Face adjacency across edges (−1 on the body's own boundary, which a closed body does not have).
std::vector<std::array<int, 3>> face_neighbours(const body::RowMatrixX3i& faces) {
  std::map<Edge, std::vector<int>> by_edge;
  for (int f = 0; f < faces.rows(); ++f)
    for (int e = 0; e < 3; ++e) by_edge[undirected(faces(f, e), faces(f, (e + 1) % 3))].push_back(f);
  std::vector<std::array<int, 3>> neighbours(faces.rows(), {-1, -1, -1});
  for (int f = 0; f < faces.rows(); ++f)
    for (int e = 0; e < 3; ++e) {
      const auto& list = by_edge[undirected(faces(f, e), faces(f, (e + 1) % 3))];
      for (int g : list)
        if (g != f) neighbours[f][e] = g;
    }
  return neighbours;
}

// Connected components of the selected faces (across edges); returns a label per face (−1: not selected).
std::vector<int> components(const std::vector<char>& selected, const std::vector<std::array<int, 3>>& neighbours,
                            int& count) {
  std::vector<int> label(selected.size(), -1);
  count = 0;
  for (std::size_t start = 0; start < selected.size(); ++start) {
    if (!selected[start] || label[start] >= 0) continue;
    std::queue<int> queue;
    queue.push(static_cast<int>(start));
    label[start] = count;
    while (!queue.empty()) {
      const int f = queue.front();
      queue.pop();
      for (int g : neighbours[f])
        if (g >= 0 && selected[g] && label[g] < 0) {
          label[g] = count;
          queue.push(g);
        }
    }
    ++count;
  }
  return label;
}

// Morphological clean-up of a face set: a face joins when two or three of its neighbours are in
// (fills notches), a selected face leaves when at most one neighbour is in (removes teeth). Repeated
// until nothing changes. Returns the number of sweeps.
int clean_teeth(std::vector<char>& selected, const std::vector<std::array<int, 3>>& neighbours) {
  for (int sweep = 1; sweep <= 200; ++sweep) {
    bool changed = false;
    for (std::size_t f = 0; f < selected.size(); ++f) {
      int in = 0;
      for (int g : neighbours[f]) in += (g >= 0 && selected[g]) ? 1 : 0;
      if (!selected[f] && in >= 2) {
        selected[f] = 1;
        changed = true;
      } else if (selected[f] && in <= 1) {
        selected[f] = 0;
        changed = true;
      }
    }
    if (!changed) return sweep;
  }
  throw_error("region selection: boundary clean-up did not settle after 200 sweeps");
}

// Drops selected components smaller than 5% of the largest (islands of stray weights) and fills
// unselected components of less than 1% of the skin (holes inside the region, e.g. at the navel).
// A region of separate parts (e.g. the two thighs alone) keeps one component per part; the head,
// forearms and lower legs (each several % of the skin) stay outside.
void drop_islands_fill_holes(std::vector<char>& selected, const std::vector<std::array<int, 3>>& neighbours) {
  for (int pass = 0; pass < 2; ++pass) {
    const bool want = pass == 0;
    std::vector<char> mask(selected.size());
    for (std::size_t f = 0; f < selected.size(); ++f) mask[f] = (selected[f] != 0) == want;
    int count = 0;
    const auto label = components(mask, neighbours, count);
    if (count <= 1) continue;
    std::vector<long> size(count, 0);
    for (int l : label)
      if (l >= 0) ++size[l];
    const long largest = *std::max_element(size.begin(), size.end());
    for (std::size_t f = 0; f < selected.size(); ++f) {
      if (label[f] < 0) continue;
      const bool small =
          want ? size[label[f]] * 20 < largest : size[label[f]] * 100 < static_cast<long>(selected.size());
      if (small) selected[f] = want ? 0 : 1;
    }
  }
}

// A vertex is pinched when its selected faces form more than one fan around it. Such vertices get all
// their faces selected (the smaller change of the two options for a notch).
int fix_pinched_vertices(std::vector<char>& selected, const body::RowMatrixX3i& faces, int num_vertices,
                         const std::vector<std::array<int, 3>>& neighbours) {
  std::vector<std::vector<int>> faces_of(num_vertices);
  for (int f = 0; f < faces.rows(); ++f)
    for (int e = 0; e < 3; ++e) faces_of[faces(f, e)].push_back(f);
  int fixed = 0;
  for (int v = 0; v < num_vertices; ++v) {
    std::vector<int> in;
    for (int f : faces_of[v])
      if (selected[f]) in.push_back(f);
    if (in.empty() || in.size() == faces_of[v].size()) continue;
    // Count fans: connected components of the selected faces around v (adjacent across an edge at v).
    std::set<int> left(in.begin(), in.end());
    int fans = 0;
    while (!left.empty()) {
      ++fans;
      std::queue<int> queue;
      queue.push(*left.begin());
      left.erase(left.begin());
      while (!queue.empty()) {
        const int f = queue.front();
        queue.pop();
        for (int g : neighbours[f])
          if (left.count(g)) {
            left.erase(g);
            queue.push(g);
          }
      }
    }
    if (fans > 1) {
      for (int f : faces_of[v]) selected[f] = 1;
      ++fixed;
    }
  }
  return fixed;
}

}  // namespace

const std::vector<std::string>& known_region_names() {
  static const std::vector<std::string> names = {"torso",           "upper_arms", "thighs",     "left_upper_arm",
                                                 "right_upper_arm", "left_thigh", "right_thigh"};
  return names;
}

std::vector<std::string> default_region_names() { return {"torso", "upper_arms", "thighs"}; }

std::vector<std::string> parse_region_names(const std::string& csv) {
  std::vector<std::string> names;
  std::stringstream stream(csv);
  std::string name;
  while (std::getline(stream, name, ',')) {
    name.erase(0, name.find_first_not_of(" \t"));
    name.erase(name.find_last_not_of(" \t") + 1);
    if (name.empty()) continue;
    if (parts_of(name).empty()) {
      std::string known;
      for (const auto& k : known_region_names()) known += (known.empty() ? "" : ", ") + k;
      throw_error("region: unknown name '{}' (expected a comma-separated list of: {})", name, known);
    }
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  require(!names.empty(), "region: empty list '{}' (expected e.g. torso,upper_arms,thighs)", csv);
  return names;
}

std::string region_key(const std::vector<std::string>& names) {
  std::vector<std::string> sorted = names;
  std::sort(sorted.begin(), sorted.end());
  std::string key;
  for (const auto& n : sorted) key += (key.empty() ? "" : "+") + n;
  return key;
}

namespace {

// The parts asked for by the region names, as a flag per part.
std::vector<char> region_wanted_parts(const std::vector<std::string>& names) {
  std::vector<char> wanted(kNumParts, 0);
  for (const auto& name : names) {
    const auto parts = parts_of(name);
    require(!parts.empty(), "region: unknown name '{}'", name);
    for (Part p : parts) wanted[static_cast<int>(p)] = 1;
  }
  return wanted;
}

// Per vertex the summed skinning weight of each part's joints (#V by kNumParts).
Eigen::MatrixXd region_part_weights(const body::BodyModel& model, int n) {
  Eigen::MatrixXd part_weight = Eigen::MatrixXd::Zero(n, kNumParts);
  for (const auto& entry : part_table())
    for (const char* joint : entry.joints)
      part_weight.col(static_cast<int>(entry.part)) += model.weights.col(body::joint_index(joint));
  return part_weight;
}

// Score: summed weight of the wanted parts, smoothed by a few Jacobi sweeps of the uniform
// Laplacian (removes the staircase of per-vertex weights before thresholding).
Eigen::VectorXd region_smoothed_score(const Eigen::MatrixXd& part_weight, const std::vector<char>& wanted,
                                      const body::RowMatrixX3i& faces, int n) {
  Eigen::VectorXd score = Eigen::VectorXd::Zero(n);
  for (int p = 0; p < kNumParts; ++p)
    if (wanted[p]) score += part_weight.col(p);
  std::vector<std::set<int>> ring(n);
  for (int f = 0; f < faces.rows(); ++f)
    for (int e = 0; e < 3; ++e) {
      ring[faces(f, e)].insert(faces(f, (e + 1) % 3));
      ring[faces(f, (e + 1) % 3)].insert(faces(f, e));
    }
  for (int sweep = 0; sweep < 8; ++sweep) {
    Eigen::VectorXd next = score;
    for (int v = 0; v < n; ++v) {
      if (ring[v].empty()) continue;
      double sum = 0.0;
      for (int w : ring[v]) sum += score(w);
      next(v) = 0.5 * score(v) + 0.5 * sum / static_cast<double>(ring[v].size());
    }
    score = next;
  }
  return score;
}

// The faces whose mean score exceeds ½, cleaned of teeth, notches, islands, holes and pinched vertices.
std::vector<char> region_selected_faces(const Eigen::VectorXd& score, const body::RowMatrixX3i& faces, int n) {
  std::vector<char> selected(faces.rows(), 0);
  for (int f = 0; f < faces.rows(); ++f)
    selected[f] = (score(faces(f, 0)) + score(faces(f, 1)) + score(faces(f, 2))) / 3.0 > 0.5;
  const auto neighbours = face_neighbours(faces);
  for (int round = 0; round < 10; ++round) {
    clean_teeth(selected, neighbours);
    drop_islands_fill_holes(selected, neighbours);
    if (fix_pinched_vertices(selected, faces, n, neighbours) == 0) break;
  }
  clean_teeth(selected, neighbours);
  return selected;
}

// Fills the region's vertices, local indices, faces (in local indices) and body faces from the selection.
void region_gather_faces(Region& region, const std::vector<char>& selected, const body::RowMatrixX3i& faces, int n,
                         const std::vector<std::string>& names) {
  region.local_of.assign(n, -1);
  std::vector<int> face_list;
  for (int f = 0; f < faces.rows(); ++f)
    if (selected[f]) face_list.push_back(f);
  require(!face_list.empty(), "region '{}': no skin faces selected (are the skinning weights SMPL-like?)",
          region_key(names));
  for (int f : face_list)
    for (int e = 0; e < 3; ++e) region.local_of[faces(f, e)] = 0;
  for (int v = 0; v < n; ++v)
    if (region.local_of[v] == 0) {
      region.local_of[v] = static_cast<int>(region.vertices.size());
      region.vertices.push_back(v);
    }
  region.faces.resize(static_cast<Eigen::Index>(face_list.size()), 3);
  for (std::size_t i = 0; i < face_list.size(); ++i)
    for (int e = 0; e < 3; ++e) region.faces(static_cast<Eigen::Index>(i), e) = region.local_of[faces(face_list[i], e)];
  region.body_faces = face_list;
}

// Gives each region vertex the wanted part of largest weight.
void region_assign_parts(Region& region, const Eigen::MatrixXd& part_weight, const std::vector<char>& wanted) {
  region.part.resize(region.vertices.size());
  for (std::size_t i = 0; i < region.vertices.size(); ++i) {
    int best = -1;
    for (int p = 0; p < kNumParts; ++p)
      if (wanted[p] && (best < 0 || part_weight(region.vertices[i], p) > part_weight(region.vertices[i], best)))
        best = p;
    region.part[i] = static_cast<Part>(best);
  }
}

// Boundary loops: directed boundary edges a → b of the region faces, chained.
void region_boundary_loops(Region& region, const std::vector<std::string>& names) {
  std::map<Edge, int> count;
  for (Eigen::Index f = 0; f < region.faces.rows(); ++f)
    for (int e = 0; e < 3; ++e) ++count[undirected(region.faces(f, e), region.faces(f, (e + 1) % 3))];
  std::map<int, int> next;
  for (Eigen::Index f = 0; f < region.faces.rows(); ++f)
    for (int e = 0; e < 3; ++e) {
      const int a = region.faces(f, e), b = region.faces(f, (e + 1) % 3);
      if (count[undirected(a, b)] != 1) continue;
      require(next.emplace(a, b).second,
              "region '{}': boundary vertex {} (body vertex {}) is not manifold after clean-up", region_key(names), a,
              region.vertices[a]);
    }
  std::set<int> visited;
  for (const auto& [start, unused] : next) {
    if (visited.count(start)) continue;
    std::vector<int> loop;
    int v = start;
    while (!visited.count(v)) {
      visited.insert(v);
      loop.push_back(v);
      const auto it = next.find(v);
      require(it != next.end(), "region '{}': open boundary chain at body vertex {}", region_key(names),
              region.vertices[v]);
      v = it->second;
    }
    require(v == start && loop.size() >= 3, "region '{}': malformed boundary loop at body vertex {}", region_key(names),
            region.vertices[start]);
    region.boundary_loops.push_back(std::move(loop));
  }
}

}  // namespace

Region select_region(const body::BodyModel& model, const std::vector<std::string>& names) {
  const int n = static_cast<int>(model.num_vertices());
  const auto& faces = model.faces;
  // Parts asked for, and per vertex the weight of each part's joints.
  const std::vector<char> wanted = region_wanted_parts(names);
  const Eigen::MatrixXd part_weight = region_part_weights(model, n);
  const Eigen::VectorXd score = region_smoothed_score(part_weight, wanted, faces, n);
  const std::vector<char> selected = region_selected_faces(score, faces, n);

  Region region;
  region.names = names;
  region_gather_faces(region, selected, faces, n, names);
  region_assign_parts(region, part_weight, wanted);
  region_boundary_loops(region, names);
  return region;
}

}  // namespace sflsh::meshing
