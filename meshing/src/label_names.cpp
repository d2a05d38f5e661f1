// Names of the label values (label_names.hpp).
#include <sflsh/meshing/label_names.hpp>

namespace sflsh::meshing {

const char* node_kind_name(NodeKind kind) {
  switch (kind) {
    case NodeKind::interior:
      return "interior";
    case NodeKind::outer:
      return "outer";
    case NodeKind::inner:
      return "inner";
    case NodeKind::side:
      return "side";
  }
  return "unknown";
}

std::vector<std::string> part_names() {
  std::vector<std::string> names;
  for (int k = 0; k < kNumParts; ++k) names.emplace_back(part_name(static_cast<Part>(k)));
  return names;
}

std::vector<std::string> node_kind_names() {
  std::vector<std::string> names;
  for (int k = 0; k < kNumNodeKinds; ++k) names.emplace_back(node_kind_name(static_cast<NodeKind>(k)));
  return names;
}

}  // namespace sflsh::meshing
