#!/usr/bin/env bash
# The README's commands, run in order on one checkout, each get what they need: one build folder
# configured as scripts/demo.sh, then scripts/test.sh, scripts/bench.sh and scripts/results.sh
# configure it (scripts/configure.sh), and after each the targets that script builds exist (and
# after test.sh's, its tests). Configures only (no build): about a minute.
#   test_scripts_configure.sh SOURCE_DIR
set -uo pipefail
source "$(dirname "$0")/cli_common.sh"
cd "$1" || fail "no source directory $1"
source scripts/configure.sh
dir="$work/build"
# has_targets PURPOSE TARGET...: configure as PURPOSE, then every TARGET is a build target.
has_targets() {
  local purpose=$1
  shift
  configure_for "$purpose" "$dir" >"$work/log" 2>&1 || fail "configure_for $purpose failed: $(tail -5 "$work/log")"
  cmake --build "$dir" --target help >"$work/targets" 2>&1 || fail "no target list after configure_for $purpose"
  for t in "$@"; do
    grep -qE "(^|[ .])$t($| )" "$work/targets" || fail "after configure_for $purpose: no target $t"
  done
  echo "ok: $purpose configures $*"
}
has_targets demo adaptseg_mission adaptseg_calibrate adaptseg_evaluate adaptseg_live
# The demo's configuration must not leave test.sh without tests.
has_targets test test_metrics test_calibration adaptseg_evaluate bench_decision
n=$(ctest --test-dir "$dir" -N | sed -n 's/^Total Tests: //p')
[ "${n:-0}" -gt 0 ] || fail "after configure_for test, ctest finds no test"
echo "ok: ctest lists $n tests before any build"
# test.sh builds the benchmarks to check them (-O0), bench.sh to time them: the option it cached
# must not follow them there.
grep -q '^ADAPTSEG_CHECK_BUILD:BOOL=ON$' "$dir/CMakeCache.txt" || fail "configure_for test: ADAPTSEG_CHECK_BUILD not on"
has_targets bench bench_gaussian_process bench_decision bench_erfnet bench_geotiff
grep -q '^ADAPTSEG_CHECK_BUILD:BOOL=OFF$' "$dir/CMakeCache.txt" ||
  fail "configure_for bench after test: the benchmarks still built to check, not to time"
has_targets results adaptseg_evaluate adaptseg_calibrate adaptseg_cell_study
# And the demo again, after all of them.
has_targets demo adaptseg_mission adaptseg_evaluate
echo "PASS"
