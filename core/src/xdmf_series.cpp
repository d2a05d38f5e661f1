// XDMF 3 + HDF5 time series (xdmf_series.hpp), written with the HDF5 C library.
#include "hdf5_handle.hpp"

#include <sflsh/core/array_units.hpp>
#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/xdmf_series.hpp>

#include <fcntl.h>
#include <fmt/format.h>
#include <hdf5.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <mutex>
#include <optional>
#include <set>

namespace sflsh::xdmf {

namespace fs = std::filesystem;

Precision parse_precision(const std::string& name, const std::string& what) {
  if (name == "float64") return Precision::float64;
  if (name == "float32") return Precision::float32;
  throw_error("{}: '{}' is not a precision (expected float64 or float32)", what, name);
}

namespace {

/// Debian's HDF5 is built without thread safety, and it is one library state for every file: the series
/// of several bodies written by background threads take turns.
std::mutex& hdf5_mutex() {
  static std::mutex m;  // NOLINT: guards the HDF5 library's own process-wide state
  return m;
}

/// One dataset reference of the XML: its HDF5 path, shape and number type.
struct Item {
  std::string path;
  hsize_t rows = 0, columns = 1;
  bool integer = false;
};

struct Attribute {
  std::string name;
  bool cell = false;
  Item item;
};

struct Step {
  double time = 0.0;
  Item geometry;
  std::vector<Attribute> attributes;
};

/// The groups on `path` that `created` does not hold yet (the series made every group of its file, so a name it
/// remembers exists; looking it up in the file cost a tenth of a crowd frame's writing).
void create_groups(hid_t file, const std::string& path, std::set<std::string>& created) {
  for (std::size_t at = path.find('/', 1); at != std::string::npos; at = path.find('/', at + 1)) {
    std::string group = path.substr(0, at);
    if (created.count(group) > 0) continue;
    if (H5Lexists(file, group.c_str(), H5P_DEFAULT) <= 0) {
      Handle g{H5Gcreate2(file, group.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose};
      require(g.id >= 0, "xdmf: cannot create group {}", group);
    }
    created.insert(std::move(group));
  }
}

/// The string attribute `unit` of a dataset (h5py: `dataset.attrs["unit"]`).
void set_unit(hid_t dataset, const std::string& unit) {
  Handle type{H5Tcopy(H5T_C_S1), H5Tclose};
  H5Tset_size(type.id, unit.size() + 1);
  Handle space{H5Screate(H5S_SCALAR), H5Sclose};
  Handle attribute{H5Acreate2(dataset, "unit", type.id, space.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose};
  require(attribute.id >= 0 && H5Awrite(attribute.id, type.id, unit.c_str()) >= 0,
          "xdmf: cannot write the unit attribute");
}

std::string joined(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& item : items) out += (out.empty() ? "" : "; ") + item;
  return out;
}

std::string attribute_type(hsize_t columns) {
  return columns == 1 ? "Scalar" : columns == 3 ? "Vector" : columns == 9 ? "Tensor" : "Matrix";
}

}  // namespace

struct Series::Impl {
  fs::path xmf;
  fs::path h5;
  Precision precision;
  bool deflate = false;  ///< shuffle + deflate (zlib) filters, one chunk per dataset
  hid_t file = -1;
  Item topology;
  std::string topology_type;
  std::vector<Attribute> static_attributes;
  std::vector<Step> steps;
  std::optional<vtk::Points> last_points;
  std::set<std::string> groups;         ///< the groups created in the file
  std::vector<std::string> unit_names;  ///< the attributes' names, each once, in the order written
  std::vector<vtk::Labels> labels;      ///< names of label values (`part_names`, …)
  bool closed = false;
  bool failed = false;  ///< a write failed: the file was abandoned and is not finished by close()

