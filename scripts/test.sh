#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite in two builds: a Release build
# with warnings as errors (the library, the example programs and benchmarks; the doctest suites
# are not compiled there), and a Debug build under AddressSanitizer + UndefinedBehaviorSanitizer
# (every test and every example program compiled with them). Each test runs in one phase: the
# doctest suites, the programs' CLI tests and the MAVLink peers sanitized; the package, doxygen,
# snippet, header-alone, lint and Python tests, which build or run nothing sanitized, and
# docs:commands, which runs the Release programs on the CLI tests' paths, in Release.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh test
jobs=$(nproc 2>/dev/null || echo 2)
# node-mavlink, pinned in tests/mavlink/package-lock.json: the peer that mavlink:node_peer checks
# adaptseg::mavlink against, and the emulated autopilot of mavlink:emulator (a test peer, never a
# library dependency). Without npm the tests are skipped, and say so.
if command -v npm >/dev/null; then
  (cd tests/mavlink && npm ci --no-audit --no-fund --loglevel=error)
fi

source scripts/configure.sh
# Without the doctest suites and the MAVLink test programs (ADAPTSEG_TEST_SUITES=OFF): this phase
# runs none of them, the sanitized one below builds and runs them.
configure_for test build/release -DADAPTSEG_TEST_SUITES=OFF
cmake --build build/release -j"$jobs"
# --no-tests=error: a phase that found no test fails instead of passing. Each test runs once: the
# doctest suites (test_*:) and tests:discovered, the example programs' CLI tests (cli:*) and the
# MAVLink peers (mavlink:*) in the sanitized phase below, with the same code built with the
# sanitizers; here what builds or runs nothing sanitized (the package, doxygen, the snippets, the
# header-alone check, lint, the Python tools, docs:commands, which runs the Release programs on
# the CLI tests' paths). Run here too, the others cost this phase about 490 s of its 730 s of test
# time (2-core VM). `ctest` in a build folder runs every test it has (build/release after this
# script: all but the suites).
ctest --test-dir build/release --output-on-failure --no-tests=error -j"$jobs" \
  --exclude-regex '^(cli|mavlink):'

# -g1: line tables only, enough for file:line in sanitizer stack traces; full -g cost the
# sanitized build ~12 % more compile time (test_decision_function: 100 s against 88 s).
# -Og: test_calibration.cpp compiled with the sanitizers in 90 s and ran in 100 s, against 152 s
# and 82 s at -O1 and 74 s and 189 s at -O0 (2-core VM, one at a time); most of the phase is
# compiling.
cmake -S . -B build/asan -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS="-Og" -DCMAKE_CXX_FLAGS_DEBUG="-g1" \
      -DADAPTSEG_WARNINGS_AS_ERRORS=ON -DADAPTSEG_SANITIZE=ON -DADAPTSEG_BUILD_TESTS=ON -DADAPTSEG_TEST_SUITES=ON -DADAPTSEG_BUILD_BENCHMARKS=OFF \
      -DADAPTSEG_BUILD_EXAMPLES=ON
cmake --build build/asan -j"$jobs"
# intercept_tls_get_addr=0: GCC 12's LeakSanitizer can take a dynamic TLS block of glibc 2.36 for an
# older glibc's and crash scanning it at exit ("Tracer caught signal 11", google/sanitizers#1322),
# depending on where the blocks land (adaptseg_calibrate's cross-fitting run began to after a change
# to the program's code, not to its TLS). Leaks on the heap, stacks, globals and static TLS are
# still found. clear_shadow_mmap_threshold=1 GiB: the shadow of a freed large buffer is cleared in
# place, not mapped afresh, so the next buffer there does not fault its shadow in again (the
# programs are bound by page faults under the sanitizers: one mission test 16.2 s -> 14.6 s,
# 0.84 M -> 0.77 M faults).
# One test more than cores: the MAVLink CLI test spends most of its time waiting for the emulated
# vehicle's real-time flights (504 s against 531 s for the phase at -j3 and -j2, 2-core VM).
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:intercept_tls_get_addr=0:clear_shadow_mmap_threshold=1073741824 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build/asan --output-on-failure --no-tests=error -j"$((jobs + 1))"
