#pragma once
// Error reporting in three tiers (docs/style.md §11):
//  - assert() for internal invariants,
//  - sflsh::Error for bad input and non-convergence: always on, one line, naming the file/field,
//  - never bool returns with prints, never exit() from library code.
#include <fmt/format.h>

#include <stdexcept>
#include <string>
#include <utility>

namespace sflsh {

/// The one exception type of the project; what() is a single line meant for the user.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// Throws sflsh::Error with an fmt-formatted one-line message.
template <typename... Args>
[[noreturn]] void throw_error(fmt::format_string<Args...> format, Args&&... args) {
  throw Error(fmt::format(format, std::forward<Args>(args)...));
}

/// Always-on check: throws sflsh::Error(message) when the condition fails.
template <typename... Args>
void require(bool condition, fmt::format_string<Args...> format, Args&&... args) {
  if (!condition) throw Error(fmt::format(format, std::forward<Args>(args)...));
}

}  // namespace sflsh
