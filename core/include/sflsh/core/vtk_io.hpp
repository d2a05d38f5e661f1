#pragma once
// VTK XML output for ParaView, VTK and meshio: surfaces (.vtp), volume meshes (.vtu), and .pvd time series.
// Every file is written atomically (temp file + rename). Inline binary data, zlib-compressed by default
// (surface frame series may choose LZ4, about 8× faster to write and ~1.3× larger, or no compression; meshio
// reads zlib but not LZ4).
// Every file says the unit of each of its arrays: a text array `units` in its field data, one line
// "<name>: <unit>" per array name (core/array_units.hpp; docs/output.md). Text arrays (`units`, label names)
// are UTF-8 text in a UInt8 array, one line per value: meshio's VTU reader refuses VTK's string arrays.
// Surfaces carry unit point normals.
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
  Eigen::MatrixXd values;  ///< rows = points (or cells), cols = components
  bool integer = false;    ///< store as Int32 instead of Float64 (e.g. labels)
};

/// A text array of field data: the names of the values of a label array (`part_names`, `node_kind_names`),
/// written as UTF-8 text in a UInt8 array, one line per value.
struct Labels {
  std::string name;
  std::vector<std::string> values;  ///< values[k] names the label value k
};

struct Fields {
  std::vector<Field> point_data;
  std::vector<Field> cell_data;
  std::vector<Field> field_data;  ///< whole-dataset values (e.g. time), one row
  std::vector<Labels> labels;     ///< whole-dataset string arrays
  /// write_surface adds the point array `Normals` (unit, area-weighted, Float32) of the written triangles
  /// when the fields hold none, and marks `Normals` as the surface's normals (ParaView shades with them).
  bool normals = true;
};

/// Area-weighted unit vertex normals of a triangle surface (zero at vertices of no triangle); they point to
/// the side from which the triangles' vertices run counter-clockwise.
Points vertex_normals(const Eigen::Ref<const Points>& points, const Eigen::Ref<const Cells>& triangles);

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

/// A ParaView collection (.pvd): write() lists every added file with its time, part and name. ParaView opens
/// it as one multiblock per time step with a block per part (the block named after the entry's name).
class PvdSeries {
 public:
  explicit PvdSeries(std::filesystem::path pvd_path) : path_(std::move(pvd_path)) {}
  /// Records `file` (relative to the .pvd's folder) at time `t` [s].
  void add(double t, const std::string& file) { entries_.push_back({t, true, file, 0, {}}); }
  /// Records `file` at time `t` [s] as part `part` (0, 1, …) named `name` (e.g. a scene's bodies and objects).
  void add(double t, const std::string& file, int part, const std::string& name) {
    entries_.push_back({t, true, file, part, name});
  }
  /// Records a file that holds at every time (no timestep), as part `part` named `name`.
  void add_untimed(const std::string& file, int part, const std::string& name) {
    entries_.push_back({0.0, false, file, part, name});
  }
  /// Writes the .pvd atomically (may be called repeatedly to keep a partial series readable).
  void write() const;
  std::size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    double time;
    bool timed;
    std::string file;
    int part;
    std::string name;
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
/// Reads the names of the cell-data arrays.
std::vector<std::string> read_cell_array_names(const std::filesystem::path& path);
/// Reads one cell-data array (rows = cells).
Eigen::MatrixXd read_cell_array(const std::filesystem::path& path, const std::string& name);
/// Reads one numeric field-data array (e.g. `TimeValue`, rows = tuples).
Eigen::MatrixXd read_field_array(const std::filesystem::path& path, const std::string& name);
/// Reads the names of the field-data arrays (numbers and text).
std::vector<std::string> read_field_array_names(const std::filesystem::path& path);
/// Reads a text array of the field data (`units`, `part_names`, …: UInt8 text, one value per line, or a string
/// array as older files hold); throws when there is none of that name.
std::vector<std::string> read_field_strings(const std::filesystem::path& path, const std::string& name);
/// Reads the cells (triangles or tetrahedra) of a .vtp or .vtu file, one row each.
Cells read_cells(const std::filesystem::path& path);

}  // namespace sflsh::vtk
