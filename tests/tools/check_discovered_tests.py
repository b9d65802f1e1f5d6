#!/usr/bin/python3
"""Every doctest case runs under CTest, exactly once, and every CTest entry of a doctest binary
runs exactly one case.

CMake's doctest discovery turns each TEST_CASE into a CTest entry that runs the binary with
`--test-case=NAME`. A name CMake cannot carry (a ';' splits it into two entries) gives entries
whose filter matches nothing, and doctest exits 0 having run nothing: the case's assertions
pass without running. This check asks CTest for its entries (`ctest --show-only=json-v1`) and,
for each doctest binary, doctest for its own list of cases (`--list-test-cases`), and fails
unless

  - each entry's own command, with `--count` added, counts exactly one case, and
  - each case the binary lists has an entry named PREFIX + case (PREFIX: the binary's name and
    ':', as tests/CMakeLists.txt discovers them).

An entry whose filter is a plain name (none of doctest's filter characters `*`, `?`, `,` and
`\\`, nor `;`; a comma escaped as discovery escapes it, `\\,`, stands for the name's comma) is
counted from the binary's own list, as doctest matches such a filter: the cases equal to it,
ignoring the case of ASCII letters. Every other entry, and of each binary the first plain entry
and the first with an escaped comma (which check that reading of doctest), is counted by running
it: a process per entry under the sanitizers cost the check about 190 s of CI's 2-core VM.

Usage: check_discovered_tests.py CTEST BUILD_DIR
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from collections import Counter
from pathlib import Path


def run(cmd: list[str], cwd: str | None = None) -> str:
    done = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} exited with {done.returncode}:\n{done.stdout}{done.stderr}")
    return done.stdout


def listed_cases(binary: str) -> list[str]:
    """The case names doctest lists, one per line between its two separator lines."""
    out = run([binary, "--list-test-cases", "--no-version"])
    lines = [line for line in out.splitlines() if line and not line.startswith("[doctest]")]
    return [line for line in lines if not re.fullmatch(r"=+", line)]


def counted(command: list[str], cwd: str | None) -> int:
    out = run(command + ["--count"], cwd)
    m = re.search(r"unskipped test cases passing the current filters: (\d+)", out)
    if not m:
        raise SystemExit(f"{' '.join(command)} --count printed no count:\n{out}")
    return int(m.group(1))


SPECIAL = re.compile(r"[*?,\\;]")


def plain_filter(command: list[str]) -> tuple[str, bool] | None:
    """The name a doctest entry's command filters on and whether it had an escaped comma, if
    the command is the binary and one plain `--test-case=NAME` and nothing else; None
    otherwise (the entry is then run)."""
    if len(command) != 2 or not command[1].startswith("--test-case="):
        return None
    escaped = command[1][len("--test-case="):]
    name = escaped.replace("\\,", ",")
    if not name or SPECIAL.search(escaped.replace("\\,", "")):
        return None
    return name, name != escaped


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    ctest, build = sys.argv[1], Path(sys.argv[2])
    entries = json.loads(run([ctest, "--test-dir", str(build), "--show-only=json-v1"]))["tests"]
    problems: list[str] = []
    by_binary: dict[str, list[str]] = {}
    plain: dict[str, list[tuple[str, str]]] = {}  # binary -> (entry, name) counted from its list
    canaries: set[tuple[str, bool]] = set()  # (binary, escaped comma) of the plain entries run
    for entry in entries:
        command = entry.get("command") or []
        if not any(arg.startswith("--test-case=") for arg in command):
            continue  # not a doctest case
        names = by_binary.setdefault(command[0], [])
        names.append(entry["name"])
        filtered = plain_filter(command)
        if filtered is not None:
            name, comma = filtered
            if (command[0], comma) in canaries:
                plain.setdefault(command[0], []).append((entry["name"], name))
                continue
            canaries.add((command[0], comma))
        cwd = next((p["value"] for p in entry.get("properties", []) if p["name"] == "WORKING_DIRECTORY"), None)
        n = counted(command, cwd)
        if n != 1:
            problems.append(f"CTest entry '{entry['name']}' runs {n} doctest cases, not 1")
    if not by_binary:
        problems.append("no CTest entry runs a doctest binary: discovery found nothing")
    for binary, names in sorted(by_binary.items()):
        prefix = Path(binary).name + ":"
        have = set(names)
        cases = listed_cases(binary)
        folded = Counter(case.encode().lower() for case in cases)  # doctest folds ASCII letters only
        for entry_name, name in plain.get(binary, []):
            n = folded.get(name.encode().lower(), 0)
            if n != 1:
                problems.append(f"CTest entry '{entry_name}' runs {n} doctest cases, not 1")
        if len(cases) != len(set(cases)):
            problems.append(f"{binary}: a case name is used twice")
        for case in cases:
            if prefix + case not in have:
                problems.append(f"doctest case '{case}' of {Path(binary).name} has no CTest entry '{prefix + case}'")
        print(f"{Path(binary).name}: {len(cases)} cases, {len(names)} CTest entries "
              f"({len(names) - len(plain.get(binary, []))} counted by running them)")
    for p in problems:
        print("FAIL:", p, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
