#!/usr/bin/python3
"""adaptseg_tools.training.host_memory.keep_freed_memory (train_segnet.py --keep-freed-memory):
after it, memory that the process frees is reused by its next allocations instead of being
mapped and faulted in again. Each case runs in a fresh interpreter, which allocates a 128 MB
buffer, writes a byte on each of its pages and frees it, five times, and reports its minor page
faults over the five; exit 77 (skip) where the C library has no mallopt (not glibc).
"""

from __future__ import annotations

import os
import subprocess
import sys

CHILD = """
import os, resource, sys
from adaptseg_tools.training.host_memory import keep_freed_memory
if sys.argv[1] == "keep" and not keep_freed_memory():
    print("no-mallopt")
    sys.exit(0)
page = os.sysconf("SC_PAGE_SIZE")
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(5):
    a = bytearray(128 << 20)  # malloc'd, not advised to use huge pages (numpy's large arrays are)
    a[::page] = b"\\x01" * (len(a) // page)  # a byte written on every page
    assert a[-page] == 1
    del a
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def faults(mode: str) -> str:
    """The child's output: its minor faults over the five buffers, or "no-mallopt"."""
    return subprocess.run([sys.executable, "-c", CHILD, mode], check=True, capture_output=True,
                          text=True).stdout.strip()


def main() -> int:
    kept = faults("keep")
    if kept == "no-mallopt":
        print("skipped: this C library has no mallopt")
        return 77
    default = int(faults("default"))
    kept = int(kept)
    pages = 5 * (128 << 20) // os.sysconf("SC_PAGE_SIZE")
    print(f"minor faults over five 128 MB buffers: {default} by default, {kept} kept ({pages} pages in all)")
    # glibc's default maps each buffer afresh: every page of every buffer faults (163,840 faults
    # with 4 KiB pages, about 164,000 measured). Kept, only the first buffer's pages do (about
    # 32,800). Where the kernel backs all memory with transparent huge pages, both fault less, in
    # the same ratio.
    assert kept < 0.3 * pages, "kept, the later buffers should reuse the first one's pages"
    assert default > 3 * kept, "glibc's default should fault each buffer's pages again"
    return 0


if __name__ == "__main__":
    sys.exit(main())
