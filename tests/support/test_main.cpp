#include <sflsh/core/log.hpp>

#include <gtest/gtest.h>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  sflsh::logger()->set_level(spdlog::level::warn);  // keep test output to failures
  return RUN_ALL_TESTS();
}
