#pragma once
// The message of the sflsh::Error that f() throws, or a marker when it throws none.
#include <sflsh/core/error.hpp>

#include <string>

namespace sflsh::testing {

template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no sflsh::Error thrown)";
}

}  // namespace sflsh::testing