  /// After a failed write HDF5 keeps dirty metadata it can never flush; closing then fails and leaves the file in
  /// HDF5's tables, where the library's exit handler crashes on it (HDF5 1.10). Point the file's descriptor at an
  /// anonymous in-memory file (memfd; /dev/null where there is none, which takes the writes but not the final
  /// truncate), so the close that follows succeeds; the run folder discards the partial file.
  void abandon() {
    failed = true;
    if (file < 0) return;
    void* handle = nullptr;
    if (H5Fget_vfd_handle(file, H5P_DEFAULT, &handle) >= 0 && handle != nullptr) {
      int sink = ::memfd_create("sflsh-abandoned-hdf5", MFD_CLOEXEC);
      if (sink < 0) sink = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
      if (sink >= 0) {
        ::dup2(sink, *static_cast<int*>(handle));
        ::close(sink);
      }
    }
    H5Fclose(file);
    file = -1;
  }

  Item write_dataset(const std::string& path, const double* values, hsize_t rows, hsize_t columns, bool integer,
                     const std::string& unit) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // per thread: the background writer's too
    create_groups(file, path, groups);
    const hsize_t dims[2] = {rows, columns};
    Handle space{H5Screate_simple(columns == 1 ? 1 : 2, dims, nullptr), H5Sclose};
    const bool single = precision == Precision::float32;
    const hid_t stored = integer ? H5T_STD_I32LE : single ? H5T_IEEE_F32LE : H5T_IEEE_F64LE;
    Handle create{H5Pcreate(H5P_DATASET_CREATE), H5Pclose};
    if (deflate && rows > 0) {
      // One chunk per dataset (a frame's array is written and read whole); the shuffle filter groups the bytes of
      // equal significance, which lets deflate find the zeros and the shared exponents of neighbouring values.
      require(H5Pset_chunk(create.id, columns == 1 ? 1 : 2, dims) >= 0 && H5Pset_shuffle(create.id) >= 0 &&
                  H5Pset_deflate(create.id, 1) >= 0,
              "{}: cannot set up compression for dataset {}", h5.string(), path);
    }
    // No chunk cache: a compressed chunk is written by H5Dwrite itself, so a full disk fails there (and is reported
    // and abandoned below) instead of in a later flush, after which HDF5 1.10 cannot close the file and crashes at
    // exit.
    Handle access{H5Pcreate(H5P_DATASET_ACCESS), H5Pclose};
    H5Pset_chunk_cache(access.id, H5D_CHUNK_CACHE_NSLOTS_DEFAULT, 0, H5D_CHUNK_CACHE_W0_DEFAULT);
    Handle set{H5Dcreate2(file, path.c_str(), stored, space.id, H5P_DEFAULT, create.id, access.id), H5Dclose};
    require(set.id >= 0, "{}: cannot create dataset {}", h5.string(), path);
    herr_t status = 0;
    errno = 0;  // HDF5's file driver leaves the failed write's errno (a full disk, a file size limit)
    if (integer) {
      std::vector<int> v(rows * columns);
      for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<int>(std::lround(values[i]));
      status = H5Dwrite(set.id, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    } else if (single) {
      std::vector<float> v(values, values + rows * columns);
      status = H5Dwrite(set.id, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    } else {
      status = H5Dwrite(set.id, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values);
    }
    if (status < 0) {
      const int write_errno = errno;
      abandon();
      if (write_errno != 0) throw_write_error(h5, fmt::format("cannot write dataset {}", path), write_errno);
      throw_error("{}: cannot write dataset {}", h5.string(), path);
    }
    set_unit(set.id, unit);
    return {path, rows, columns, integer};
  }

  /// Row-major copy of a field's values (Eigen matrices are column-major).
  Item write_field(const std::string& path, const vtk::Field& field) {
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rows = field.values;
    if (std::find(unit_names.begin(), unit_names.end(), field.name) == unit_names.end())
      unit_names.push_back(field.name);
    const std::string_view unit = units::of(field.name);
    return write_dataset(path, rows.data(), static_cast<hsize_t>(rows.rows()), static_cast<hsize_t>(rows.cols()),
                         field.integer, unit.empty() ? "?" : std::string(unit));
  }

  /// The units of the attributes and the label names, as Information of the domain (readers skip it).
  std::string information_xml() const {
    std::vector<std::string> entries;
    for (const std::string& name : unit_names) entries.push_back(units::entry(name));
    std::string s = fmt::format("    <Information Name=\"units\" Value=\"{}\"/>\n", joined(entries));
    for (const vtk::Labels& l : labels)
      s += fmt::format("    <Information Name=\"{}\" Value=\"{}\"/>\n", l.name, joined(l.values));
    return s;
  }

  std::string data_item(const Item& item) const {
    const std::string dims =
        item.columns == 1 ? fmt::format("{}", item.rows) : fmt::format("{} {}", item.rows, item.columns);
    const char* type = item.integer ? "Int" : "Float";
    const int bytes = item.integer ? 4 : precision == Precision::float32 ? 4 : 8;
    return fmt::format(R"(<DataItem Dimensions="{}" NumberType="{}" Precision="{}" Format="HDF">{}:{}</DataItem>)",
                       dims, type, bytes, h5.filename().string(), item.path);
  }

  std::string attribute_xml(const Attribute& a) const {
    return fmt::format(R"(        <Attribute Name="{}" AttributeType="{}" Center="{}">{}</Attribute>
)",
                       a.name, attribute_type(a.item.columns), a.cell ? "Cell" : "Node", data_item(a.item));
  }

