"""The command line of the experiments' driver (scripts/results.sh runs it after the build).

  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.experiments [--dry-run | --check]
      [--runs scripts/results.toml] [PART] [JOBS]

PART (default all) as scripts/results.toml lists them, JOBS runs at a time (default: one per
core). --dry-run prints every command instead, one per line in order (`wait` after each batch
of parallel runs; the tables' folder lists as the files stand now). --check expands the part
and checks what it needs, and runs nothing. The knobs (CONFIG, EXTRA, NETS, ...) come from the
environment. Run from the repository root: every path is relative to it.
"""

from __future__ import annotations

import argparse
import os
import sys
import textwrap

from adaptseg_tools.experiments.plan import CatalogError, expand
from adaptseg_tools.experiments.runner import run_plan

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    tomllib = None

USAGE = "bash scripts/results.sh [PART] [JOBS]   (default: all, one job per core)"


def load(path: str) -> dict:
    if tomllib is None:
        raise CatalogError(f"reading {path} needs Python 3.11 or later (tomllib); Debian's /usr/bin/python3 is one")
    try:
        with open(path, "rb") as f:
            catalog = tomllib.load(f)
    except FileNotFoundError:
        raise CatalogError(f"no {path}: run from the repository root, or give --runs") from None
    except tomllib.TOMLDecodeError as e:
        raise CatalogError(f"{path}: {e}") from None
    if not isinstance(catalog.get("parts"), dict) or not catalog["parts"]:
        raise CatalogError(f"{path}: no [parts.NAME] tables")
    return catalog


def help_text(catalog: dict, path: str) -> str:
    """The usage and every part's description."""
    lines = [f"usage: {USAGE}", "       bash scripts/results.sh --help", "",
             f"The parts ({path}; every command of one, nothing run:",
             "PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.experiments --dry-run PART):"]
    for name, spec in catalog["parts"].items():
        lines += ["", name, textwrap.indent(spec.get("description", "").strip(), "  ")]
    return "\n".join(lines)


def positive(text: str) -> int:
    if not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f"JOBS must be a whole number >= 1, got '{text}'")
    return int(text)


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog="python3 -m adaptseg_tools.experiments", add_help=False,
                                 usage="%(prog)s [-h] [--dry-run | --check] [--runs FILE] [PART] [JOBS]")
    ap.add_argument("-h", "--help", action="store_true", help="the usage and every part's description")
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--dry-run", action="store_true", help="print every command instead of running it")
    mode.add_argument("--check", action="store_true", help="expand the part and check what it needs; run nothing")
    ap.add_argument("--runs", default="scripts/results.toml", help="the list of runs (default: %(default)s)")
    ap.add_argument("part", nargs="?", default="all")
    ap.add_argument("jobs", nargs="?", type=positive, default=os.cpu_count() or 2)
    args = ap.parse_args(argv)
    try:
        catalog = load(args.runs)
        if args.help:
            print(help_text(catalog, args.runs))
            return 0
        if args.part not in catalog["parts"]:
            print(f"results: unknown part '{args.part}'; the parts: {', '.join(catalog['parts'])}\n"
                  f"usage: {USAGE}  (--help: what each part flies)", file=sys.stderr)
            return 2
        plan = expand(catalog, args.part, os.environ, args.jobs)
    except CatalogError as e:
        print(f"results: {e}", file=sys.stderr)
        return 2
    if args.check:
        if plan.missing:
            print("\n".join(plan.missing), file=sys.stderr)
            return 1
        return 0
    return run_plan(plan, args.jobs, dry_run=args.dry_run)


if __name__ == "__main__":
    try:
        raise SystemExit(main(sys.argv[1:]))
    except BrokenPipeError:  # the output piped into a reader that stopped (`--help | head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        raise SystemExit(1)
