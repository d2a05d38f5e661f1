#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/npz.hpp>

#include <zip.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
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

}  // namespace

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
  require(is_numeric(), "array of dtype {} is not numeric", dtype());
  const std::size_t n = size();
  std::vector<double> out(n);
  const std::uint8_t* p = bytes.data();
  for (std::size_t i = 0; i < n; ++i, p += itemsize) {
    switch (kind) {
      case 'f':
        if (itemsize == 8) out[i] = load_le<double>(p);
        else if (itemsize == 4) out[i] = static_cast<double>(load_le<float>(p));
        else throw_error("unsupported float size {} bytes", itemsize);
        break;
      case 'i':
        if (itemsize == 8) out[i] = static_cast<double>(load_le<std::int64_t>(p));
        else if (itemsize == 4) out[i] = static_cast<double>(load_le<std::int32_t>(p));
        else if (itemsize == 2) out[i] = static_cast<double>(load_le<std::int16_t>(p));
        else out[i] = static_cast<double>(load_le<std::int8_t>(p));
        break;
      case 'u':
        if (itemsize == 8) out[i] = static_cast<double>(load_le<std::uint64_t>(p));
        else if (itemsize == 4) out[i] = static_cast<double>(load_le<std::uint32_t>(p));
        else if (itemsize == 2) out[i] = static_cast<double>(load_le<std::uint16_t>(p));
        else out[i] = static_cast<double>(*p);
        break;
      default:  // 'b'
        out[i] = *p ? 1.0 : 0.0;
    }
  }
  return out;
}

std::vector<std::int64_t> Array::to_int64() const {
  require(is_numeric(), "array of dtype {} is not numeric", dtype());
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
    require(std::isfinite(values[i]) && std::floor(values[i]) == values[i],
            "array of dtype {} holds a non-integer value {} where integers are expected", dtype(), values[i]);
    out[i] = static_cast<std::int64_t>(values[i]);
  }
  return out;
}

