#!/usr/bin/env bash
# What a call to a lent accelerator (the `device` tool) carries, and room for it when the
# repository outgrows it: the call copies the tracked files and the untracked ones git does not
# ignore, plus the ignored paths it is told to carry, 64 MiB in all. The repository's tracked
# files alone reached 68.0 MB on 2026-12-04 (the bundled networks), so a training call
# (`bash scripts/loto.sh train`, which reads none of examples/models) goes with them set aside.
#   bash scripts/device_travel.sh size [CARRY...]
#       the bytes that would travel, with the carried paths CARRY (as the call's carry names
#       them, e.g. .device), against the limit, and the five largest files; exit 1 when over.
#   bash scripts/device_travel.sh aside [PATH...]
#       moves PATH (default examples/models) into .device-aside/ (never tracked: listed in
#       .git/info/exclude), so the call does not carry it; refused while an earlier aside is
#       not restored.
#   bash scripts/device_travel.sh restore
#       moves everything in .device-aside/ back where it was, refusing to overwrite a file that
#       has reappeared there, then checks that git misses no tracked file under what was set aside.
set -euo pipefail
cd "$(dirname "$0")/.."
limit=$((64 * 1024 * 1024))
aside=.device-aside
paths=.paths  # in $aside: what was set aside, one path a line

usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2; exit 2; }

# travelling: NUL-separated, every file the call carries without CARRY (tracked or untracked and
# not ignored, present in the work tree).
travelling() {
  git ls-files -z --cached --others --exclude-standard | while IFS= read -r -d '' f; do
    [ -f "$f" ] && [ ! -L "$f" ] && printf '%s\0' "$f"
  done
}

size() {
  local list total=0 carried=0 c b
  list=$(mktemp)
  trap 'rm -f "$list"' RETURN
  travelling | xargs -0 -r stat -c '%s %n' >"$list"
  total=$(awk '{ s += $1 } END { print s + 0 }' "$list")
  for c in "$@"; do
    [ -e "$c" ] || { echo "carry $c: no such path" >&2; return 2; }
    b=$(find "$c" -type f -printf '%s\n' | awk '{ s += $1 } END { print s + 0 }')
    carried=$((carried + b))
    echo "carry $c: $b bytes"
  done
  total=$((total + carried))
  echo "largest files of the work tree that travel:"
  sort -rn "$list" | awk 'NR <= 5 { printf "  %10d  %s\n", $1, substr($0, index($0, " ") + 1) }'
  awk -v t="$total" -v l="$limit" 'BEGIN { printf "travels: %d bytes (%.1f MiB) of %.0f MiB\n", t, t / 1048576, l / 1048576 }'
  if [ "$total" -gt "$limit" ]; then
    echo "over the limit by $((total - limit)) bytes: bash $0 aside [PATH...] first" >&2
    return 1
  fi
}

exclude_aside() {
  local exclude
  exclude=$(git rev-parse --git-path info/exclude)
  mkdir -p "$(dirname "$exclude")"
  grep -qx "/$aside/" "$exclude" 2>/dev/null || echo "/$aside/" >>"$exclude"
}

set_aside() {
  [ $# -gt 0 ] || set -- examples/models
  if [ -d "$aside" ] && [ -n "$(find "$aside" -mindepth 1 -print -quit)" ]; then
    echo "$aside/ holds an earlier aside: bash $0 restore first" >&2
    return 1
  fi
  local p
  for p in "$@"; do
    case "$p" in /* | *..*) echo "$p: a path inside the repository, relative to its root" >&2; return 2 ;; esac
    [ -e "$p" ] || { echo "$p: no such path" >&2; return 2; }
  done
  exclude_aside
  mkdir -p "$aside"
  for p in "$@"; do
    mkdir -p "$aside/$(dirname "$p")"
    mv "$p" "$aside/$p"
    printf '%s\n' "$p" >>"$aside/$paths"
    echo "aside: $p"
  done
}

restore() {
  [ -f "$aside/$paths" ] || { echo "nothing set aside ($aside/$paths is absent)"; return 0; }
  local f clash=0 p moved=0 missing=()
  while IFS= read -r -d '' f; do
    f=${f#"$aside"/}
    if [ -e "$f" ] && ! cmp -s "$aside/$f" "$f"; then
      echo "$f exists and differs from the one set aside: not overwritten" >&2
      clash=1
    fi
  done < <(find "$aside" -type f ! -path "$aside/$paths" -print0)
  [ "$clash" = 0 ] || return 1
  while IFS= read -r -d '' f; do
    f=${f#"$aside"/}
    mkdir -p "$(dirname "$f")"
    mv -f "$aside/$f" "$f"
    moved=$((moved + 1))
  done < <(find "$aside" -type f ! -path "$aside/$paths" -print0)
  while IFS= read -r p; do
    while IFS= read -r f; do missing+=("$f"); done < <(git ls-files --deleted -- "$p")
  done <"$aside/$paths"
  if [ ${#missing[@]} -gt 0 ]; then
    echo "tracked files under what was set aside still missing:" >&2
    printf '  %s\n' "${missing[@]}" >&2
    return 1
  fi
  rm -f "$aside/$paths"
  find "$aside" -depth -type d -empty -delete
  echo "restored $moved files; no tracked file under them missing"
}

case "${1:-}" in
size) shift; size "$@" ;;
aside) shift; set_aside "$@" ;;
restore) [ $# -eq 1 ] || usage; restore ;;
*) usage ;;
esac
