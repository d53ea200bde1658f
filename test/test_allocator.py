"""The allocator setting of the command line and the search worker: freed arrays are
reused, not faulted in again (counted page faults, not time)."""
from __future__ import annotations

import platform
import subprocess
import sys

import pytest

from mt_accuracy_ros.allocator import keep_freed_arrays

CHILD = """
import resource, sys
import numpy as np
if sys.argv[1] == "tuned":
    from mt_accuracy_ros.allocator import keep_freed_arrays
    assert keep_freed_arrays()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(20):
    # Several arrays of megabytes alive together, then freed, as a selection step's are:
    # by default glibc hands the freed top of its heap back and faults it in again.
    alive = [np.ones(1_000_000) for _ in range(4)]
    del alive
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""

glibc = pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="glibc's mallopt")


def _faults(mode: str) -> int:
    out = subprocess.run([sys.executable, "-c", CHILD, mode], capture_output=True, text=True,
                         check=True, timeout=120)
    return int(out.stdout.strip())


@glibc
def test_the_setting_takes_and_can_be_repeated():
    assert keep_freed_arrays() and keep_freed_arrays()


@glibc
def test_freed_arrays_are_served_again_without_page_faults():
    # 20 x 4 x 8 MB = 156,000 pages touched. Kept, only the first round's 7,800 fault;
    # by default several rounds fault again (43,000 faults here).
    plain, tuned = _faults("plain"), _faults("tuned")
    assert tuned < 2 * 7800
    assert plain > 4 * tuned
