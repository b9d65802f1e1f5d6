#!/usr/bin/env python3
"""Validates adaptseg field directories against the field format (docs/data_format.md).

Usage: /usr/bin/python3 examples/tools/check_field.py DIR [DIR ...]
Exit code 0 if every field is valid; prints a summary line per field, or the first problem.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fieldio import check_field  # noqa: E402


def main(dirs):
    ok = True
    for d in dirs:
        try:
            s = check_field(d)
        except ValueError as e:
            print(f"INVALID {d}: {e}")
            ok = False
            continue
        fr = ", ".join(f"{k} {v:.4f}" for k, v in s["fractions"].items())
        print(f"ok {d}: {s['name']} {s['width']}x{s['height']} px at {s['gsd_cm']} cm/px, "
              f"{s['valid']} valid px, {s['ignore']} ignore px; {fr}")
    return 0 if ok else 1


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1:]))
