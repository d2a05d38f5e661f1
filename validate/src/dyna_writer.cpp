// Writing DYNA registration files in the layout of docs/physics.md §3.2 (used for synthetic ground truth).
#include "hdf5_util.hpp"

#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/validate/dyna_file.hpp>

#include <cmath>

namespace sflsh::validate {

struct DynaWriter::Impl {
  H5::H5File file;
};

DynaWriter::DynaWriter(std::filesystem::path path, const RowMatrixX3i& faces, const Attributes& file_attributes)
    : path_(std::move(path)) {
  const std::string where = path_.string();
  require(faces.rows() > 0, "{}: a DYNA file needs at least one face", where);
  require(faces.minCoeff() >= 0, "{}: face indices must be non-negative", where);
  faces_max_ = faces.maxCoeff();
  if (path_.has_parent_path()) ensure_directory(path_.parent_path());
  tmp_ = temporary_sibling(path_);
  detail::quiet_hdf5();
  try {
    impl_ = std::make_unique<Impl>(Impl{H5::H5File(tmp_.string(), H5F_ACC_TRUNC)});
    const hsize_t dims[2] = {static_cast<hsize_t>(faces.rows()), 3};
    H5::DataSet dataset = impl_->file.createDataSet("faces", H5::PredType::STD_I32LE, H5::DataSpace(2, dims));
    const RowMatrixX3i row_major = faces;  // C order, as HDF5 expects
    dataset.write(row_major.data(), H5::PredType::NATIVE_INT);
    detail::write_attributes(impl_->file, file_attributes);
  } catch (const H5::Exception& e) {
    impl_.reset();
    std::filesystem::remove(tmp_);
    throw_error("{}: cannot write the HDF5 file: {}", where, detail::describe(e));
  }
}

DynaWriter::~DynaWriter() {
  if (committed_) return;
  try {
    impl_.reset();
  } catch (...) {
  }
  std::error_code ignored;
  std::filesystem::remove(tmp_, ignored);
}

void DynaWriter::add(const DynaSequence& sequence) {
  const std::string where = path_.string();
  require(!committed_, "{}: sequence '{}' added after commit", where, sequence.key);
  require(!sequence.key.empty() && sequence.key != "faces" && sequence.key.find('/') == std::string::npos,
          "{}: '{}' is not a valid sequence key (expected <subject>_<sequence>)", where, sequence.key);
  require(!sequence.frames.empty(), "{}: sequence '{}' has no frames", where, sequence.key);
  const auto V = sequence.frames.front().rows();
  if (vertices_ == 0) vertices_ = static_cast<int>(V);
  require(V == vertices_, "{}: sequence '{}' has {} vertices, earlier sequences have {}", where, sequence.key, V,
          vertices_);
  require(faces_max_ < V, "{}: the faces refer to vertex {}, but sequence '{}' has {} vertices", where, faces_max_,
          sequence.key, V);
  const auto T = sequence.frames.size();
  std::vector<double> values(static_cast<std::size_t>(V) * 3 * T);
  for (std::size_t t = 0; t < T; ++t) {
    const RowMatrixX3d& frame = sequence.frames[t];
    require(frame.rows() == V, "{}: sequence '{}' frame {} has {} vertices, frame 0 has {}", where, sequence.key, t,
            frame.rows(), V);
    require(frame.allFinite(), "{}: sequence '{}' frame {} has a non-finite value", where, sequence.key, t);
    for (Eigen::Index v = 0; v < V; ++v)
      for (int c = 0; c < 3; ++c)
        values[(3 * static_cast<std::size_t>(v) + static_cast<std::size_t>(c)) * T + t] = frame(v, c);
  }
  Attributes attributes = sequence.attributes;
  require(std::isfinite(sequence.fps) && sequence.fps > 0.0, "{}: sequence '{}' has fps {}, expected a positive number",
          where, sequence.key, sequence.fps);
  if (!attributes.numbers.count("fps") && sequence.fps != kDynaFps) attributes.numbers["fps"] = {sequence.fps};
  detail::quiet_hdf5();
  try {
    const hsize_t dims[3] = {static_cast<hsize_t>(V), 3, static_cast<hsize_t>(T)};
    H5::DataSet dataset = impl_->file.createDataSet(sequence.key, H5::PredType::IEEE_F64LE, H5::DataSpace(3, dims));
    dataset.write(values.data(), H5::PredType::NATIVE_DOUBLE);
    detail::write_attributes(dataset, attributes);
  } catch (const H5::Exception& e) {
    throw_error("{}: cannot write dataset '{}': {}", where, sequence.key, detail::describe(e));
  }
}

void DynaWriter::commit() {
  const std::string where = path_.string();
  require(!committed_, "{}: committed twice", where);
  detail::quiet_hdf5();
  try {
    impl_->file.close();
  } catch (const H5::Exception& e) {
    throw_error("{}: cannot close the HDF5 file: {}", where, detail::describe(e));
  }
  impl_.reset();
  std::error_code error;
  std::filesystem::rename(tmp_, path_, error);
  if (error) {
    std::filesystem::remove(tmp_, error);
    throw_error("{}: cannot move the finished file into place: {}", where, error.message());
  }
  committed_ = true;
}

void write_dyna_file(const std::filesystem::path& path, const RowMatrixX3i& faces,
                     const std::vector<DynaSequence>& sequences, const Attributes& file_attributes) {
  DynaWriter writer(path, faces, file_attributes);
  for (const DynaSequence& sequence : sequences) writer.add(sequence);
  writer.commit();
}

}  // namespace sflsh::validate
