#pragma once
// DYNA registrations in HDF5 (docs/physics.md §3.2): `dyna_female.h5` / `dyna_male.h5` hold a `faces`
// dataset (F×3 integer) and one dataset per "<subject>_<sequence>" of shape (V, 3, T), float32 or
// float64, metres. Element [v][c][t] is coordinate c of vertex v in frame t; we hand out T frames of V×3.
// Optional attributes (ours, written by DynaWriter): "fps" on the file or a dataset (DYNA is 60 fps
// when absent), and any string / number / number-array attribute such as a subject's "beta".
//
// Every problem is one sflsh::Error line "<file>: <dataset>: found, expected": not an HDF5 file, missing
// `faces`, wrong rank or shape (found and expected), face indices out of range, an unknown key (with the
// available ones), sizes beyond the bounds below, non-finite values (dataset and frame), coordinates
// beyond ±10 km, a frame collapsed to less than 1 cm, a vertex count that is not the body's.
// HDF5's own error stack printing is switched off.
#include <sflsh/body/body_model.hpp>

#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace sflsh::validate {

using body::RowMatrixX3d;
using body::RowMatrixX3i;

/// The frame rate of DYNA captures when a file carries no "fps" attribute.
inline constexpr double kDynaFps = 60.0;

/// Bounds on a DYNA file. Opening checks the counts from the dataset shapes; reading checks the bytes it
/// is about to allocate (V × 3 × frames read × 8 B) and then every value.
inline constexpr std::size_t kMaxDynaVertices = 1000000;                ///< vertices per registration
inline constexpr std::size_t kMaxDynaFaces = 4000000;                   ///< rows of `faces`
inline constexpr std::size_t kMaxDynaFrames = 2147483647;               ///< frames of one dataset (fits `int`)
inline constexpr std::size_t kMaxDynaReadBytes = std::size_t{1} << 31;  ///< positions read at once: 2 GiB
inline constexpr double kMaxDynaMetres = 1e4;                           ///< |coordinate| of a registered vertex [m]
inline constexpr double kMinDynaSpan = 0.01;                            ///< smallest extent of one frame's vertices [m]
inline constexpr double kMinDynaFps = 1.0;                              ///< "fps" attribute bounds [Hz]
inline constexpr double kMaxDynaFps = 10000.0;

/// DYNA sequence names (docs/physics.md §3.2), used to split keys whose subject contains '_'.
const std::vector<std::string>& dyna_sequence_names();

/// Attributes of the file or of one dataset. A number attribute keeps all its values (a scalar is one).
struct Attributes {
  std::map<std::string, std::vector<double>> numbers;
  std::map<std::string, std::string> strings;

  /// The scalar number attribute `name` (the first value of an array), if present.
  std::optional<double> number(const std::string& name) const;
  bool empty() const { return numbers.empty() && strings.empty(); }
};

/// "50004_jiggle_on_toes" → "50004", "OPEN_TRAIN_1_jiggle_on_toes" → "OPEN_TRAIN_1". Subject names may
/// contain '_', so the key is split before the longest known sequence name it ends with (DYNA's and the
/// procedural motions'); failing that, after the first all-digit part ("S_7_walk" → "S_7"); failing that,
/// at the first '_' (the whole key when there is none).
std::string subject_of(const std::string& key);
/// The rest of the key after subject_of(key) and its '_' (empty when there is none).
std::string sequence_of(const std::string& key);

/// One sequence as read from (or to be written to) a DYNA file.
struct DynaSequence {
  std::string key;                   ///< "<subject>_<sequence>"
  std::vector<RowMatrixX3d> frames;  ///< T frames of V×3 vertex positions [m]
  Attributes attributes;             ///< the dataset's attributes
  double fps = kDynaFps;             ///< dataset "fps", else file "fps", else 60

  int num_frames() const { return static_cast<int>(frames.size()); }
  int num_vertices() const { return frames.empty() ? 0 : static_cast<int>(frames.front().rows()); }
};

