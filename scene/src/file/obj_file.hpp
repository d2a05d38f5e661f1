#pragma once
// Reading Wavefront .obj triangle meshes for mesh obstacles (triangle_mesh.cpp), strictly: every vertex
// finite, every face index within the file's vertices, errors as "<file>:<line>: <statement>: …".
#include <sflsh/scene/obstacle.hpp>

#include <filesystem>

namespace sflsh::scene::detail {

struct ObjMesh {
  RowMatrixX3d vertices;   ///< exactly coincident vertices merged, vertices no face uses dropped
  RowMatrixX3i triangles;  ///< polygons fanned into triangles; triangles that merging collapsed dropped
};

/// Reads the `v` and `f` statements (f indices 1-based or negative = relative, "i", "i/t", "i//n", "i/t/n");
/// other statements (vt, vn, o, g, s, usemtl, mtllib, l, …) are ignored. Throws sflsh::Error naming the file
/// and line for a non-finite or missing coordinate, a face with fewer than 3 vertices, an index outside the
/// file's vertices, or a file without faces.
ObjMesh read_obj(const std::filesystem::path& path);

}  // namespace sflsh::scene::detail
