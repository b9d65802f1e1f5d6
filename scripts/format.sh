#!/usr/bin/env bash
# Formats every C++ file of the repository with the house .clang-format (Debian's clang-format
# 14: another version formats some constructs differently, so the check asks for this one).
#   scripts/format.sh          rewrites the files in place
#   scripts/format.sh --check  changes nothing; lists each file that is not formatted, exit 1 if any
set -euo pipefail
cd "$(dirname "$0")/.."
fmt=$(command -v clang-format-14 || true)
if [ -z "$fmt" ]; then
  echo "format.sh: clang-format-14 not found (Debian: apt-get install clang-format, or bash scripts/deps.sh test)" >&2
  exit 77
fi
mapfile -d '' files < <(git ls-files -z '*.hpp' '*.cpp' '*.h' '*.cc' 2>/dev/null ||
                        find include examples tests benchmarks fuzz -name node_modules -prune -o \
                             \( -name '*.hpp' -o -name '*.cpp' -o -name '*.h' -o -name '*.cc' \) -print0)
[ ${#files[@]} -gt 0 ] || { echo "format.sh: no C++ files found" >&2; exit 1; }
case "${1:-}" in
  "") "$fmt" -i --style=file "${files[@]}" ;;
  --check)
    # One process for every file (one per file cost 29 s of the 2-core VM's CPU, most of it
    # starting clang-format 226 times); only where that fails, file by file to name them.
    if "$fmt" --style=file --dry-run -Werror "${files[@]}" >/dev/null 2>&1; then
      echo "format.sh: ${#files[@]} files formatted"
      exit 0
    fi
    bad=()
    for f in "${files[@]}"; do
      "$fmt" --style=file --dry-run -Werror "$f" >/dev/null 2>&1 || bad+=("$f")
    done
    if [ ${#bad[@]} -gt 0 ]; then
      printf 'not formatted: %s\n' "${bad[@]}" >&2
      echo "format.sh: ${#bad[@]} of ${#files[@]} files differ from .clang-format; run bash scripts/format.sh" >&2
      exit 1
    fi
    echo "format.sh: ${#files[@]} files formatted" ;;
  *) echo "usage: $0 [--check]" >&2; exit 2 ;;
esac
