#pragma once
// A compact time series of one mesh: XDMF 3 (the light XML, `.xmf`) over one HDF5 file (the heavy data,
// `.h5`). The topology is stored once; the node positions once per step only when they change; every field
// once per step, or once for the whole series when it is declared static (material fields, labels).
// Float32 halves the file; zlib compression (HDF5's shuffle + deflate filters, one chunk per dataset) shrinks it
// further and is read transparently by every HDF5 reader (ParaView, meshio through h5py, h5dump). ParaView opens the
// `.xmf` (its XDMF 3 reader) and meshio reads it (meshio.xdmf.TimeSeriesReader); the datasets are ordinary HDF5 (h5py,
// h5dump). Layout of the `.h5`:
//   /topology                      cells × k  int32 (k = 3 triangles, 4 tetrahedra)
//   /geometry/<step>               nodes × 3  positions [m] (a step that does not move the nodes reuses the last)
//   /point/<name>/<step>, /cell/<name>/<step>      rows × components
//   /static/point/<name>, /static/cell/<name>      fields that do not change over time
// Every dataset has a string attribute `unit` (core/array_units.hpp); the `.xmf`'s Domain holds
// <Information Name="units" Value="<name>: <unit>; …"/> and one Information per label list (`part_names`, …).
// The file format is documented for users in docs/output.md.
#include <sflsh/core/vtk_io.hpp>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace sflsh::xdmf {

enum class Precision { float64, float32 };
/// "float64" | "float32"; throws sflsh::Error naming `what` otherwise.
Precision parse_precision(const std::string& name, const std::string& what);

class Series {
 public:
  /// Opens `<stem>.h5` beside `xmf_path` (replacing it) for the mesh of `cells` (3 or 4 columns).
  /// `compression`: zlib (shuffle + deflate level 1) or none (contiguous datasets, the fastest to write); HDF5
  /// has no LZ4 filter here, so lz4 is refused with an error naming the choice.
  Series(std::filesystem::path xmf_path, const Eigen::Ref<const vtk::Cells>& cells,
         Precision precision = Precision::float64, vtk::Compression compression = vtk::Compression::none);
  ~Series();
  Series(const Series&) = delete;
  Series& operator=(const Series&) = delete;

  /// Fields that stay the same in every step: written once and referenced by every step.
  void set_static(const vtk::Fields& fields);
  /// One step at time `time` [s]: the node positions [m] and the fields that change.
  void write(double time, const Eigen::Ref<const vtk::Points>& points, const vtk::Fields& fields);
  /// Closes the HDF5 file and writes the `.xmf` (atomically). Called by the destructor when not called.
  void close();

  std::size_t steps() const;
  /// Bytes of the `.h5` so far (after flushing).
  std::uintmax_t bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sflsh::xdmf
