#!/usr/bin/env bash
# Checks that every C++ source of the tree is as clang-format writes it (.clang-format), and with
# --fix rewrites those that are not. CTest runs the check (test "format"). The layout is that of
# Debian 12's clang-format 14; other major versions lay some constructs out differently, so the
# check skips with a message under them rather than failing on their taste.
#   bash scripts/check_format.sh [--fix]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
formatter=$(command -v clang-format-14 || command -v clang-format || true)
if [[ -z $formatter ]]; then
  echo "skipped: clang-format is not installed (Debian: apt-get install clang-format)"
  exit 77
fi
version=$("$formatter" --version)
if [[ $version != *"version 14."* ]]; then
  echo "skipped: $version; the tree is laid out by clang-format 14 (Debian 12)"
  exit 77
fi
if git rev-parse --is-inside-work-tree > /dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.cpp' '*.hpp')
else
  mapfile -t files < <(find base graph nodes plugins tests bench -name '*.cpp' -o -name '*.hpp' | sort)
fi
if [[ ${1:-} == --fix ]]; then
  "$formatter" -i "${files[@]}"
  exit 0
fi
# One run over every file; its warnings name each file that differs.
mapfile -t bad < <("$formatter" --dry-run "${files[@]}" 2>&1 | sed -n 's/^\([^:]*\):[0-9]*:[0-9]*: warning: code should be clang-formatted.*/\1/p' | sort -u)
if ((${#bad[@]})); then
  echo "${#bad[@]} of ${#files[@]} files differ from clang-format (fix: bash scripts/check_format.sh --fix):"
  printf '  %s\n' "${bad[@]}"
  exit 1
fi
echo "${#files[@]} files as clang-format writes them"
