#!/usr/bin/python3
"""No public header of the library is longer than LIMIT lines (450): a reader holds one file's
parts in mind. A header that grows past it is split into named parts (as adaptive_planner.hpp's
are in vision/detail/), not trimmed of its comments.

Usage: check_header_sizes.py SOURCE_DIR [LIMIT]
"""

from __future__ import annotations

import sys
from pathlib import Path


def main() -> int:
    root = Path(sys.argv[1])
    limit = int(sys.argv[2]) if len(sys.argv) > 2 else 450
    headers = sorted((root / "include").rglob("*.hpp"))
    if not headers:
        print(f"no headers under {root / 'include'}")
        return 1
    over = []
    for h in headers:
        with open(h, encoding="utf-8") as f:
            n = sum(1 for _ in f)
        if n > limit:
            over.append((n, h.relative_to(root)))
    for n, h in over:
        print(f"{h}: {n} lines, more than {limit}")
    print(f"{len(headers)} headers, {len(over)} over {limit} lines")
    return 1 if over else 0


if __name__ == "__main__":
    raise SystemExit(main())
