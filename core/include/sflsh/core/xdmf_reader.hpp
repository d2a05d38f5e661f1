#pragma once
// Reads back a time series written by xdmf::Series (xdmf_series.hpp): the steps, times and dataset references of
// the `.xmf` (parsed with VTK's XML parser), the arrays from the `.h5` beside it (HDF5's C library; compressed
// datasets are read transparently). `sflsh render` draws a run written with --format xdmf through it; tests read
// the series back. Only the layout xdmf::Series writes is accepted (one temporal collection of uniform grids whose
// DataItems are HDF references); anything else is one error line naming the file and what was expected.
#include <sflsh/core/vtk_io.hpp>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace sflsh::xdmf {

class SeriesReader {
 public:
  /// Parses `xmf`; throws sflsh::Error "<xmf>: …" when it cannot be read or is not such a series.
  explicit SeriesReader(std::filesystem::path xmf);

  std::size_t steps() const { return steps_.size(); }
  /// The time of step `step` [s].
  double time(std::size_t step) const;
  /// The cells (triangles or tetrahedra, 0-based node indices) shared by every step.
  vtk::Cells cells() const;
  /// The node positions of step `step` [m].
  vtk::Points points(std::size_t step) const;
  /// The names of the node arrays of step `step` (static ones included), in the file's order.
  std::vector<std::string> point_array_names(std::size_t step) const;
  /// A node array of step `step` (rows × components, Float64 whatever the file's precision); throws naming the
  /// file, the step and the arrays there are when the step has no such array.
  Eigen::MatrixXd point_array(std::size_t step, const std::string& name) const;
  /// The `.h5` the series' datasets are in.
  const std::filesystem::path& heavy_data() const { return h5_; }

 private:
  struct DataRef {
    std::string path;  ///< dataset path inside the .h5
    int rows = 0, columns = 1;
  };
  struct Step {
    double time = 0.0;
    DataRef geometry;
    std::vector<std::pair<std::string, DataRef>> point_arrays;
  };
  std::filesystem::path xmf_, h5_;
  DataRef topology_;
  std::vector<Step> steps_;

  const Step& step_at(std::size_t step) const;
  Eigen::MatrixXd read(const DataRef& ref) const;
};

}  // namespace sflsh::xdmf
