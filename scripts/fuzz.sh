#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ with clang (ASan + UBSan) in build/fuzz and runs each
# for SECONDS (default 60) from its committed seed corpus. Fails on any finding: a crash, a
# sanitizer report, an undocumented exception, a timeout (> 10 s for one input) or an
# allocation over 1 GiB. Findings land in build/fuzz/findings/<target>/; new corpus entries
# in build/fuzz/corpus/<target>/ (the committed fuzz/corpus/ is only read).
#   scripts/fuzz.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
bash scripts/deps.sh fuzz
jobs=$(nproc 2>/dev/null || echo 2)

CC=clang CXX=clang++ cmake -S . -B build/fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DADAPTSEG_BUILD_FUZZERS=ON \
  -DADAPTSEG_BUILD_TESTS=OFF -DADAPTSEG_BUILD_EXAMPLES=OFF -DADAPTSEG_BUILD_BENCHMARKS=OFF >/dev/null
targets=(field_load decision_model_load gaussian_process_load wpl_read mavlink)
cmake --build build/fuzz -j"$jobs" --target "${targets[@]/#/fuzz_}"

status=0
for t in "${targets[@]}"; do
  mkdir -p "build/fuzz/corpus/$t" "build/fuzz/findings/$t"
  echo "== fuzz_$t for $seconds s"
  if ! UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 "build/fuzz/fuzz/fuzz_$t" \
      -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 \
      -print_final_stats=1 -artifact_prefix="build/fuzz/findings/$t/" \
      "build/fuzz/corpus/$t" "fuzz/corpus/$t" 2>"build/fuzz/fuzz_$t.log"; then
    echo "FINDING in fuzz_$t: see build/fuzz/fuzz_$t.log and build/fuzz/findings/$t/" >&2
    tail -n 40 "build/fuzz/fuzz_$t.log" >&2
    status=1
  fi
  grep -E "^(stat::number_of_executed_units|stat::peak_rss_mb|#[0-9]+ *DONE)" "build/fuzz/fuzz_$t.log" || true
done
exit "$status"
