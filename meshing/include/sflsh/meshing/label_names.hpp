#pragma once
// The names of the values of the label arrays `part` and `node_kind` (types.hpp), written beside them as
// the field data `part_names` and `node_kind_names` (docs/output.md, "Label names").
#include <sflsh/meshing/types.hpp>

#include <string>
#include <vector>

namespace sflsh::meshing {

inline constexpr int kNumNodeKinds = 4;
const char* node_kind_name(NodeKind kind);
/// names[k] is the name of the value k.
std::vector<std::string> part_names();
std::vector<std::string> node_kind_names();

}  // namespace sflsh::meshing
