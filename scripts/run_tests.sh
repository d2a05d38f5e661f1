#!/usr/bin/env bash
# Builds sflsh and runs every test with CTest (GoogleTest suites). Warnings are errors when
# SFLSH_WERROR=ON (CI sets it).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset release -DSFLSH_WERROR="${SFLSH_WERROR:-OFF}" >/dev/null
cmake --build --preset release -j"$(nproc)"
ctest --preset release -j"$(nproc)"
