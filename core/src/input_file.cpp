// require_input_file (input_file.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/core/input_file.hpp>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <system_error>

namespace sflsh {

void require_input_file(const std::filesystem::path& path, std::string_view what) {
  const std::string name = path.string();
  require(!name.empty(), "(empty path): expected {}", what);
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) throw_error("{}: not found, expected {}", name, what);
  if (ec) throw_error("{}: cannot be examined ({}), expected {}", name, ec.message(), what);
  if (std::filesystem::is_directory(status)) throw_error("{}: is a directory, expected {}", name, what);
  if (!std::filesystem::is_regular_file(status)) throw_error("{}: is not a regular file, expected {}", name, what);
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in.is_open()) {
    const int error = errno;
    throw_error("{}: cannot be read ({}), expected {}", name, error != 0 ? std::strerror(error) : "open failed", what);
  }
}

}  // namespace sflsh
