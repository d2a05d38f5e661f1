// The .npy format: arrays, their conversions (float16 included) and the header parser, which checks the
// dtype, the shape and the byte count before copying anything. Archives are in npz_archive.cpp.
#include <sflsh/core/error.hpp>
#include <sflsh/core/npz.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <optional>
#include <regex>

namespace sflsh::npz {

namespace {

constexpr char kMagic[] = "\x93NUMPY";

template <typename T>
T load_le(const std::uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));  // x86-64 and aarch64 are little-endian, as .npy data here
  return value;
}

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\n");
  if (first == std::string::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t\n") - first + 1);
}

/// IEEE 754 binary16 → double, exact: 1 sign, 5 exponent (bias 15), 10 mantissa bits.
double half_to_double(std::uint16_t h) {
  const bool negative = (h & 0x8000u) != 0;
  const int exponent = (h >> 10) & 0x1F;
  const int mantissa = h & 0x3FF;
  double magnitude = 0.0;
  if (exponent == 0)
    magnitude = std::ldexp(static_cast<double>(mantissa), -24);  // zero and subnormals
  else if (exponent == 31)
    magnitude = mantissa == 0 ? std::numeric_limits<double>::infinity() : std::numeric_limits<double>::quiet_NaN();
  else
    magnitude = std::ldexp(static_cast<double>(mantissa | 0x400), exponent - 25);
  return negative ? -magnitude : magnitude;
}

/// A whole number made of decimal digits only (no sign, no spaces), at most `limit`; nullopt otherwise.
std::optional<std::size_t> parse_count(const std::string& text, std::size_t limit) {
  if (text.empty() || text.size() > 19) return std::nullopt;
  std::size_t value = 0;
  for (const char c : text) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
    value = 10 * value + static_cast<std::size_t>(c - '0');
  }
  if (value > limit) return std::nullopt;
  return value;
}

/// The item sizes NumPy uses for each kind we accept.
bool supported_itemsize(char kind, std::size_t itemsize) {
  switch (kind) {
    case 'f':
      return itemsize == 2 || itemsize == 4 || itemsize == 8;
    case 'i':
    case 'u':
      return itemsize == 1 || itemsize == 2 || itemsize == 4 || itemsize == 8;
    case 'b':
      return itemsize == 1;
    default:
      return itemsize > 0;  // 'U', 'S': bounded by kMaxStringLength when parsed
  }
}

constexpr const char* kSupportedDtypes =
    "expected float16/32/64, int8-64, uint8-64, bool or a fixed-width string (<f8, <i4, |b1, <U6, ...)";

}  // namespace

std::string Array::describe() const { return origin.empty() ? std::string("array") : origin; }

std::size_t Array::size() const {
  return std::accumulate(shape.begin(), shape.end(), std::size_t{1}, std::multiplies<>());
}

std::string Array::dtype() const {
  const char order = (kind == 'U' || itemsize > 1) ? '<' : '|';
  const std::size_t n = kind == 'U' ? itemsize / 4 : itemsize;
  return fmt::format("{}{}{}", order, kind, n);
}

std::string Array::shape_string() const {
  std::string s = "(";
  for (std::size_t i = 0; i < shape.size(); ++i) {
    s += std::to_string(shape[i]);
    if (shape.size() == 1 || i + 1 < shape.size()) s += shape.size() == 1 ? "," : ", ";
  }
  return s + ")";
}

