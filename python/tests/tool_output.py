"""Shared by the Python tools' self-tests (python/tests/test_*.py, run by CTest as scripts, so
this folder is on the import path): a tool's main() run in-process and what it printed; the
skip without torch and the failing check."""
import contextlib
import importlib.util
import io
import os
import sys
import tempfile


def require_torch():
    """Exits 77 (CTest's skip) where torch is not installed, saying so."""
    if importlib.util.find_spec("torch") is None:
        print("torch is not installed (Debian python3-torch): skipped")
        sys.exit(77)


def check(cond: bool, what: str):
    """Exits 1 with FAIL: what, where cond is false."""
    if not cond:
        print(f"FAIL: {what}")
        sys.exit(1)


def printed(main, argv):
    """(return value, standard output) of `main(argv)`."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = main(argv)
    return rc, out.getvalue()


def check_on_csv(main, csv_text, args, rows):
    """Writes `csv_text` to a temporary cells.csv, runs `main([path, *args])`, and exits naming
    the first of `rows` its output lacks (or its exit code, if not 0); returns the output."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "cells.csv")
        with open(path, "w") as f:
            f.write(csv_text)
        rc, text = printed(main, [path, *args])
    if rc != 0:
        sys.exit(f"exit code {rc}:\n{text}")
    for want in rows:
        if want not in text:
            sys.exit(f"no row {want}:\n{text}")
    return text


def two_class_log_probs(labels, sure):
    """2 x 1 x N log-probabilities of a hand-made row of pixels: each pixel's label (0 or 1) with
    probability `sure`, the other 1 − sure (two_looks' and scale_trend's hand-made fields)."""
    import numpy as np

    lab = np.array(labels)[None, :]
    p1 = np.where(lab == 1, sure, 1.0 - sure)
    return np.log(np.stack([1.0 - p1, p1])).astype(np.float32)


def check_refused(main, argv, reason, what):
    """Exits unless `main(argv)` exits with a message containing `reason` (`what`: what is refused)."""
    try:
        main(argv)
    except SystemExit as e:
        if reason not in str(e):
            sys.exit(f"unexpected refusal of {what}: {e}")
    else:
        sys.exit(f"{what} was not refused")
