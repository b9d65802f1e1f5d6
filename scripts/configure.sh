# Sourced by the scripts that build in build/release (demo.sh, test.sh, bench.sh, results.sh):
# one function per script that configures a build folder with every option that script relies
# on, so that none depends on what another script cached in the folder before it (the demo's
# configuration once left build/release without tests, and test.sh then ran none).
# tests/cli/test_scripts_configure.sh configures one folder with all of them in the README's order.

# configure_for PURPOSE DIR [CMAKE ARGS...]: PURPOSE demo (the example programs), test (everything,
# warnings as errors, built to check and not to time: ADAPTSEG_CHECK_BUILD), bench (the
# benchmarks), results (the example programs).
configure_for() {
  local purpose=$1 dir=$2
  shift 2
  local -a opts=(-DCMAKE_BUILD_TYPE=Release -DADAPTSEG_SANITIZE=OFF -DADAPTSEG_BUILD_EXAMPLES=ON -DADAPTSEG_CHECK_BUILD=OFF)
  case "$purpose" in
    demo | results) ;;
    test) opts+=(-DADAPTSEG_BUILD_TESTS=ON -DADAPTSEG_TEST_SUITES=ON -DADAPTSEG_BUILD_BENCHMARKS=ON -DADAPTSEG_WARNINGS_AS_ERRORS=ON
                 -DADAPTSEG_CHECK_BUILD=ON) ;;
    bench) opts+=(-DADAPTSEG_BUILD_BENCHMARKS=ON) ;;
    *) echo "configure_for: unknown purpose '$purpose'" >&2; return 2 ;;
  esac
  cmake -S . -B "$dir" "${opts[@]}" "$@"
}
