"""Validates adaptseg field directories against the field format (docs/data_format.md).

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.check_field DIR [DIR ...]
Exit code 0 if every field is valid; prints a summary line per field, or the first problem.
"""
import sys

from .fieldio import check_field


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
