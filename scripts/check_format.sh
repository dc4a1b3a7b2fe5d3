#!/usr/bin/env bash
# Checks that every tracked C++/CUDA source is formatted as .clang-format (Google base) says.
# Exits non-zero and lists the badly formatted files (fix: clang-format -i FILE...).
# Then checks that every relative link and anchor in README.md and docs/*.md resolves
# (scripts/check_links.py; a broken link is listed as FILE:LINE and fails the check too), and
# that no tier includes what it must not (scripts/check_tiers.py: core <- planning <- ros).
# Usage: bash scripts/check_format.sh
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

CLANG_FORMAT="${CLANG_FORMAT:-clang-format}"
if ! command -v "$CLANG_FORMAT" >/dev/null 2>&1; then
  echo "check_format: $CLANG_FORMAT not found (bash scripts/install_deps.sh installs it)" >&2
  exit 2
fi

mapfile -t files < <(git ls-files -- '*.h' '*.hpp' '*.cpp' '*.cu' '*.cuh')
if [ "${#files[@]}" -eq 0 ]; then
  echo "check_format: no tracked C++/CUDA sources"
  exit 0
fi

bad=()
for f in "${files[@]}"; do
  [ -f "$f" ] || continue  # deleted in the working tree but still tracked
  if ! "$CLANG_FORMAT" --dry-run --Werror "$f" >/dev/null 2>&1; then
    bad+=("$f")
  fi
done

if [ "${#bad[@]}" -ne 0 ]; then
  echo "check_format: ${#bad[@]} of ${#files[@]} files are not clang-formatted:" >&2
  printf '  %s\n' "${bad[@]}" >&2
  echo "fix with: $CLANG_FORMAT -i <file>... (version: $("$CLANG_FORMAT" --version))" >&2
  exit 1
fi
echo "check_format: ${#files[@]} files OK ($("$CLANG_FORMAT" --version))"
/usr/bin/python3 scripts/check_links.py
# The tier check (DESIGN §12): core <- planning <- ros, by includes.
/usr/bin/python3 scripts/check_tiers.py