std::vector<double> Array::to_doubles() const {
  require(is_numeric(), "{}: dtype {} is not numeric, expected numbers", describe(), dtype());
  require(supported_itemsize(kind, itemsize) && bytes.size() / itemsize >= size(),
          "{}: dtype {} with shape {} and {} bytes is inconsistent", describe(), dtype(), shape_string(), bytes.size());
  const std::size_t n = size();
  std::vector<double> out(n);
  const std::uint8_t* p = bytes.data();
  for (std::size_t i = 0; i < n; ++i, p += itemsize) {
    switch (kind) {
      case 'f':
        if (itemsize == 8)
          out[i] = load_le<double>(p);
        else if (itemsize == 4)
          out[i] = static_cast<double>(load_le<float>(p));
        else
          out[i] = half_to_double(load_le<std::uint16_t>(p));
        break;
      case 'i':
        if (itemsize == 8)
          out[i] = static_cast<double>(load_le<std::int64_t>(p));
        else if (itemsize == 4)
          out[i] = static_cast<double>(load_le<std::int32_t>(p));
        else if (itemsize == 2)
          out[i] = static_cast<double>(load_le<std::int16_t>(p));
        else
          out[i] = static_cast<double>(load_le<std::int8_t>(p));
        break;
      case 'u':
        if (itemsize == 8)
          out[i] = static_cast<double>(load_le<std::uint64_t>(p));
        else if (itemsize == 4)
          out[i] = static_cast<double>(load_le<std::uint32_t>(p));
        else if (itemsize == 2)
          out[i] = static_cast<double>(load_le<std::uint16_t>(p));
        else
          out[i] = static_cast<double>(*p);
        break;
      default:  // 'b'
        out[i] = *p ? 1.0 : 0.0;
    }
  }
  return out;
}

std::vector<std::int64_t> Array::to_int64() const {
  require(is_numeric(), "{}: dtype {} is not numeric, expected integers", describe(), dtype());
  require(supported_itemsize(kind, itemsize) && bytes.size() / itemsize >= size(),
          "{}: dtype {} with shape {} and {} bytes is inconsistent", describe(), dtype(), shape_string(), bytes.size());
  if (kind == 'u' && itemsize == 8) {
    std::vector<std::int64_t> out(size());
    for (std::size_t i = 0; i < out.size(); ++i)
      out[i] = static_cast<std::int64_t>(load_le<std::uint64_t>(bytes.data() + 8 * i));
    return out;
  }
  if (kind == 'i' && itemsize == 8) {
    std::vector<std::int64_t> out(size());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = load_le<std::int64_t>(bytes.data() + 8 * i);
    return out;
  }
  const std::vector<double> values = to_doubles();
  std::vector<std::int64_t> out(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    require(std::isfinite(values[i]) && std::floor(values[i]) == values[i] && std::abs(values[i]) <= 9.0e15,
            "{}: element {} is {} (dtype {}), expected an integer", describe(), i, values[i], dtype());
    out[i] = static_cast<std::int64_t>(values[i]);
  }
  return out;
}

std::string Array::to_string() const {
  require(kind == 'U' || kind == 'S', "{}: dtype {} is not a string, expected <U… or |S…", describe(), dtype());
  require(size() == 1, "{}: shape {}, expected a single string", describe(), shape_string());
  require(bytes.size() >= itemsize, "{}: {} bytes for a string of {} bytes", describe(), bytes.size(), itemsize);
  std::string out;
  if (kind == 'S') {
    for (std::size_t i = 0; i < itemsize && bytes[i] != 0; ++i) out.push_back(static_cast<char>(bytes[i]));
    return out;
  }
  for (std::size_t i = 0; i + 4 <= itemsize; i += 4) {
    const auto cp = load_le<std::uint32_t>(bytes.data() + i);
    if (cp == 0) break;
    if (cp < 0x80) {
      out.push_back(static_cast<char>(cp));
    } else if (cp < 0x800) {
      out.push_back(static_cast<char>(0xC0 | (cp >> 6)));
      out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
    } else if (cp < 0x10000) {
      out.push_back(static_cast<char>(0xE0 | (cp >> 12)));
      out.push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
      out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
    } else {
      out.push_back(static_cast<char>(0xF0 | (cp >> 18)));
      out.push_back(static_cast<char>(0x80 | ((cp >> 12) & 0x3F)));
      out.push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
      out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
    }
  }
  return out;
}

