// Reading DYNA registration files (docs/physics.md §3.2).
#include <sflsh/validate/dyna_file.hpp>

#include "hdf5_util.hpp"

#include <sflsh/core/error.hpp>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <set>

namespace sflsh::validate {

std::optional<double> Attributes::number(const std::string& name) const {
  const auto it = numbers.find(name);
  if (it == numbers.end() || it->second.empty()) return std::nullopt;
  return it->second.front();
}

std::string subject_of(const std::string& key) {
  const auto underscore = key.find('_');
  return underscore == std::string::npos ? key : key.substr(0, underscore);
}

std::string sequence_of(const std::string& key) {
  const auto underscore = key.find('_');
  return underscore == std::string::npos ? std::string() : key.substr(underscore + 1);
}

namespace {

std::string shape_string(const std::vector<hsize_t>& dims) {
  std::string s = "(";
  for (std::size_t i = 0; i < dims.size(); ++i) s += (i ? ", " : "") + std::to_string(dims[i]);
  return s + (dims.size() == 1 ? ",)" : ")");
}

std::vector<hsize_t> dimensions(const H5::DataSet& dataset) {
  const H5::DataSpace space = dataset.getSpace();
  std::vector<hsize_t> dims(static_cast<std::size_t>(std::max(space.getSimpleExtentNdims(), 0)));
  if (!dims.empty()) space.getSimpleExtentDims(dims.data());
  return dims;
}

/// The dataset names at the file's root, sorted (groups and other objects are ignored).
std::vector<std::string> root_datasets(const H5::H5File& file) {
  std::vector<std::string> names;
  const hsize_t count = file.getNumObjs();
  for (hsize_t i = 0; i < count; ++i) {
    const std::string name = file.getObjnameByIdx(i);
    if (file.childObjType(name) == H5O_TYPE_DATASET) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

RowMatrixX3i read_faces(const H5::H5File& file, const std::string& where) {
  if (!file.nameExists("faces")) throw_error("{}: no 'faces' dataset (expected F×3 integer face indices)", where);
  const H5::DataSet dataset = file.openDataSet("faces");
  const std::vector<hsize_t> dims = dimensions(dataset);
  require(dims.size() == 2 && dims[1] == 3 && dims[0] > 0, "{}: dataset 'faces' has shape {}, expected (F, 3) with F ≥ 1", where,
          shape_string(dims));
  require(dataset.getTypeClass() == H5T_INTEGER, "{}: dataset 'faces' is not integer-valued, expected F×3 integer face indices", where);
  std::vector<long long> values(static_cast<std::size_t>(dims[0] * 3));
  dataset.read(values.data(), H5::PredType::NATIVE_LLONG);
  RowMatrixX3i faces(static_cast<Eigen::Index>(dims[0]), 3);
  for (std::size_t i = 0; i < values.size(); ++i) {
    require(values[i] >= 0 && values[i] < (1LL << 31), "{}: dataset 'faces' has index {} at face {}, expected a vertex index ≥ 0",
            where, values[i], i / 3);
    faces.data()[i] = static_cast<int>(values[i]);
  }
  return faces;
}

}  // namespace

DynaFile::DynaFile(const std::filesystem::path& path) : path_(path) {
  const std::string where = path.string();
  require(std::filesystem::is_regular_file(path), "{}: no such file (expected a DYNA registration file, HDF5)", where);
  detail::quiet_hdf5();
  try {
    require(H5::H5File::isHdf5(where) > 0, "{}: not an HDF5 file (expected a DYNA registration file such as dyna_female.h5)", where);
    const H5::H5File file(where, H5F_ACC_RDONLY);
    faces_ = read_faces(file, where);
    attributes_ = detail::read_attributes(file);
    for (const std::string& name : root_datasets(file)) {
      if (name == "faces") continue;
      const H5::DataSet dataset = file.openDataSet(name);
      const std::vector<hsize_t> dims = dimensions(dataset);
      require(dims.size() == 3 && dims[1] == 3 && dims[0] > 0 && dims[2] > 0,
              "{}: dataset '{}' has shape {}, expected (V, 3, T) with V, T ≥ 1", where, name, shape_string(dims));
      require(dataset.getTypeClass() == H5T_FLOAT, "{}: dataset '{}' is not floating-point, expected float32 or float64 positions",
              where, name);
      DynaSequenceInfo info;
      info.key = name;
      info.vertices = static_cast<int>(dims[0]);
      info.frames = static_cast<int>(dims[2]);
      info.dtype = dataset.getFloatType().getSize() == 4 ? "float32" : "float64";
      if (vertices_ == 0) vertices_ = info.vertices;
      require(info.vertices == vertices_, "{}: dataset '{}' has {} vertices, but '{}' has {}", where, name, info.vertices,
              infos_.front().key, vertices_);
      keys_.push_back(name);
      infos_.push_back(std::move(info));
    }
  } catch (const H5::Exception& e) {
    throw_error("{}: cannot read the HDF5 file: {}", where, detail::describe(e));
  }
  if (vertices_ > 0) {
    const int max_index = faces_.maxCoeff();
    require(max_index < vertices_, "{}: dataset 'faces' refers to vertex {}, but the sequences have {} vertices", where, max_index,
            vertices_);
  }
}

DynaFile::~DynaFile() = default;
DynaFile::DynaFile(DynaFile&&) noexcept = default;
DynaFile& DynaFile::operator=(DynaFile&&) noexcept = default;

bool DynaFile::has(const std::string& key) const { return std::binary_search(keys_.begin(), keys_.end(), key); }

std::vector<std::string> DynaFile::subjects() const {
  std::set<std::string> subjects;
  for (const std::string& key : keys_) subjects.insert(subject_of(key));
  return {subjects.begin(), subjects.end()};
}

std::vector<std::string> DynaFile::sequences(const std::string& subject) const {
  std::vector<std::string> out;
  for (const std::string& key : keys_)
    if (subject_of(key) == subject) out.push_back(sequence_of(key));
  return out;
}

const DynaSequenceInfo& DynaFile::info(const std::string& key) const {
  const auto it = std::lower_bound(keys_.begin(), keys_.end(), key);
  if (it == keys_.end() || *it != key) {
    if (keys_.empty()) throw_error("{}: no sequence '{}': the file holds no sequence dataset", path_.string(), key);
    throw_error("{}: no sequence '{}'; available: {}", path_.string(), key, fmt::join(keys_, ", "));
  }
  return infos_[static_cast<std::size_t>(it - keys_.begin())];
}

DynaSequence DynaFile::read(const std::string& key) const {
  const DynaSequenceInfo& meta = info(key);
  const std::string where = path_.string();
  DynaSequence sequence;
  sequence.key = key;
  const auto V = static_cast<std::size_t>(meta.vertices), T = static_cast<std::size_t>(meta.frames);
  std::vector<double> values(V * 3 * T);
  detail::quiet_hdf5();
  try {
    const H5::H5File file(where, H5F_ACC_RDONLY);
    const H5::DataSet dataset = file.openDataSet(key);
    dataset.read(values.data(), H5::PredType::NATIVE_DOUBLE);  // float32 is converted by HDF5
    sequence.attributes = detail::read_attributes(dataset);
  } catch (const H5::Exception& e) {
    throw_error("{}: cannot read dataset '{}': {}", where, key, detail::describe(e));
  }
  const std::optional<double> fps = sequence.attributes.number("fps") ? sequence.attributes.number("fps") : attributes_.number("fps");
  sequence.fps = fps.value_or(kDynaFps);
  require(std::isfinite(sequence.fps) && sequence.fps > 0.0, "{}: dataset '{}': attribute fps = {}, expected a positive number",
          where, key, sequence.fps);
  // (V, 3, T) in C order: element [v][c][t] at (3v + c)·T + t.
  sequence.frames.assign(T, RowMatrixX3d(meta.vertices, 3));
  for (std::size_t v = 0; v < V; ++v)
    for (std::size_t c = 0; c < 3; ++c) {
      const double* row = values.data() + (3 * v + c) * T;
      for (std::size_t t = 0; t < T; ++t) sequence.frames[t](static_cast<Eigen::Index>(v), static_cast<Eigen::Index>(c)) = row[t];
    }
  for (std::size_t t = 0; t < T; ++t) {
    if (!sequence.frames[t].allFinite()) {
      Eigen::Index bad = 0;
      for (; bad < sequence.frames[t].rows() && sequence.frames[t].row(bad).allFinite(); ++bad) {
      }
      throw_error("{}: dataset '{}' has a non-finite value in frame {} (vertex {})", where, key, t, bad);
    }
  }
  return sequence;
}

void DynaFile::require_vertices(const body::BodyModel& model) const {
  require(vertices_ == static_cast<int>(model.num_vertices()),
          "{}: the registrations have {} vertices, but the body model '{}' has {} (DYNA registrations need the body's topology, "
          "e.g. SMPL's 6890 vertices; pass the matching model with --body)",
          path_.string(), vertices_, model.name, model.num_vertices());
}

}  // namespace sflsh::validate
