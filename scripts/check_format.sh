#!/usr/bin/env bash
# Checks that every tracked C++ file is formatted by clang-format with the repository's .clang-format (Debian 12's
# clang-format 14). Prints the files that are not, with the command that fixes them, and exits 1 when there are any.
# Fix everything: scripts/check_format.sh --fix
set -euo pipefail
cd "$(dirname "$0")/.."
clang_format=${CLANG_FORMAT:-clang-format}
command -v "$clang_format" >/dev/null || { echo "check_format: $clang_format not found (Debian package clang-format)"; exit 1; }
mapfile -t files < <(git ls-files '*.cpp' '*.hpp' '*.h' 2>/dev/null || find . -path ./build -prune -o \( -name '*.cpp' -o -name '*.hpp' \) -print)
if [[ "${1:-}" == "--fix" ]]; then
  "$clang_format" -i "${files[@]}"
  echo "check_format: formatted ${#files[@]} files"
  exit 0
fi
# Batches of files on every core; clang-format names each unformatted file in "FILE:LINE:COL: error: …".
out=$(printf '%s\0' "${files[@]}" | xargs -0 -n 40 -P "$(nproc)" "$clang_format" --dry-run --Werror 2>&1 || true)
mapfile -t bad < <(grep -oE '^[^:]+:[0-9]+:[0-9]+: error' <<<"$out" | cut -d: -f1 | sort -u)
if ((${#bad[@]})); then
  for f in "${bad[@]}"; do echo "$f: not formatted (run: clang-format -i $f)"; done
  echo "check_format: ${#bad[@]} of ${#files[@]} files not formatted; scripts/check_format.sh --fix formats them all"
  exit 1
fi
echo "check_format: ${#files[@]} files formatted"