Array make_f64(std::vector<std::size_t> shape, const std::vector<double>& values) {
  Array a;
  a.kind = 'f';
  a.itemsize = 8;
  a.shape = std::move(shape);
  require(a.size() == values.size(), "make_f64: shape holds {} elements, got {}", a.size(), values.size());
  a.bytes.resize(values.size() * 8);
  std::memcpy(a.bytes.data(), values.data(), a.bytes.size());
  return a;
}

Array make_f64(const Eigen::Ref<const Eigen::MatrixXd>& matrix) {
  std::vector<double> values(static_cast<std::size_t>(matrix.size()));
  for (Eigen::Index r = 0; r < matrix.rows(); ++r)
    for (Eigen::Index c = 0; c < matrix.cols(); ++c)
      values[static_cast<std::size_t>(r * matrix.cols() + c)] = matrix(r, c);
  return make_f64({static_cast<std::size_t>(matrix.rows()), static_cast<std::size_t>(matrix.cols())}, values);
}

Array make_i64(std::vector<std::size_t> shape, const std::vector<std::int64_t>& values) {
  Array a;
  a.kind = 'i';
  a.itemsize = 8;
  a.shape = std::move(shape);
  require(a.size() == values.size(), "make_i64: shape holds {} elements, got {}", a.size(), values.size());
  a.bytes.resize(values.size() * 8);
  std::memcpy(a.bytes.data(), values.data(), a.bytes.size());
  return a;
}

Array make_u32(std::vector<std::size_t> shape, const std::vector<std::uint32_t>& values) {
  Array a;
  a.kind = 'u';
  a.itemsize = 4;
  a.shape = std::move(shape);
  require(a.size() == values.size(), "make_u32: shape holds {} elements, got {}", a.size(), values.size());
  a.bytes.resize(values.size() * 4);
  std::memcpy(a.bytes.data(), values.data(), a.bytes.size());
  return a;
}

Array make_string(const std::string& value) {
  Array a;
  a.kind = 'U';
  a.itemsize = 4 * std::max<std::size_t>(1, value.size());
  a.bytes.assign(a.itemsize, 0);
  for (std::size_t i = 0; i < value.size(); ++i) {
    const auto cp = static_cast<std::uint32_t>(static_cast<unsigned char>(value[i]));  // ASCII/Latin-1
    std::memcpy(a.bytes.data() + 4 * i, &cp, 4);
  }
  return a;
}

Array make_scalar(double value) { return make_f64({}, {value}); }

