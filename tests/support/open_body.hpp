#pragma once
// The open body (data/open_body.npz), loaded once per test process.
#include <sflsh/body/body_io.hpp>

#include <filesystem>

namespace sflsh::testing {

inline const body::BodyModel& open_body() {
  static const body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  return model;
}

}  // namespace sflsh::testing
