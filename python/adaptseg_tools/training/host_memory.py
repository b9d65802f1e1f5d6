"""The C library's handling of freed memory, for training on the CPU (train_segnet.py
--keep-freed-memory). Imports nothing but ctypes, so that it is tested without PyTorch
(python/tests/test_host_memory.py).
"""

from __future__ import annotations

import ctypes


def keep_freed_memory() -> bool:
    """Has glibc's malloc keep what the process frees for its next allocations instead of handing it
    back to the kernel: no allocation served by its own mmap (M_MMAP_MAX 0), the heap's top never
    trimmed (M_TRIM_THRESHOLD -1; mallopt(3)). Returns False where the C library has no mallopt
    or refuses it (musl, macOS, Windows: nothing changes).

    A training step on the CPU allocates and frees activations of hundreds of MB (batch 32 at
    512x384: 200 MB a layer at stride 2). glibc serves every allocation above its mmap threshold,
    which grows to at most 32 MB, by mmap and returns it with munmap, so each step faults every
    page of them in again. On the 2-core VM, whose page faults are slow (paravirtualised), the
    MobileNetV2 recipe spent about 40 % of its CPU time in the kernel at about 100,000 faults a
    second and ran at 2 to 5 images a second; kept, at about 440 faults a second and 13.6 to 15.3
    images a second, with a resident set of 5.3 GB instead of 3.2 GB (docs/benchmarks.md,
    "Training on the CPU"). The numbers computed do not change. Data workers forked afterwards
    inherit the setting."""
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError, TypeError):
        return False
    m_trim_threshold, m_mmap_max = -1, -4
    return bool(mallopt(m_mmap_max, 0)) and bool(mallopt(m_trim_threshold, -1))
