#pragma once
// Reading back a triangle surface written by vtk::write_surface (.vtp): points, triangles and the frame's time.
#include <sflsh/core/vtk_io.hpp>

#include <filesystem>

namespace sflsh::vtk {

struct SurfaceFrame {
  Points points;      ///< n × 3 [m]
  Cells triangles;    ///< f × 3 point indices
  double time = 0.0;  ///< field data TimeValue [s]; 0 when the file has none
};

/// Reads a .vtp surface; throws sflsh::Error "<file>: …" when it cannot be read or holds cells other than triangles.
SurfaceFrame read_surface_frame(const std::filesystem::path& path);

}  // namespace sflsh::vtk
