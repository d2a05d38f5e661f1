#pragma once
// Checking a file argument before reading it: a directory, a missing file or one that cannot be opened is
// refused with one line saying which and what was expected ("<path>: is a directory, expected a material
// TOML file"), instead of the reader's own confusing follow-on error.
#include <filesystem>
#include <string_view>

namespace sflsh {

/// Throws sflsh::Error "<path>: <problem>, expected <what>" unless `path` is a regular file (or a link to
/// one) that can be opened for reading. `what` names the kind, with its article: "a material TOML file".
void require_input_file(const std::filesystem::path& path, std::string_view what);

}  // namespace sflsh
