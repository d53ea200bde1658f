"""The C allocator's settings for a process that runs the workbench's numerics.

A diagnosis allocates and frees thousands of arrays of 0.1-10 MB (designs, fold
products, periodogram lattices). glibc serves each of them from a fresh
``mmap`` above its threshold (128 KiB at start, raised only as large blocks are
freed), so every one costs page faults on first touch - about a quarter of a
cold 10,000-reading diagnosis on a 2-core VM. Serving them from the heap, and
keeping freed heap memory for the next array, removes that cost; the peak
resident memory is unchanged (the same arrays are alive at the peak).

Only the command line and the monitor's search worker call this, at start: a
library must not change its host process's allocator.
"""
from __future__ import annotations

import ctypes

#: mallopt parameters (glibc's malloc.h).
_M_TRIM_THRESHOLD, _M_TOP_PAD, _M_MMAP_THRESHOLD = -1, -2, -3
#: Arrays below this come from the heap [bytes] (glibc's own ceiling is 32 MiB on 64-bit).
MMAP_THRESHOLD_BYTES = 32 * 2 ** 20
#: Freed heap memory kept for reuse up to this much [bytes] before it goes back.
TRIM_THRESHOLD_BYTES = 256 * 2 ** 20
#: Extra heap asked for on each growth [bytes] (address space; pages come on use).
TOP_PAD_BYTES = 64 * 2 ** 20


def keep_freed_arrays() -> bool:
    """Serve numpy's large temporaries from a heap that keeps freed memory (glibc only).

    Returns True when the settings took (False on another C library: nothing changes).
    """
    try:
        # The process's own symbols hold the C library's (no library search at start-up:
        # ctypes.util costs more than the rest of this module).
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    mallopt.restype = ctypes.c_int
    return all(mallopt(parameter, value) == 1 for parameter, value in (
        (_M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES),
        (_M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES),
        (_M_TOP_PAD, TOP_PAD_BYTES)))
