// Reading DYNA registration files (docs/physics.md §3.2).
#include "hdf5_util.hpp"

#include <sflsh/body/motion.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/validate/dyna_file.hpp>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>

namespace sflsh::validate {

std::optional<double> Attributes::number(const std::string& name) const {
  const auto it = numbers.find(name);
  if (it == numbers.end() || it->second.empty()) return std::nullopt;
  return it->second.front();
}

const std::vector<std::string>& dyna_sequence_names() {
  static const std::vector<std::string> names = {"chicken_wings",
                                                 "hips",
                                                 "jiggle_on_toes",
                                                 "jumping_jacks",
                                                 "knees",
                                                 "light_hopping_loose",
                                                 "light_hopping_stiff",
                                                 "one_leg_jump",
                                                 "one_leg_loose",
                                                 "punching",
                                                 "running_on_spot",
                                                 "shake_arms",
                                                 "shake_hips",
                                                 "shake_shoulders"};
  return names;
}

namespace {

/// Length of the subject part of `key` (see subject_of), or npos when the key has no '_'.
std::size_t subject_length(const std::string& key) {
  if (key.find('_') == std::string::npos) return std::string::npos;
  // 1. Before the longest known sequence name the key ends with.
  std::size_t best = 0;
  auto consider = [&](const std::string& sequence) {
    if (key.size() > sequence.size() + 1 && sequence.size() > best && key.ends_with("_" + sequence))
      best = sequence.size();
  };
  for (const std::string& name : dyna_sequence_names()) consider(name);
  for (const std::string& name : body::procedural_motion_names()) consider(name);
  for (const std::string& name : body::showcase_motion_names()) consider(name);
  if (best > 0) return key.size() - best - 1;
  // 2. Through the first all-digit part, when something follows it ("OPEN_TRAIN_1_x", "50004_x").
  std::size_t start = 0;
  while (start < key.size()) {
    const std::size_t end = std::min(key.find('_', start), key.size());
    const bool digits = end > start && std::all_of(key.begin() + static_cast<std::ptrdiff_t>(start),
                                                   key.begin() + static_cast<std::ptrdiff_t>(end),
                                                   [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
    if (digits && end < key.size()) return end;
    start = end + 1;
  }
  // 3. At the first '_'.
  return key.find('_');
}

}  // namespace

std::string subject_of(const std::string& key) {
  const std::size_t n = subject_length(key);
  return n == std::string::npos ? key : key.substr(0, n);
}

std::string sequence_of(const std::string& key) {
  const std::size_t n = subject_length(key);
  return n == std::string::npos ? std::string() : key.substr(n + 1);
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

/// What the root entry `name` is: a dataset, a group, a named datatype, or a link that leads nowhere — said in
/// words, not as the HDF5 call that failed on it.
std::string kind_of_entry(const H5::H5File& file, const std::string& name) {
  const htri_t exists = H5Oexists_by_name(file.getId(), name.c_str(), H5P_DEFAULT);
  if (exists <= 0) return "a link that leads nowhere (a dangling soft or external link)";
  switch (file.childObjType(name)) {
    case H5O_TYPE_DATASET:
      return "a dataset";
    case H5O_TYPE_GROUP:
      return "a group";
    case H5O_TYPE_NAMED_DATATYPE:
      return "a named datatype";
    default:
      return "an object of unknown kind";
  }
}

/// The dataset names at the file's root, sorted (groups and other objects are ignored; a dangling link is refused).
std::vector<std::string> root_datasets(const H5::H5File& file, const std::string& where) {
  std::vector<std::string> names;
  const hsize_t count = file.getNumObjs();
  for (hsize_t i = 0; i < count; ++i) {
    const std::string name = file.getObjnameByIdx(i);
    if (H5Oexists_by_name(file.getId(), name.c_str(), H5P_DEFAULT) <= 0)
      throw_error("{}: {}: is {}, expected a dataset", where, name, kind_of_entry(file, name));
    if (file.childObjType(name) == H5O_TYPE_DATASET) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

RowMatrixX3i read_faces(const H5::H5File& file, const std::string& where) {
  if (!file.nameExists("faces")) throw_error("{}: faces: no such dataset, expected F×3 integer face indices", where);
  if (const std::string kind = kind_of_entry(file, "faces"); kind != "a dataset")
    throw_error("{}: faces: is {}, expected a dataset of F×3 integer face indices", where, kind);
  const H5::DataSet dataset = file.openDataSet("faces");
  const std::vector<hsize_t> dims = dimensions(dataset);
  require(dims.size() == 2 && dims[1] == 3 && dims[0] > 0, "{}: faces: shape {}, expected (F, 3) with F ≥ 1", where,
          shape_string(dims));
  require(dims[0] <= kMaxDynaFaces, "{}: faces: {} faces, above the limit of {}", where, dims[0], kMaxDynaFaces);
  require(dataset.getTypeClass() == H5T_INTEGER, "{}: faces: not integer-valued, expected F×3 integer face indices",
          where);
  std::vector<long long> values(static_cast<std::size_t>(dims[0] * 3));
  dataset.read(values.data(), H5::PredType::NATIVE_LLONG);
  RowMatrixX3i faces(static_cast<Eigen::Index>(dims[0]), 3);
  for (std::size_t i = 0; i < values.size(); ++i) {
    require(values[i] >= 0 && values[i] < static_cast<long long>(kMaxDynaVertices),
            "{}: faces: index {} at face {}, expected a vertex index in 0..{}", where, values[i], i / 3,
            kMaxDynaVertices - 1);
    faces.data()[i] = static_cast<int>(values[i]);
  }
  return faces;
}

/// Reads frames [0, frames) of a (V, 3, T) dataset into `out` (frames × V×3), a block of frames at a time
/// so that the temporary stays small whatever T is.
void read_frames(const H5::DataSet& dataset, std::size_t vertices, std::size_t frames, std::vector<RowMatrixX3d>& out) {
  constexpr std::size_t kBlockBytes = std::size_t{64} << 20;
  const std::size_t block = std::clamp<std::size_t>(kBlockBytes / (24 * vertices), 1, frames);
  std::vector<double> buffer(vertices * 3 * block);
  out.assign(frames, RowMatrixX3d(static_cast<Eigen::Index>(vertices), 3));
  for (std::size_t t0 = 0; t0 < frames; t0 += block) {
    const std::size_t nb = std::min(block, frames - t0);
    const hsize_t start[3] = {0, 0, t0}, count[3] = {vertices, 3, nb};
    H5::DataSpace selection = dataset.getSpace();
    selection.selectHyperslab(H5S_SELECT_SET, count, start);
    const H5::DataSpace memory(3, count);
    dataset.read(buffer.data(), H5::PredType::NATIVE_DOUBLE, memory, selection);  // float32 converted by HDF5
    // (V, 3, nb) in C order: element [v][c][t] at (3v + c)·nb + t.
    for (std::size_t v = 0; v < vertices; ++v)
      for (std::size_t c = 0; c < 3; ++c) {
        const double* row = buffer.data() + (3 * v + c) * nb;
        for (std::size_t t = 0; t < nb; ++t)
          out[t0 + t](static_cast<Eigen::Index>(v), static_cast<Eigen::Index>(c)) = row[t];
      }
  }
}

/// Every value finite, within ±kMaxDynaMetres, and no frame collapsed below kMinDynaSpan.
void check_frames(const std::vector<RowMatrixX3d>& frames, const std::string& where, const std::string& key) {
  for (std::size_t t = 0; t < frames.size(); ++t) {
    if (!frames[t].allFinite()) {
      Eigen::Index bad = 0;
      while (bad < frames[t].rows() && frames[t].row(bad).allFinite()) ++bad;
      throw_error("{}: {}: non-finite value in frame {} (vertex {}), expected finite positions [m]", where, key, t,
                  bad);
    }
  }
  for (std::size_t t = 0; t < frames.size(); ++t) {
    Eigen::Index row = 0, col = 0;
    const double largest = frames[t].cwiseAbs().maxCoeff(&row, &col);
    require(largest <= kMaxDynaMetres,
            "{}: {}: coordinate {:g} m in frame {} (vertex {}) is beyond ±{:g} m, expected positions in metres", where,
            key, frames[t](row, col), t, row, kMaxDynaMetres);
  }
  for (std::size_t t = 0; t < frames.size(); ++t) {
    const double span = (frames[t].colwise().maxCoeff() - frames[t].colwise().minCoeff()).maxCoeff();
    require(span >= kMinDynaSpan,
            "{}: {}: frame {} is degenerate: its vertices span {:g} m, expected a body at least {:g} m across", where,
            key, t, span, kMinDynaSpan);
  }
}

}  // namespace

DynaFile::DynaFile(const std::filesystem::path& path) : path_(path) {
  const std::string where = path.string();
  require(std::filesystem::is_regular_file(path), "{}: no such file (expected a DYNA registration file, HDF5)", where);
  detail::quiet_hdf5();
  try {
    require(H5::H5File::isHdf5(where) > 0,
            "{}: not an HDF5 file (expected a DYNA registration file such as dyna_female.h5)", where);
    const H5::H5File file(where, H5F_ACC_RDONLY);
    faces_ = read_faces(file, where);
    attributes_ = detail::read_attributes(file, where);
    for (const std::string& name : root_datasets(file, where)) {
      if (name == "faces") continue;
      // A sequence key is '<subject>_<sequence>'; a dataset whose name cannot be one is not a sequence written
      // badly but something else kept beside them (a note, a template): read past it, and say so.
      const std::size_t underscore = name.find('_');
      if (underscore == std::string::npos || underscore == 0 || underscore + 1 == name.size()) {
        notes_.push_back(fmt::format("{}: {}: not a <subject>_<sequence> key, read past", where, name));
        logger()->info("{}", notes_.back());
        continue;
      }
      const H5::DataSet dataset = file.openDataSet(name);
      const std::vector<hsize_t> dims = dimensions(dataset);
      require(dims.size() == 3 && dims[1] == 3 && dims[0] > 0 && dims[2] > 0,
              "{}: {}: shape {}, expected (V, 3, T) with V, T ≥ 1", where, name, shape_string(dims));
      require(dims[0] <= kMaxDynaVertices, "{}: {}: {} vertices, above the limit of {}", where, name, dims[0],
              kMaxDynaVertices);
      require(dims[2] <= kMaxDynaFrames, "{}: {}: {} frames, above the limit of {}", where, name, dims[2],
              kMaxDynaFrames);
      require(dataset.getTypeClass() == H5T_FLOAT, "{}: {}: not floating-point, expected float32 or float64 positions",
              where, name);
      DynaSequenceInfo info;
      info.key = name;
      info.vertices = static_cast<int>(dims[0]);
      info.frames = static_cast<int>(dims[2]);
      info.dtype = dataset.getFloatType().getSize() == 4 ? "float32" : "float64";
      if (vertices_ == 0) vertices_ = info.vertices;
      require(info.vertices == vertices_, "{}: {}: {} vertices, but '{}' has {}, expected one vertex count", where,
              name, info.vertices, infos_.front().key, vertices_);
      keys_.push_back(name);
      infos_.push_back(std::move(info));
    }
  } catch (const H5::Exception& e) {
    throw_error("{}: cannot read the HDF5 file: {}", where, detail::describe(e));
  }
  if (vertices_ > 0) {
    const int max_index = faces_.maxCoeff();
    require(max_index < vertices_, "{}: faces: refers to vertex {}, but the sequences have {} vertices", where,
            max_index, vertices_);
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
    if (keys_.empty())
      throw_error("{}: {}: no such sequence in the file, which holds no sequence dataset (only 'faces')",
                  path_.string(), key);
    throw_error("{}: {}: no such sequence in the file, expected one of {}", path_.string(), key,
                fmt::join(keys_, ", "));
  }
  return infos_[static_cast<std::size_t>(it - keys_.begin())];
}

DynaSequence DynaFile::read(const std::string& key, int max_frames) const {
  const DynaSequenceInfo& meta = info(key);
  const std::string where = path_.string();
  DynaSequence sequence;
  sequence.key = key;
  const auto V = static_cast<std::size_t>(meta.vertices);
  const auto T = max_frames > 0 ? std::min(static_cast<std::size_t>(max_frames), static_cast<std::size_t>(meta.frames))
                                : static_cast<std::size_t>(meta.frames);
  // V ≤ 1e6 and T < 2^31, so the product fits; bound it before allocating anything.
  const double bytes = 24.0 * static_cast<double>(V) * static_cast<double>(T);
  require(
      bytes <= static_cast<double>(kMaxDynaReadBytes),
      "{}: {}: {} frames of {} vertices need {:.3g} GB, above the read limit of {:.3g} GB (2 GiB); read fewer frames",
      where, key, T, V, 1e-9 * bytes, 1e-9 * static_cast<double>(kMaxDynaReadBytes));
  detail::quiet_hdf5();
  try {
    const H5::H5File file(where, H5F_ACC_RDONLY);
    const H5::DataSet dataset = file.openDataSet(key);
    sequence.attributes = detail::read_attributes(dataset, where + ": " + key);
    const std::optional<double> fps =
        sequence.attributes.number("fps") ? sequence.attributes.number("fps") : attributes_.number("fps");
    sequence.fps = fps.value_or(kDynaFps);
    require(std::isfinite(sequence.fps) && sequence.fps >= kMinDynaFps && sequence.fps <= kMaxDynaFps,
            "{}: {}: attribute fps = {:g} Hz is outside [{:g}, {:g}] Hz", where, key, sequence.fps, kMinDynaFps,
            kMaxDynaFps);
    read_frames(dataset, V, T, sequence.frames);
  } catch (const H5::Exception& e) {
    throw_error("{}: {}: cannot read the dataset: {}", where, key, detail::describe(e));
  }
  check_frames(sequence.frames, where, key);
  return sequence;
}

void DynaFile::require_vertices(const body::BodyModel& model) const {
  require(vertices_ > 0,
          "{}: the file holds no sequence dataset (only 'faces'), expected <subject>_<sequence> datasets of shape (V, "
          "3, T)",
          path_.string());
  require(vertices_ == static_cast<int>(model.num_vertices()),
          "{}: the registrations have {} vertices, but the body model '{}' has {} (DYNA registrations need the body's "
          "topology, "
          "e.g. SMPL's 6890 vertices; pass the matching model with --body)",
          path_.string(), vertices_, model.name, model.num_vertices());
}

}  // namespace sflsh::validate
