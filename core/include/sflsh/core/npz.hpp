#pragma once
// NumPy .npy arrays and .npz archives (zip of .npy members, stored or deflated), as written by
// numpy.save / savez / savez_compressed. Used for body models (SMPL layout) and AMASS motions.
//
// Hand-written on purpose: Debian ships no npz reader for C++ (xtensor's xnpy reads single .npy
// files into xtensor types only); the .npy header is a short Python-dict literal, and the zip part
// is delegated to libzip.
//
// Input limits (docs/physics.md §3.5): a member holds at most kMaxMemberBytes once
// inflated, its CRC-32 must match the archive's, a header's shape × itemsize must fit the bytes that
// follow it (computed without overflow), and only the dtypes real SMPL/AMASS files use are accepted:
// float16/32/64, int8–64, uint8–64, bool, and fixed-width strings ('U', 'S'). Every refusal is one
// line "<file>: <key>: what was found, what was expected".
#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace sflsh::npz {

/// Largest member (inflated .npy bytes) a Reader accepts: 1 GiB. SMPL-X's posedirs, the largest
/// array of the body files we know, is 122 MB.
inline constexpr std::uint64_t kMaxMemberBytes = std::uint64_t{1} << 30;
/// Largest number of dimensions of an array (NumPy's own limit).
inline constexpr std::size_t kMaxDimensions = 32;
/// Longest fixed-width string dtype ('<U…' characters or '|S…' bytes).
inline constexpr std::size_t kMaxStringLength = 1 << 20;

/// One array: element kind as NumPy's dtype kind character ('f' float, 'i' signed, 'u' unsigned,
/// 'b' bool, 'U' unicode, 'S' bytes), item size in bytes, shape, and raw little-endian bytes in
/// C (row-major) order (Fortran-ordered files are transposed to C order on read).
struct Array {
  char kind = 'f';
  std::size_t itemsize = 8;
  std::vector<std::size_t> shape;
  std::vector<std::uint8_t> bytes;
  /// Where the array came from, "<file>: <key>" (set by Reader::read and parse_npy); the conversions
  /// below name it in their errors ("array" when empty).
  std::string origin;

  std::size_t size() const;          ///< number of elements
  std::string dtype() const;         ///< e.g. "<f8", "<u4", "<U6"
  std::string shape_string() const;  ///< e.g. "(6890, 3)"
  std::string describe() const;      ///< origin, or "array" when it has none
  bool is_numeric() const { return kind == 'f' || kind == 'i' || kind == 'u' || kind == 'b'; }

  /// All elements converted to double (numeric kinds only; throws otherwise). float16 converts
  /// exactly (subnormals, ±inf and NaN included).
  std::vector<double> to_doubles() const;
  /// All elements converted to int64 (integer/bool kinds; floats only when integral).
  std::vector<std::int64_t> to_int64() const;
  /// A string array of one element (or a 0-d array), decoded from UTF-32 ('U') or bytes ('S').
  std::string to_string() const;
};

/// Builds a float64 array of the given shape from row-major values.
Array make_f64(std::vector<std::size_t> shape, const std::vector<double>& values);
/// Builds a float64 2-D array from an Eigen matrix (stored row-major, as NumPy does).
Array make_f64(const Eigen::Ref<const Eigen::MatrixXd>& matrix);
/// Builds an int64 array.
Array make_i64(std::vector<std::size_t> shape, const std::vector<std::int64_t>& values);
/// Builds a uint32 array.
Array make_u32(std::vector<std::size_t> shape, const std::vector<std::uint32_t>& values);
/// Builds a 0-d unicode string array ('<U…').
Array make_string(const std::string& value);
/// Builds a 0-d float64 scalar.
Array make_scalar(double value);

/// Parses one .npy byte buffer; `what` names the source in error messages ("<file>: <key>") and
/// becomes the array's origin. Checks the dtype, the shape (digits only, ≤ kMaxDimensions, no
/// overflow of elements × itemsize) and that the data is all there before copying it.
Array parse_npy(const std::vector<std::uint8_t>& buffer, const std::string& what);
/// Serializes to .npy (format version 1.0).
std::vector<std::uint8_t> serialize_npy(const Array& array);

/// A read-only .npz archive. Keys are member names without the ".npy" suffix.
class Reader {
 public:
  /// Opens `path` and checks every member's CRC-32 (read or not); throws sflsh::Error "<path>: …" when it is missing
  /// or not a zip archive, "<path>: <member>: … (corrupt archive)" when a member's data and checksum disagree.
  explicit Reader(const std::filesystem::path& path);
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  const std::vector<std::string>& keys() const { return keys_; }
  bool has(const std::string& key) const;
  /// Reads and parses member `key`; throws "<path>: <key>: …" when it is malformed, larger than
  /// kMaxMemberBytes or its CRC-32 does not match, "<path>: missing key '<key>'" when absent.
  Array read(const std::string& key) const;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::vector<std::string> keys_;
  struct Impl;
  std::unique_ptr<Impl> impl_;

  void verify_member(std::uint64_t index, const std::string& member) const;
};

/// Writes an .npz (deflate-compressed members) atomically: temp file, then rename.
void write(const std::filesystem::path& path, const std::vector<std::pair<std::string, Array>>& members);

}  // namespace sflsh::npz
