# Shared by the command-line test scripts (sourced): a scratch directory removed on exit,
# fail, and expect_error. The caller sets $mission to the program under test.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# expect_error FRAGMENT ARGS...: exit code 2, exactly one stderr line containing FRAGMENT.
expect_error() {
  local fragment=$1; shift
  "$mission" "$@" >"$work/out" 2>"$work/err"
  local rc=$?
  [ "$rc" -eq 2 ] || fail "exit code $rc (want 2) for: $* ($(cat "$work/err"))"
  [ "$(wc -l <"$work/err")" -eq 1 ] || fail "want one error line for: $*, got: $(cat "$work/err")"
  grep -qF -- "$fragment" "$work/err" || fail "error for: $* lacks '$fragment': $(cat "$work/err")"
  echo "ok: $(cat "$work/err")"
}
