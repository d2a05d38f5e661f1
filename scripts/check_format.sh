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
bad=()
for f in "${files[@]}"; do
  if ! "$clang_format" --dry-run --Werror "$f" >/dev/null 2>&1; then bad+=("$f"); fi
done
if ((${#bad[@]})); then
  for f in "${bad[@]}"; do echo "$f: not formatted (run: clang-format -i $f)"; done
  echo "check_format: ${#bad[@]} of ${#files[@]} files not formatted; scripts/check_format.sh --fix formats them all"
  exit 1
fi
echo "check_format: ${#files[@]} files formatted"
