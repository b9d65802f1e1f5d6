#!/usr/bin/env bash
# Runs the house .clang-tidy checks on every public header of the library: one translation unit
# that includes every component's umbrella header (core, vision, erfnet, geo, gdal, mavlink, sim,
# planner.hpp), so each header is parsed once and its diagnostics reported where they are
# (HeaderFilterRegex). Debian's clang-tidy 14, which scripts/deps.sh test installs; exit 77
# (skipped) without it. Any diagnostic fails (WarningsAsErrors); a header that Clang cannot
# compile fails too.
#   scripts/tidy.sh
set -euo pipefail
cd "$(dirname "$0")/.."
tidy=$(command -v clang-tidy-14 || true)
if [ -z "$tidy" ]; then
  echo "tidy.sh: clang-tidy-14 not found (Debian: apt-get install clang-tidy, or bash scripts/deps.sh test)" >&2
  exit 77
fi
unit=$(mktemp --suffix=.cpp)
trap 'rm -f "$unit"' EXIT
flags=(-std=c++20 "-I$PWD/include" -isystem /usr/include/eigen3 -isystem /usr/include/opencv4)
for h in include/adaptseg/*.hpp; do
  [ "$h" = include/adaptseg/gdal.hpp ] && [ ! -d /usr/include/gdal ] && continue  # adaptseg::gdal needs GDAL
  echo "#include <${h#include/}>" >>"$unit"
done
[ -d /usr/include/gdal ] && flags+=(-isystem /usr/include/gdal -DADAPTSEG_HAVE_GDAL=1)
"$tidy" --quiet --config-file="$PWD/.clang-tidy" "$unit" -- "${flags[@]}"
echo "tidy.sh: $(grep -c include "$unit") umbrella headers checked"
