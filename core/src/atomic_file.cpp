#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>

#include <unistd.h>

#include <atomic>
#include <fstream>
#include <system_error>

namespace sflsh {

namespace fs = std::filesystem;

fs::path temporary_sibling(const fs::path& target) {
  static std::atomic<unsigned long> counter{0};
  return target.parent_path() /
         fmt::format(".{}.tmp-{}-{}", target.filename().string(), static_cast<long>(::getpid()), counter.fetch_add(1));
}

void write_atomically(const fs::path& target, const std::function<void(const fs::path&)>& write) {
  const fs::path tmp = temporary_sibling(target);
  try {
    write(tmp);
    if (!fs::exists(tmp)) throw_error("{}: writer produced no file", target.string());
    std::error_code ec;
    fs::rename(tmp, target, ec);
    if (ec) throw_error("{}: cannot move finished file into place: {}", target.string(), ec.message());
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

void write_text_atomically(const fs::path& target, std::string_view contents) {
  write_atomically(target, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw_error("{}: cannot open for writing", target.string());
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.close();
    if (!out) throw_error("{}: write failed (disk full?)", target.string());
  });
}

void ensure_directory(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    throw_error("{}: cannot create output directory{}", dir.string(),
                ec ? ": " + ec.message() : std::string(" (a file is in the way)"));
  }
}

}  // namespace sflsh
