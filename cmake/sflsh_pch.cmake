# Precompiled headers: the third-party headers nearly every translation unit parses (Eigen, fmt, spdlog,
# nlohmann::json, the standard library; GoogleTest in the tests, CLI11 in the CLI) are compiled once per target
# instead of once per file. Measured cold builds are in docs/build.md. Turn off with -DSFLSH_PCH=OFF (e.g. for
# include-what-you-use checks: with PCH a file that forgets an include still compiles).
if(COMMAND sflsh_precompile)
  return()
endif()
option(SFLSH_PCH "Precompile the heavy third-party headers of each target" ON)

set(SFLSH_PCH_HEADERS
  <algorithm> <array> <cmath> <filesystem> <functional> <map> <memory> <optional> <string> <unordered_map> <vector>
  <Eigen/Core> <Eigen/Dense> <Eigen/Sparse>
  <fmt/format.h> <spdlog/spdlog.h> <nlohmann/json.hpp>)

# sflsh_precompile(target [extra headers…]): the common headers plus the target's own heavy ones.
function(sflsh_precompile target)
  if(SFLSH_PCH)
    target_precompile_headers(${target} PRIVATE ${SFLSH_PCH_HEADERS} ${ARGN})
  endif()
endfunction()

# sflsh_precompile_shared(target group [extra headers…]): the targets of one group (the test executables that link
# PETSc, those that do not, the benchmarks) reuse the precompiled header of the group's first target
# (REUSE_FROM) instead of compiling their own: ≈ 10–17 s of CPU saved per target on a cold build (docs/build.md).
# A group's targets must compile with the definitions the header was built with (GCC refuses it otherwise, and
# CMake's -Winvalid-pch makes that an error under SFLSH_WERROR): see the groups in tests/CMakeLists.txt.
function(sflsh_precompile_shared target group)
  if(NOT SFLSH_PCH)
    return()
  endif()
  get_property(owner GLOBAL PROPERTY SFLSH_PCH_OWNER_${group})
  if(owner)
    target_precompile_headers(${target} REUSE_FROM ${owner})
  else()
    target_precompile_headers(${target} PRIVATE ${SFLSH_PCH_HEADERS} ${ARGN})
    set_property(GLOBAL PROPERTY SFLSH_PCH_OWNER_${group} ${target})
  endif()
endfunction()
