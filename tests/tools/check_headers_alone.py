#!/usr/bin/python3
"""Every public header compiles alone: each translation unit of the header-alone check (one per
header, tests/CMakeLists.txt: the targets adaptseg_header_alone_<component>, which include the
header twice) parsed with the flags CMake gives it in compile_commands.json (its component's
include directories and definitions, the tests' warnings as errors), but by a compiler's front
end alone (-fsyntax-only): nothing to generate, since a header's unit defines nothing that is
called. COMPILER parses them where given (CMake gives Clang's front end where it finds one:
on the 2-core VM it parsed the 146 units in 369 s of CPU where GCC compiled them in about
588 s), each command's own compiler otherwise. Runs the units as many at a time as there are
CPUs; any output fails a unit (a warning too); prints each failure with the output, and a count.

Usage: check_headers_alone.py COMPILE_COMMANDS_JSON [COMPILER]
"""

from __future__ import annotations

import json
import os
import shlex
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

UNIT_DIR = "/header_alone/"


def syntax_only(entry: dict, compiler: str | None) -> list[str]:
    """The entry's command with its output dropped and -fsyntax-only instead of -c."""
    args = entry["arguments"] if "arguments" in entry else shlex.split(entry["command"])
    out = [compiler or args[0]]
    skip = False
    for a in args[1:]:
        if skip:
            skip = False
            continue
        if a == "-o":
            skip = True
            continue
        if a == "-c":
            continue
        out.append(a)
    return out + ["-fsyntax-only"]


def main() -> int:
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    db = Path(sys.argv[1])
    compiler = sys.argv[2] if len(sys.argv) > 2 and sys.argv[2] else None
    jobs = os.cpu_count() or 2
    entries = [e for e in json.loads(db.read_text(encoding="utf-8")) if UNIT_DIR in e["file"]]
    if not entries:
        print(f"{db}: no header-alone unit (no file under a {UNIT_DIR} folder)")
        return 1
    print(f"{len(entries)} headers, each alone, parsed by {compiler or 'the build compiler'}, {jobs} at a time")

    def check(entry: dict) -> tuple[str, int, str]:
        run = subprocess.run(syntax_only(entry, compiler), cwd=entry["directory"], capture_output=True, text=True)
        return entry["file"], run.returncode, run.stdout + run.stderr

    failed = 0
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        for unit, rc, output in pool.map(check, sorted(entries, key=lambda e: e["file"])):
            if rc != 0 or output.strip():
                failed += 1
                print(f"FAIL {Path(unit).name} (exit {rc}):\n{output}")
    print(f"{len(entries)} headers, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
