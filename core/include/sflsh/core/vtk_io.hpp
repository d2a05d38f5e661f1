#pragma once
// VTK XML output for ParaView: surfaces (.vtp), volume meshes (.vtu), and .pvd time series.
// Every file is written atomically (temp file + rename). Binary appended data, zlib-compressed by default
// (frame series may choose LZ4, about 8× faster to write and ~1.3× larger, or no compression).
#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace sflsh::vtk {

using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using Cells = Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// A named data array with one row per point (or cell) and 1, 3 or more components.
struct Field {
  std::string name;
  Eigen::MatrixXd values;   ///< rows = points (or cells), cols = components
  bool integer = false;     ///< store as Int32 instead of Float64 (e.g. labels)
};

struct Fields {
  std::vector<Field> point_data;
  std::vector<Field> cell_data;
  std::vector<Field> field_data;  ///< whole-dataset values (e.g. time), one row
};

/// How the binary data blocks are compressed (every VTK/ParaView reader since VTK 8.1 reads all three).
enum class Compression { zlib, lz4, none };
/// "zlib" | "lz4" | "none"; throws sflsh::Error naming `what` otherwise.
Compression parse_compression(const std::string& name, const std::string& what);
const char* to_string(Compression compression);

/// Writes a triangle surface as VTK XML PolyData (.vtp).
void write_surface(const std::filesystem::path& path, const Eigen::Ref<const Points>& points,
                   const Eigen::Ref<const Cells>& triangles, const Fields& fields = {},
                   Compression compression = Compression::zlib);

/// Writes a mesh of tetrahedra (4 columns) or triangles (3 columns) as VTK XML UnstructuredGrid (.vtu).
void write_unstructured(const std::filesystem::path& path, const Eigen::Ref<const Points>& points,
                        const Eigen::Ref<const Cells>& cells, const Fields& fields = {},
                        Compression compression = Compression::zlib);

/// A ParaView collection of time steps: write() lists every added file with its time.
class PvdSeries {
 public:
  explicit PvdSeries(std::filesystem::path pvd_path) : path_(std::move(pvd_path)) {}
  /// Records `file` (relative to the .pvd's folder) at time `t` [s].
  void add(double t, const std::string& file) { entries_.push_back({t, file}); }
  /// Writes the .pvd atomically (may be called repeatedly to keep a partial series readable).
  void write() const;
  std::size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    double time;
    std::string file;
  };
  std::filesystem::path path_;
  std::vector<Entry> entries_;
};

/// Reads the points of a .vtp or .vtu file back with VTK's own reader (tests and tools).
Points read_points(const std::filesystem::path& path);
/// Reads the names of the point-data arrays of a .vtp or .vtu file with VTK's reader.
std::vector<std::string> read_point_array_names(const std::filesystem::path& path);
/// Reads one point-data array (rows = points) with VTK's reader.
Eigen::MatrixXd read_point_array(const std::filesystem::path& path, const std::string& name);

}  // namespace sflsh::vtk
