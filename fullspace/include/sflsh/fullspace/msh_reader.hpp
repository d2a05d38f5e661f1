#pragma once
// gmsh .msh input and output (ASCII formats 2.2 and 4.1) for the full-space verification problems,
// and a structured box tet mesh for tests and canonical problems.
//
// Reading keeps the 4-node tets (gmsh element type 4) as the mesh; elements of every dimension (points,
// lines, triangles, tets, …) put their nodes into the physical groups they belong to, so a boundary
// condition can name a physical point, curve, surface or volume. Node indices are 0-based in the order
// the nodes appear in the file (gmsh node tags may be sparse and unsorted). Unused nodes are kept.
#include <sflsh/meshing/types.hpp>

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace sflsh::fullspace {

/// The ASCII .msh format versions read and written.
enum class MshVersion { v22, v41 };

/// A tet mesh with named node groups, as read from a .msh file.
struct MshMesh {
  meshing::RowMatrixX3d nodes;  ///< #N by 3 node positions [m], in file node order
  meshing::RowMatrixX4i tets;   ///< #M by 4 node indices (0-based), positively oriented
  /// Physical group name → sorted unique 0-based node indices. Unnamed groups are named by their tag
  /// number ("7"); a group named in $PhysicalNames that has no elements is present and empty.
  std::map<std::string, std::vector<int>> node_groups;
  std::map<std::string, int> group_dimension;  ///< physical group name → its dimension (0 … 3)
  int flipped_tets = 0;                        ///< tets read with negative volume, reordered to positive orientation
  MshVersion version = MshVersion::v41;        ///< format of the file read (v41 for generated meshes)
};

/// Reads an ASCII gmsh .msh file (format 2.2 or 4.1). Skips sections it does not know ($NodeData, …).
/// Negatively oriented tets are flipped (two vertices swapped) and counted in flipped_tets.
/// Throws sflsh::Error "<file>:<line>: $Section: what was expected" on malformed input, binary files,
/// other format versions, references to missing nodes, degenerate (zero-volume) tets and meshes without tets.
MshMesh read_msh(const std::filesystem::path& path);

/// Writes an ASCII gmsh .msh file atomically (readable by read_msh and by gmsh): the tets as the
/// physical volume "volume" (dimension 3), each node group as point elements (gmsh type 15) of its own
/// physical group of dimension 0. Node tags are 1 … N in row order; coordinates round-trip exactly.
/// @param[in] nodes        #N by 3 positions [m]
/// @param[in] tets         #M by 4 node indices (0-based)
/// @param[in] node_groups  group name → 0-based node indices (names must not contain '"' or line breaks,
///                         and "volume" is reserved for the tets)
void write_msh(const std::filesystem::path& path, const meshing::RowMatrixX3d& nodes, const meshing::RowMatrixX4i& tets,
               const std::map<std::string, std::vector<int>>& node_groups, MshVersion version = MshVersion::v41);

/// The box [0, size] split into cells[0]×cells[1]×cells[2] hexahedra of 6 positively oriented tets each
/// (Kuhn/Freudenthal split along each cell's (0,0,0)–(1,1,1) diagonal, conforming across cells).
/// Node (i, j, k) has index i + (cells[0]+1)·(j + (cells[1]+1)·k) (x fastest). Node groups "xmin", "xmax",
/// "ymin", "ymax", "zmin", "zmax" (the nodes of each face, dimension 2) and "all" (dimension 3).
MshMesh box_tet_mesh(const Eigen::Vector3d& size, std::array<int, 3> cells);

}  // namespace sflsh::fullspace
