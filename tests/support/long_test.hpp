#pragma once
// Tests too slow for every CI run (tens of seconds each on 2 cores) stay in their suite but are skipped unless
// SFLSH_LONG_TESTS is set; tests/CMakeLists.txt runs them as CTest tests labelled `long`
// (`ctest --preset long`, docs/build.md "Long tests").
#include <gtest/gtest.h>

#include <cstdlib>

#define SFLSH_LONG_TEST()                                                            \
  do {                                                                               \
    if (std::getenv("SFLSH_LONG_TESTS") == nullptr)                                  \
      GTEST_SKIP() << "a long test: run it with `ctest --preset long` (label long)"; \
  } while (false)
