#!/usr/bin/env bash
# Builds the API reference with docs/Doxyfile into OUT_DIR and fails on any doxygen warning.
#   tests/docs/run_doxygen.sh SOURCE_DIR OUT_DIR
# Exit 77 (CTest's SKIP_RETURN_CODE for docs:doxygen) if doxygen is not installed.
set -euo pipefail
src=$1 out=$2
command -v doxygen >/dev/null || { echo "doxygen not installed (scripts/deps.sh docs)"; exit 77; }
mkdir -p "$out"
cd "$src"
# The Doxyfile's paths are relative to the repository root; only the output directory differs.
# WARN_AS_ERROR = FAIL_ON_WARNINGS makes doxygen exit non-zero after listing every warning;
# the log is checked as well, so a doxygen that ignores the setting still fails.
status=0
{ cat docs/Doxyfile; echo "OUTPUT_DIRECTORY = $out"; echo "WARN_LOGFILE = $out/warnings.log"; } \
  | doxygen - || status=$?
if [ -s "$out/warnings.log" ]; then
  cat "$out/warnings.log" >&2
  echo "doxygen: $(grep -c 'warning:\|error:' "$out/warnings.log") warning(s), see above" >&2
  exit 1
fi
[ "$status" -eq 0 ] || { echo "doxygen failed (exit $status)" >&2; exit 1; }
echo "doxygen: 0 warnings; reference in $out/html/index.html"