std::string Array::to_string() const {
  require(kind == 'U' || kind == 'S', "array of dtype {} is not a string", dtype());
  require(size() == 1, "expected a single string, got shape {}", shape_string());
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

Array parse_npy(const std::vector<std::uint8_t>& buffer, const std::string& what) {
  require(buffer.size() >= 10 && std::memcmp(buffer.data(), kMagic, 6) == 0,
          "{}: not a .npy array (bad magic)", what);
  const int major = buffer[6];
  std::size_t header_len = 0;
  std::size_t offset = 0;
  if (major == 1) {
    header_len = load_le<std::uint16_t>(buffer.data() + 8);
    offset = 10;
  } else if (major == 2 || major == 3) {
    require(buffer.size() >= 12, "{}: truncated .npy header", what);
    header_len = load_le<std::uint32_t>(buffer.data() + 8);
    offset = 12;
  } else {
    throw_error("{}: unsupported .npy format version {}", what, major);
  }
  require(offset + header_len <= buffer.size(), "{}: truncated .npy header", what);
  const std::string header(reinterpret_cast<const char*>(buffer.data() + offset), header_len);

  static const std::regex descr_re(R"('descr'\s*:\s*'([^']*)')");
  static const std::regex order_re(R"('fortran_order'\s*:\s*(True|False))");
  static const std::regex shape_re(R"('shape'\s*:\s*\(([^)]*)\))");
  std::smatch m;
  require(std::regex_search(header, m, descr_re), "{}: .npy header has no 'descr'", what);
  const std::string descr = m[1];
  require(std::regex_search(header, m, order_re), "{}: .npy header has no 'fortran_order'", what);
  const bool fortran = m[1] == "True";
  require(std::regex_search(header, m, shape_re), "{}: .npy header has no 'shape'", what);
  const std::string shape_text = m[1];

  Array a;
  require(descr.size() >= 3, "{}: unsupported dtype '{}'", what, descr);
  const char byteorder = descr[0];
  a.kind = descr[1];
  require(a.kind != 'O', "{}: dtype 'O' (pickled Python objects) is not supported; save plain arrays", what);
  require(std::string("fiubUS").find(a.kind) != std::string::npos, "{}: unsupported dtype '{}'", what, descr);
  std::size_t count = 0;
  try {
    count = std::stoul(descr.substr(2));
  } catch (const std::exception&) {
    throw_error("{}: unsupported dtype '{}'", what, descr);
  }
  a.itemsize = a.kind == 'U' ? 4 * count : count;
  require(byteorder != '>' || a.itemsize == 1, "{}: big-endian dtype '{}' is not supported", what, descr);
  require(a.itemsize > 0, "{}: zero-size dtype '{}'", what, descr);

  std::size_t start = 0;
  while (start < shape_text.size()) {
    std::size_t comma = shape_text.find(',', start);
    if (comma == std::string::npos) comma = shape_text.size();
    const std::string token = trim(shape_text.substr(start, comma - start));
    if (!token.empty()) {
      try {
        a.shape.push_back(std::stoul(token));
      } catch (const std::exception&) {
        throw_error("{}: bad shape '({})'", what, shape_text);
      }
    }
    start = comma + 1;
  }
  const std::size_t data_offset = offset + header_len;
  const std::size_t nbytes = a.size() * a.itemsize;
  require(buffer.size() - data_offset >= nbytes, "{}: data truncated: shape {} needs {} bytes, file has {}", what,
          a.shape_string(), nbytes, buffer.size() - data_offset);
  a.bytes.assign(buffer.begin() + static_cast<std::ptrdiff_t>(data_offset),
                 buffer.begin() + static_cast<std::ptrdiff_t>(data_offset + nbytes));

  if (fortran && a.shape.size() > 1) {  // transpose to C order
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
  return a;
}

std::vector<std::uint8_t> serialize_npy(const Array& array) {
  std::string header = fmt::format("{{'descr': '{}', 'fortran_order': False, 'shape': {}, }}", array.dtype(),
                                   array.shape_string());
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

struct Reader::Impl {
  zip_t* archive = nullptr;
};

Reader::Reader(const std::filesystem::path& path) : path_(path), impl_(std::make_unique<Impl>()) {
  require(std::filesystem::exists(path), "{}: file not found", path.string());
  int err = 0;
  impl_->archive = zip_open(path.c_str(), ZIP_RDONLY, &err);
  if (!impl_->archive) {
    zip_error_t ze;
    zip_error_init_with_code(&ze, err);
    const std::string msg = zip_error_strerror(&ze);
    zip_error_fini(&ze);
    throw_error("{}: not a readable .npz (zip) archive: {}", path.string(), msg);
  }
  const zip_int64_t n = zip_get_num_entries(impl_->archive, 0);
  for (zip_int64_t i = 0; i < n; ++i) {
    std::string name = zip_get_name(impl_->archive, static_cast<zip_uint64_t>(i), 0);
    if (name.size() > 4 && name.ends_with(".npy")) name.resize(name.size() - 4);
    keys_.push_back(name);
  }
}

Reader::~Reader() {
  if (impl_ && impl_->archive) zip_discard(impl_->archive);
}

bool Reader::has(const std::string& key) const {
  return std::find(keys_.begin(), keys_.end(), key) != keys_.end();
}

Array Reader::read(const std::string& key) const {
  const std::string what = fmt::format("{}: key '{}'", path_.string(), key);
  require(has(key), "{}: missing key '{}'", path_.string(), key);
  zip_stat_t st;
  std::string member = key + ".npy";
  if (zip_stat(impl_->archive, member.c_str(), 0, &st) != 0) {
    member = key;
    require(zip_stat(impl_->archive, member.c_str(), 0, &st) == 0, "{}: cannot stat member", what);
  }
  zip_file_t* file = zip_fopen(impl_->archive, member.c_str(), 0);
  require(file != nullptr, "{}: cannot open member", what);
  std::vector<std::uint8_t> buffer(st.size);
  const zip_int64_t got = zip_fread(file, buffer.data(), st.size);
  zip_fclose(file);
  require(got == static_cast<zip_int64_t>(st.size), "{}: cannot read member (corrupt archive?)", what);
  return parse_npy(buffer, what);
}

void write(const std::filesystem::path& path, const std::vector<std::pair<std::string, Array>>& members) {
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    int err = 0;
    zip_t* archive = zip_open(tmp.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
    require(archive != nullptr, "{}: cannot create archive", path.string());
    // libzip reads the source buffers at zip_close, so keep them alive until then.
    std::vector<std::vector<std::uint8_t>> buffers;
    buffers.reserve(members.size());
    for (const auto& [key, array] : members) {
      buffers.push_back(serialize_npy(array));
      zip_source_t* src = zip_source_buffer(archive, buffers.back().data(), buffers.back().size(), 0);
      const std::string name = key + ".npy";
      const zip_int64_t idx = src ? zip_file_add(archive, name.c_str(), src, ZIP_FL_OVERWRITE) : -1;
      if (idx < 0) {
        if (src) zip_source_free(src);
        zip_discard(archive);
        throw_error("{}: cannot add member '{}'", path.string(), key);
      }
      zip_set_file_compression(archive, static_cast<zip_uint64_t>(idx), ZIP_CM_DEFLATE, 6);
    }
    if (zip_close(archive) != 0) {
      const std::string msg = zip_strerror(archive);
      zip_discard(archive);
      throw_error("{}: cannot write archive: {}", path.string(), msg);
    }
  });
}

}  // namespace sflsh::npz