  std::string xml() const {
    std::string s = R"(<?xml version="1.0"?>
<Xdmf Version="3.0" xmlns:xi="http://www.w3.org/2001/XInclude">
  <Domain>
)";
    s += information_xml();
    s += R"(    <Grid Name="series" GridType="Collection" CollectionType="Temporal">
)";
    for (std::size_t k = 0; k < steps.size(); ++k) {
      const Step& step = steps[k];
      s += fmt::format(R"(      <Grid Name="step_{:06d}" GridType="Uniform">
        <Time Value="{:.17g}"/>
        <Topology TopologyType="{}" NumberOfElements="{}">{}</Topology>
        <Geometry GeometryType="XYZ">{}</Geometry>
)",
                       k, step.time, topology_type, topology.rows, data_item(topology), data_item(step.geometry));
      for (const Attribute& a : static_attributes) s += attribute_xml(a);
      for (const Attribute& a : step.attributes) s += attribute_xml(a);
      s += "      </Grid>\n";
    }
    s += "    </Grid>\n  </Domain>\n</Xdmf>\n";
    return s;
  }
};

Series::Series(fs::path xmf_path, const Eigen::Ref<const vtk::Cells>& cells, Precision precision,
               vtk::Compression compression)
    : impl_(std::make_unique<Impl>()) {
  const std::lock_guard<std::mutex> lock(hdf5_mutex());
  Impl& m = *impl_;
  m.xmf = std::move(xmf_path);
  m.h5 = fs::path(m.xmf).replace_extension(".h5");
  m.precision = precision;
  require(compression != vtk::Compression::lz4,
          "{}: lz4 is not available for HDF5 datasets (expected zlib or none for an xdmf series)", m.xmf.string());
  m.deflate = compression == vtk::Compression::zlib;
  if (m.deflate)
    require(H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0 && H5Zfilter_avail(H5Z_FILTER_SHUFFLE) > 0,
            "{}: this HDF5 library has no deflate filter (use compression none)", m.xmf.string());
  require(cells.cols() == 3 || cells.cols() == 4, "xdmf: cells need 3 (triangles) or 4 (tetrahedra) nodes, got {}",
          cells.cols());
  m.topology_type = cells.cols() == 3 ? "Triangle" : "Tetrahedron";
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // failures are one sflsh error line, not HDF5's error stack
  errno = 0;
  m.file = H5Fcreate(m.h5.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (m.file < 0) throw_write_error(m.h5, "cannot create the HDF5 file", errno != 0 ? errno : EIO);
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> topology = cells.cast<double>();
  m.topology = m.write_dataset("/topology", topology.data(), static_cast<hsize_t>(cells.rows()),
                               static_cast<hsize_t>(cells.cols()), true, "index");
}

Series::~Series() {
  try {
    close();
  } catch (...) {  // a destructor must not throw; close() reports errors when called explicitly
  }
}

void Series::set_static(const vtk::Fields& fields) {
  const std::lock_guard<std::mutex> lock(hdf5_mutex());
  Impl& m = *impl_;
  require(m.steps.empty(), "{}: static fields must be set before the first step", m.xmf.string());
  for (const vtk::Field& f : fields.point_data)
    m.static_attributes.push_back({f.name, false, m.write_field("/static/point/" + f.name, f)});
  for (const vtk::Field& f : fields.cell_data)
    m.static_attributes.push_back({f.name, true, m.write_field("/static/cell/" + f.name, f)});
  m.labels.insert(m.labels.end(), fields.labels.begin(), fields.labels.end());
}

void Series::write(double time, const Eigen::Ref<const vtk::Points>& points, const vtk::Fields& fields) {
  const std::lock_guard<std::mutex> lock(hdf5_mutex());
  Impl& m = *impl_;
  require(!m.closed, "{}: series already closed", m.xmf.string());
  require(std::isfinite(time), "{}: step time is not finite", m.xmf.string());
  const std::string step = fmt::format("{:06d}", m.steps.size());
  Step s;
  s.time = time;
  if (m.last_points && m.last_points->rows() == points.rows() && *m.last_points == points) {
    s.geometry = m.steps.back().geometry;  // the nodes did not move: reuse the dataset
  } else {
    s.geometry =
        m.write_dataset("/geometry/" + step, points.data(), static_cast<hsize_t>(points.rows()), 3, false, "m");
    m.last_points = points;
  }
  for (const vtk::Field& f : fields.point_data)
    s.attributes.push_back({f.name, false, m.write_field("/point/" + f.name + "/" + step, f)});
  for (const vtk::Field& f : fields.cell_data)
    s.attributes.push_back({f.name, true, m.write_field("/cell/" + f.name + "/" + step, f)});
  for (const vtk::Labels& l : fields.labels)
    if (std::none_of(m.labels.begin(), m.labels.end(), [&](const vtk::Labels& known) { return known.name == l.name; }))
      m.labels.push_back(l);
  m.steps.push_back(std::move(s));
}

void Series::close() {
  const std::lock_guard<std::mutex> lock(hdf5_mutex());
  Impl& m = *impl_;
  if (m.closed) return;
  m.closed = true;
  if (m.failed) return;  // the write error was reported; nothing is finished
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  errno = 0;
  if (m.file >= 0 && H5Fflush(m.file, H5F_SCOPE_LOCAL) < 0) {
    const int flush_errno = errno;
    m.abandon();
    if (flush_errno != 0) throw_write_error(m.h5, "writing the HDF5 file failed", flush_errno);
    throw_error("{}: writing the HDF5 file failed", m.h5.string());
  }
  errno = 0;
  const herr_t status = m.file >= 0 ? H5Fclose(m.file) : 0;
  const int close_errno = errno;
  m.file = -1;
  if (status < 0) {
    if (close_errno != 0) throw_write_error(m.h5, "closing the HDF5 file failed", close_errno);
    throw_error("{}: closing the HDF5 file failed", m.h5.string());
  }
  write_text_atomically(m.xmf, m.xml());
}

std::size_t Series::steps() const { return impl_->steps.size(); }

std::uintmax_t Series::bytes() const {
  {
    const std::lock_guard<std::mutex> lock(hdf5_mutex());
    if (impl_->file >= 0) H5Fflush(impl_->file, H5F_SCOPE_LOCAL);
  }
  std::error_code ec;
  const auto n = fs::file_size(impl_->h5, ec);
  return ec ? 0 : n;
}

}  // namespace sflsh::xdmf
