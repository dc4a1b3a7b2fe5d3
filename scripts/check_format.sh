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

# Files that exist (a file deleted in the working tree may still be tracked), checked in batches
# of 40 on every core (one clang-format per file took a minute of CI); a batch that fails is
# checked file by file to name its badly formatted files.
present=()
for f in "${files[@]}"; do [ -f "$f" ] && present+=("$f"); done
export CLANG_FORMAT
check_batch() {
  "$CLANG_FORMAT" --dry-run --Werror "$@" >/dev/null 2>&1 && return 0
  for f in "$@"; do
    "$CLANG_FORMAT" --dry-run --Werror "$f" >/dev/null 2>&1 || echo "$f"
  done
}
export -f check_batch
mapfile -t bad < <(printf '%s\0' "${present[@]}" |
  xargs -0 -n 40 -P "$(nproc)" bash -c 'check_batch "$@"' check_batch | sort)

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
