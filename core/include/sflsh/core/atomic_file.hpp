#pragma once
// Atomic output: every file the project writes goes to "<path>.tmp-<pid>-<n>" first and is renamed
// onto <path> only when complete, so a failed run never leaves a partial or corrupted file.
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

namespace sflsh {

/// A temporary sibling path of `target`, unique within this process.
std::filesystem::path temporary_sibling(const std::filesystem::path& target);

/// Calls write(tmp) with a temporary sibling path, then renames it onto `target`.
/// If write throws, the temporary is removed and the exception propagates; `target` is untouched.
void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path& tmp)>& write);

/// Removes the temporaries of `target` that writers killed before their rename left behind (".<name>.tmp-<pid>-<n>"
/// and the files libzip derives from them) whose process <pid> is gone; those of live processes are left alone.
/// Returns how many were removed. Caches call it before building an entry (issue 45: kills mid-write).
int remove_stale_temporaries(const std::filesystem::path& target);

/// Throws sflsh::Error "<target>: <what> (<strerror(error_number)>)", the one shape of every write failure.
[[noreturn]] void throw_write_error(const std::filesystem::path& target, std::string_view what, int error_number);

/// Writes `contents` to `file` with its space reserved first (fallocate; fsync after the writes where the file system
/// cannot reserve) and checked writes and close: a full disk, a quota, a file size limit, an I/O error throw through
/// throw_write_error naming `target`, the path the user knows.
void write_file_checked(const std::filesystem::path& file, const std::filesystem::path& target,
                        std::string_view contents);

/// Writes `contents` to `target` atomically (write_file_checked on a temporary sibling, then a rename).
void write_text_atomically(const std::filesystem::path& target, std::string_view contents);

/// Creates `dir` (and parents); throws sflsh::Error naming the path when it is not a writable directory.
void ensure_directory(const std::filesystem::path& dir);

}  // namespace sflsh
