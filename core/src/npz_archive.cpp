// .npz archives: reading members through libzip (bounded size, CRC-32 checked with zlib) and
// writing them atomically. The .npy format itself is in npz.cpp.
#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/npz.hpp>

#include <fcntl.h>
#include <unistd.h>
#include <zip.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <new>

namespace sflsh::npz {

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
    const char* raw = zip_get_name(impl_->archive, static_cast<zip_uint64_t>(i), 0);
    require(raw != nullptr, "{}: member #{} has no readable name (corrupt archive)", path.string(), i);
    std::string name = raw;
    verify_member(static_cast<zip_uint64_t>(i), name);
    if (name.size() > 4 && name.ends_with(".npy")) name.resize(name.size() - 4);
    keys_.push_back(name);
  }
}

// Every member's CRC-32 at open, read or not: a damaged archive is refused as a whole, naming the member, instead of
// working until the damaged member is needed (or never noticing). Streamed in 64 KiB blocks; nothing is kept.
void Reader::verify_member(std::uint64_t index, const std::string& member) const {
  const std::string what = fmt::format("{}: {}", path_.string(), member);
  zip_stat_t st;
  zip_stat_init(&st);
  require(zip_stat_index(impl_->archive, index, 0, &st) == 0, "{}: cannot stat the zip member (corrupt archive)", what);
  if ((st.valid & ZIP_STAT_CRC) == 0 || (st.valid & ZIP_STAT_SIZE) == 0) return;
  require(st.size <= kMaxMemberBytes, "{}: member of {} bytes is above the limit of {} bytes (1 GiB)", what, st.size,
          kMaxMemberBytes);
  zip_file_t* file = zip_fopen_index(impl_->archive, index, 0);
  if (file == nullptr)
    throw_error("{}: cannot open the zip member: {} (corrupt archive)", what, zip_strerror(impl_->archive));
  std::vector<std::uint8_t> block(64 * 1024);
  uLong crc = crc32_z(0L, Z_NULL, 0);
  zip_uint64_t total = 0;
  zip_int64_t got = 0;
  while ((got = zip_fread(file, block.data(), block.size())) > 0) {
    crc = crc32_z(crc, block.data(), static_cast<z_size_t>(got));
    total += static_cast<zip_uint64_t>(got);
  }
  const std::string read_error = got < 0 ? zip_file_strerror(file) : std::string();
  zip_fclose(file);
  // libzip reports a CRC mismatch itself when it reads a member to its end ("CRC error").
  require(got >= 0, "{}: cannot read the zip member: {} (corrupt archive)", what, read_error);
  require(total == st.size, "{}: zip member truncated: {} of {} bytes (corrupt archive)", what, total, st.size);
  require(static_cast<std::uint32_t>(crc) == st.crc,
          "{}: CRC-32 of the data is {:08x}, the archive says {:08x} (corrupt archive)", what,
          static_cast<std::uint32_t>(crc), static_cast<std::uint32_t>(st.crc));
}

Reader::~Reader() {
  if (impl_ && impl_->archive) zip_discard(impl_->archive);
}

bool Reader::has(const std::string& key) const { return std::find(keys_.begin(), keys_.end(), key) != keys_.end(); }

Array Reader::read(const std::string& key) const {
  const std::string what = fmt::format("{}: {}", path_.string(), key);
  require(has(key), "{}: missing key '{}'", path_.string(), key);
  zip_stat_t st;
  zip_stat_init(&st);
  std::string member = key + ".npy";
  if (zip_stat(impl_->archive, member.c_str(), 0, &st) != 0) {
    member = key;
    require(zip_stat(impl_->archive, member.c_str(), 0, &st) == 0, "{}: cannot stat the zip member", what);
  }
  require((st.valid & ZIP_STAT_SIZE) != 0, "{}: the zip member has no size (corrupt archive)", what);
  // Bounds before allocating: the size the archive claims, and what its compressed bytes can hold.
  require(st.size <= kMaxMemberBytes, "{}: member of {} bytes is above the limit of {} bytes (1 GiB)", what, st.size,
          kMaxMemberBytes);
  if ((st.valid & ZIP_STAT_COMP_SIZE) != 0 && (st.valid & ZIP_STAT_COMP_METHOD) != 0) {
    if (st.comp_method == ZIP_CM_STORE)
      require(st.size == st.comp_size, "{}: stored member claims {} bytes but holds {} (corrupt archive)", what,
              st.size, st.comp_size);
    else if (st.comp_method == ZIP_CM_DEFLATE)  // deflate expands at most 1032:1
      require(st.size <= 1032 * st.comp_size + 1024,
              "{}: member claims {} bytes from {} compressed, more than deflate can produce (corrupt archive)", what,
              st.size, st.comp_size);
  }
  zip_file_t* file = zip_fopen(impl_->archive, member.c_str(), 0);
  if (file == nullptr) throw_error("{}: cannot open the zip member: {}", what, zip_strerror(impl_->archive));
  std::vector<std::uint8_t> buffer;
  try {
    buffer.resize(st.size);
  } catch (const std::bad_alloc&) {
    zip_fclose(file);
    throw_error("{}: cannot allocate {} bytes for the member", what, st.size);
  }
  const zip_int64_t got = st.size > 0 ? zip_fread(file, buffer.data(), st.size) : 0;
  const std::string read_error = got < 0 ? zip_file_strerror(file) : std::string();
  zip_fclose(file);
  require(got >= 0, "{}: cannot read the zip member: {} (corrupt archive)", what, read_error);
  require(got == static_cast<zip_int64_t>(st.size), "{}: zip member truncated: {} of {} bytes (corrupt archive)", what,
          got, st.size);
  if ((st.valid & ZIP_STAT_CRC) != 0) {
    const auto crc = static_cast<std::uint32_t>(crc32_z(crc32_z(0L, Z_NULL, 0), buffer.data(), buffer.size()));
    require(crc == st.crc, "{}: CRC-32 of the data is {:08x}, the archive says {:08x} (corrupt archive)", what, crc,
            static_cast<std::uint32_t>(st.crc));
  }
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
      const int system_errno = zip_error_code_system(zip_get_error(archive));
      const bool is_errno = zip_error_system_type(zip_get_error(archive)) == ZIP_ET_SYS && system_errno != 0;
      zip_discard(archive);
      if (is_errno) throw_write_error(path, "cannot write archive", system_errno);
      throw_error("{}: cannot write archive ({})", path.string(), msg);
    }
    // On the disk before the rename makes it visible: a crash then leaves the old entry or the whole new one.
    const int fd = ::open(tmp.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
      const int synced = ::fsync(fd) == 0 || errno == EINVAL || errno == EROFS ? 0 : errno;
      ::close(fd);
      if (synced != 0) throw_write_error(path, "cannot write archive", synced);
    }
  });
}

}  // namespace sflsh::npz