namespace {

/// Where a .npy header's text lies in the buffer: its byte offset and its length.
struct NpyHeaderSpan {
  std::size_t offset = 0;
  std::size_t length = 0;
};

/// The three entries of a .npy header dictionary, as read from its text.
struct NpyHeaderFields {
  std::string descr;
  bool fortran = false;
  std::string shape_text;
};

/// Checks the magic and the format version of a .npy buffer and locates its header text.
NpyHeaderSpan npy_header_span(const std::vector<std::uint8_t>& buffer, const std::string& what) {
  require(buffer.size() >= 10 && std::memcmp(buffer.data(), kMagic, 6) == 0,
          "{}: not a .npy array (no \\x93NUMPY magic in the first {} bytes), expected a NumPy array", what,
          std::min<std::size_t>(buffer.size(), 6));
  const int major = buffer[6];
  std::size_t header_len = 0;
  std::size_t offset = 0;
  if (major == 1) {
    header_len = load_le<std::uint16_t>(buffer.data() + 8);
    offset = 10;
  } else if (major == 2 || major == 3) {
    require(buffer.size() >= 12, "{}: .npy header truncated ({} bytes), expected at least 12", what, buffer.size());
    header_len = load_le<std::uint32_t>(buffer.data() + 8);
    offset = 12;
  } else {
    throw_error("{}: .npy format version {}, expected 1, 2 or 3", what, major);
  }
  require(header_len <= buffer.size() - offset, "{}: .npy header of {} bytes runs past the member's {} bytes", what,
          header_len, buffer.size());
  return {offset, header_len};
}

/// Finds 'descr', 'fortran_order' and 'shape' in a .npy header's text.
NpyHeaderFields npy_header_fields(const std::string& header, const std::string& what) {
  static const std::regex descr_re(R"('descr'\s*:\s*'([^']*)')");
  static const std::regex order_re(R"('fortran_order'\s*:\s*(True|False))");
  static const std::regex shape_re(R"('shape'\s*:\s*\(([^)]*)\))");
  NpyHeaderFields fields;
  std::smatch m;
  require(std::regex_search(header, m, descr_re),
          "{}: .npy header has no plain 'descr' (structured dtypes are not supported), {}", what, kSupportedDtypes);
  fields.descr = m[1];
  require(std::regex_search(header, m, order_re), "{}: .npy header has no 'fortran_order', expected True or False",
          what);
  fields.fortran = m[1] == "True";
  require(std::regex_search(header, m, shape_re), "{}: .npy header has no 'shape', expected a tuple such as (6890, 3)",
          what);
  fields.shape_text = m[1];
  return fields;
}

/// Sets the kind and item size of `a` from a descr such as '<f8', refusing the dtypes we do not read.
void npy_set_dtype(Array& a, const std::string& descr, const std::string& what) {
  require(descr.size() >= 3, "{}: dtype '{}' is not supported, {}", what, descr, kSupportedDtypes);
  const char byteorder = descr[0];
  a.kind = descr[1];
  require(a.kind != 'O', "{}: dtype 'O' (pickled Python objects) is not supported; save plain arrays", what);
  require(std::string("<|=>").find(byteorder) != std::string::npos &&
              std::string("fiubUS").find(a.kind) != std::string::npos,
          "{}: dtype '{}' is not supported, {}", what, descr, kSupportedDtypes);
  const std::optional<std::size_t> count = parse_count(descr.substr(2), kMaxStringLength);
  require(count.has_value() && *count > 0, "{}: dtype '{}' is not supported, {}", what, descr, kSupportedDtypes);
  a.itemsize = a.kind == 'U' ? 4 * *count : *count;
  require(supported_itemsize(a.kind, a.itemsize), "{}: dtype '{}' is not supported, {}", what, descr, kSupportedDtypes);
  require(byteorder != '>' || a.itemsize == 1 || a.kind == 'S',
          "{}: big-endian dtype '{}' is not supported, expected little-endian ('<{}')", what, descr, descr.substr(1));
}

/// Parses the inside of a shape tuple into `a.shape`; returns the element count, nullopt if it overflows.
std::optional<std::size_t> npy_parse_shape(Array& a, const std::string& shape_text, const std::string& what) {
  std::size_t start = 0;
  std::size_t elements = 1;
  bool overflow = false;
  while (start < shape_text.size()) {
    std::size_t comma = shape_text.find(',', start);
    if (comma == std::string::npos) comma = shape_text.size();
    const std::string token = trim(shape_text.substr(start, comma - start));
    if (!token.empty()) {
      // Python may write 6890L for a long on old files.
      const std::string digits = token.back() == 'L' ? token.substr(0, token.size() - 1) : token;
      const std::optional<std::size_t> extent = parse_count(digits, std::numeric_limits<std::size_t>::max());
      require(extent.has_value(), "{}: shape ({}) has '{}', expected non-negative whole numbers", what, shape_text,
              token);
      a.shape.push_back(*extent);
      require(a.shape.size() <= kMaxDimensions, "{}: shape ({}) has more than {} dimensions", what, shape_text,
              kMaxDimensions);
      overflow = overflow || __builtin_mul_overflow(elements, *extent, &elements);
    }
    start = comma + 1;
  }
  if (overflow) return std::nullopt;
  return elements;
}

/// The byte count of the array's data given its element count; nullopt when it exceeds 2^64 bytes.
std::optional<std::size_t> npy_data_bytes(const Array& a, std::optional<std::size_t> elements) {
  std::size_t nbytes = 0;
  bool overflow = !elements.has_value() || __builtin_mul_overflow(*elements, a.itemsize, &nbytes);
  if (std::find(a.shape.begin(), a.shape.end(), std::size_t{0}) != a.shape.end()) {
    overflow = false;  // a zero extent makes the array empty whatever the other extents are
    nbytes = 0;
  }
  if (overflow) return std::nullopt;
  return nbytes;
}

/// Reorders the `nbytes` bytes of a Fortran-ordered array with more than one dimension into C order.
void npy_fortran_to_c_order(Array& a, std::size_t nbytes) {
  const std::size_t nd = a.shape.size();
  std::vector<std::size_t> c_strides(nd), f_strides(nd);
  c_strides[nd - 1] = 1;
  for (std::size_t d = nd - 1; d-- > 0;) c_strides[d] = c_strides[d + 1] * a.shape[d + 1];
  f_strides[0] = 1;
  for (std::size_t d = 1; d < nd; ++d) f_strides[d] = f_strides[d - 1] * a.shape[d - 1];
  std::vector<std::uint8_t> c_bytes(nbytes);
  std::vector<std::size_t> idx(nd, 0);
  for (std::size_t f = 0; f < a.size(); ++f) {
    std::size_t rem = f, c = 0;
    for (std::size_t d = 0; d < nd; ++d) {
      const std::size_t i = (rem / f_strides[d]) % a.shape[d];
      c += i * c_strides[d];
    }
    std::memcpy(c_bytes.data() + c * a.itemsize, a.bytes.data() + f * a.itemsize, a.itemsize);
    (void)rem;
  }
  a.bytes = std::move(c_bytes);
}

}  // namespace

