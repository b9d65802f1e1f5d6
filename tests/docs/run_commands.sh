#!/usr/bin/env bash
# Runs, verbatim and in order, the shell commands that README.md, docs/programs.md and
# docs/quickstart.md tell a user to type after the README's first command, in a scratch
# directory with an empty out/:
# first the main job of scripts/demo.sh (what `bash scripts/demo.sh` runs once it has
# installed and built), then every ```sh block of README.md, of docs/programs.md, then of
# docs/quickstart.md.
# Skipped, because the test suite is itself their result: `bash scripts/...` (install + build
# + demo / test suite), `source scripts/configure.sh` with its `configure_for ...` and `cmake ...`
# (configure, build, install). Every other command must
# exit with 0, and what the docs say the commands write must be there.
#   run_commands.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
source_dir=$(cd "$1" && pwd) build_dir=$(cd "$2" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# The scratch checkout: the bundled data and docs, and build/release -> this build directory.
mkdir -p "$work/build"
ln -s "$source_dir/examples" "$work/examples"
ln -s "$source_dir/tests" "$work/tests"
ln -s "$build_dir" "$work/build/release"

# The commands of a file: the lines of its ```sh blocks (or of a script), backslash
# continuations joined, comments and blank lines dropped.
commands() {
  awk -v whole="$2" '
    whole == "script" || /^```sh/ { inside = 1; if (whole != "script") next }
    /^```/ { inside = 0; next }
    inside {
      line = $0
      sub(/[ \t]+#.*$/, "", line)
      if (line ~ /^[ \t]*#/ || line ~ /^[ \t]*$/) next
      if (line ~ /\\$/) { sub(/\\$/, "", line); pending = pending line; next }
      print pending line
      pending = ""
    }' "$1"
}

# run_file FILE [KIND [MIN]]: KIND script (the whole file) or docs (its ```sh blocks); at least
# MIN commands (default 1) must be found.
run_file() {
  local file=$1 kind=${2:-docs} min=${3:-1} n=0
  while IFS= read -r cmd; do
    case "$cmd" in
      "bash scripts/"* | "source scripts/"* | configure_for\ * | cmake* | set\ * | cd\ * | echo\ *)
        echo "skip ($file): $cmd"; continue ;;
    esac
    n=$((n + 1))
    echo "run ($file): $cmd"
    (cd "$work" && bash -c "$cmd") >"$work/log" 2>&1 || { cat "$work/log" >&2; fail "$file: $cmd"; }
  done < <(commands "$source_dir/$file" "$kind")
  [ "$n" -ge "$min" ] || fail "$n commands found in $file, expected at least $min"
}

run_file scripts/demo.sh script
run_file README.md docs 0  # today only the two scripts, which are skipped
run_file docs/programs.md
run_file docs/quickstart.md

# What the docs promise those commands write.
for f in out/demo/results.csv out/demo/model.yaml out/demo/decisions.csv out/lawnmower-3.0/result.json \
  out/model.yaml out/adaptive/result.json out/eval/results.csv out/road/results.csv \
  out/live-images/area.yaml out/live/map.png out/my-field-15/map.tif out/my-field-15/mission.plan; do
  [ -s "$work/$f" ] || fail "missing $f"
done
echo "ok: the commands of README.md, docs/programs.md and docs/quickstart.md run in order"