/// Shape of one sequence dataset, known without reading its values.
struct DynaSequenceInfo {
  std::string key;
  int vertices = 0;
  int frames = 0;
  std::string dtype;  ///< "float32" or "float64"
};

/// A DYNA file opened for reading. Opening checks the layout (faces, every dataset's rank and shape,
/// one vertex count, face indices in range); values are checked for finiteness when read.
class DynaFile {
 public:
  explicit DynaFile(const std::filesystem::path& path);
  ~DynaFile();
  DynaFile(DynaFile&&) noexcept;
  DynaFile& operator=(DynaFile&&) noexcept;

  const std::filesystem::path& path() const { return path_; }
  /// Sequence dataset names (`<subject>_<sequence>`: every root dataset but `faces` whose name has an underscore),
  /// sorted.
  const std::vector<std::string>& keys() const { return keys_; }
  /// What was read past (root datasets that cannot be `<subject>_<sequence>` keys, e.g. 'readme'), one line each;
  /// also logged when the file is opened.
  const std::vector<std::string>& notes() const { return notes_; }
  bool has(const std::string& key) const;
  /// Distinct subjects (sorted) and the sequences of one subject (sorted).
  std::vector<std::string> subjects() const;
  std::vector<std::string> sequences(const std::string& subject) const;
  /// F×3 face indices (0-based, < num_vertices()).
  const RowMatrixX3i& faces() const { return faces_; }
  /// Vertices per frame shared by every sequence (0 when the file has no sequence).
  int num_vertices() const { return vertices_; }
  const DynaSequenceInfo& info(const std::string& key) const;
  const Attributes& attributes() const { return attributes_; }

  /// Reads one sequence, only its first `max_frames` frames when max_frames > 0 (a hyperslab: the rest
  /// is neither read nor allocated). An unknown key lists the available ones; more than
  /// kMaxDynaReadBytes to read, a NaN/Inf, a coordinate beyond ±kMaxDynaMetres or a frame whose vertices
  /// span less than kMinDynaSpan (all zeros, collapsed) is refused naming the dataset and the frame.
  DynaSequence read(const std::string& key, int max_frames = 0) const;
  /// Throws unless the file's vertex count is the body model's (and when the file holds no sequence).
  void require_vertices(const body::BodyModel& model) const;

 private:
  std::filesystem::path path_;
  std::vector<std::string> keys_;
  std::vector<DynaSequenceInfo> infos_;
  std::vector<std::string> notes_;
  RowMatrixX3i faces_;
  int vertices_ = 0;
  Attributes attributes_;
};

/// Writes a DYNA file in the same layout (faces as int32, sequences as float64 (V, 3, T)), atomically:
/// everything goes to a temporary sibling that commit() renames onto the target; a writer destroyed
/// before commit() removes the temporary and leaves the target untouched.
class DynaWriter {
 public:
  DynaWriter(std::filesystem::path path, const RowMatrixX3i& faces, const Attributes& file_attributes = {});
  ~DynaWriter();
  DynaWriter(const DynaWriter&) = delete;
  DynaWriter& operator=(const DynaWriter&) = delete;

  /// Adds dataset `key` (frames T ≥ 1 of V×3, finite, V the same for every sequence and > every face
  /// index) with its attributes. A sequence's fps is stored as its "fps" attribute unless it is 60
  /// and the attributes do not already carry one.
  void add(const DynaSequence& sequence);
  /// Closes the file and moves it onto the target path.
  void commit();

 private:
  struct Impl;
  std::filesystem::path path_;
  std::filesystem::path tmp_;
  std::unique_ptr<Impl> impl_;
  int faces_max_ = -1;
  int vertices_ = 0;
  bool committed_ = false;
};

/// One-call writer: faces, sequences, file attributes (atomic).
void write_dyna_file(const std::filesystem::path& path, const RowMatrixX3i& faces,
                     const std::vector<DynaSequence>& sequences, const Attributes& file_attributes = {});

}  // namespace sflsh::validate