Array parse_npy(const std::vector<std::uint8_t>& buffer, const std::string& what) {
  const NpyHeaderSpan span = npy_header_span(buffer, what);
  const std::string header(reinterpret_cast<const char*>(buffer.data() + span.offset), span.length);
  const NpyHeaderFields fields = npy_header_fields(header, what);

  Array a;
  a.origin = what;
  npy_set_dtype(a, fields.descr, what);
  const std::optional<std::size_t> nbytes = npy_data_bytes(a, npy_parse_shape(a, fields.shape_text, what));
  const std::size_t data_offset = span.offset + span.length;
  const std::size_t available = buffer.size() - data_offset;
  require(nbytes.has_value(), "{}: shape {} of dtype {} needs more than 2^64 bytes, the member has {}", what,
          a.shape_string(), a.dtype(), available);
  require(available >= *nbytes, "{}: data truncated: shape {} of dtype {} needs {} bytes, the member has {}", what,
          a.shape_string(), a.dtype(), *nbytes, available);
  a.bytes.assign(buffer.begin() + static_cast<std::ptrdiff_t>(data_offset),
                 buffer.begin() + static_cast<std::ptrdiff_t>(data_offset + *nbytes));

  if (fields.fortran && a.shape.size() > 1) npy_fortran_to_c_order(a, *nbytes);  // transpose to C order
  return a;
}

std::vector<std::uint8_t> serialize_npy(const Array& array) {
  std::string header =
      fmt::format("{{'descr': '{}', 'fortran_order': False, 'shape': {}, }}", array.dtype(), array.shape_string());
  const std::size_t total = 10 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header.push_back('\n');
  std::vector<std::uint8_t> out;
  out.reserve(10 + header.size() + array.bytes.size());
  for (int i = 0; i < 6; ++i) out.push_back(static_cast<std::uint8_t>(kMagic[i]));
  out.push_back(1);
  out.push_back(0);
  const auto len = static_cast<std::uint16_t>(header.size());
  out.push_back(static_cast<std::uint8_t>(len & 0xFF));
  out.push_back(static_cast<std::uint8_t>(len >> 8));
  out.insert(out.end(), header.begin(), header.end());
  out.insert(out.end(), array.bytes.begin(), array.bytes.end());
  return out;
}

}  // namespace sflsh::npz
