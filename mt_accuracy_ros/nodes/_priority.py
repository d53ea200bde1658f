"""CPU priority for the processes on the compensation path.

The path (scales -> estimator -> broadcaster -> CNC) has a deadline; everything
else on the host (the monitor's search, a recorder, a user's build) has none.
A node on the path may take a negative niceness (``niceness`` parameter): the
kernel's fair scheduler then gives it the CPU as soon as it wakes and ~99 % of
a core that others also want (weight 29,154 at -15 against 1,024 at 0), while
its own threads - the node's loop and the DDS threads that deliver its
messages - still share time fairly with each other.

Measured (docs/benchmarks.md, 20 kHz x 6 scales in 10 ms batches, a searching
monitor and two CPU burners): p99 stamp -> applied 555 ms at niceness 0, 32 ms
at -15. ``SCHED_FIFO`` was measured too and is not offered: a FIFO thread runs
until it blocks, so the node's loop and its own DDS threads at the same
priority starved each other (3,200-8,000 samples lost where normal scheduling
lost none).

A negative niceness needs ``CAP_SYS_NICE`` or an ``RLIMIT_NICE`` (``nice`` in
``/etc/security/limits.conf``, ``LimitNICE=`` of a systemd unit). Without it the
node says so on ``/diagnostics`` and runs at the niceness it has: nothing else
changes.
"""
from __future__ import annotations

import os

#: The range of a Linux niceness.
NICENESS_RANGE = (-20, 19)


def take_niceness(niceness: int) -> tuple[bool, str]:
    """Give every thread of this process ``niceness``.

    Threads started later inherit it from the thread that starts them (every
    thread of the process has it). ``niceness`` 0 leaves the process as it is.

    Returns
    -------
    (taken, text)
        Whether the process now runs at ``niceness``, and a line for
        ``/diagnostics`` saying what it runs at and, if it could not take it, why.
    """
    niceness = int(niceness)
    low, high = NICENESS_RANGE
    if not low <= niceness <= high:
        raise ValueError(f"niceness must be in {low}..{high}, got {niceness}")
    if niceness == 0:
        return False, f"niceness {os.getpriority(os.PRIO_PROCESS, 0)} (niceness parameter 0)"
    try:
        done = _set_every_thread(niceness)
    except PermissionError as exc:
        return False, (f"asked for niceness {niceness}, not permitted ({exc.strerror}: needs "
                       "CAP_SYS_NICE or an RLIMIT_NICE); running at niceness "
                       f"{os.getpriority(os.PRIO_PROCESS, 0)}")
    return True, f"niceness {niceness} ({done} threads)"


def leave_path_priority() -> None:
    """In a worker process a path node started (it inherits the node's niceness): back to
    niceness 0 on every thread - its work has no deadline and must not take the path's
    CPU. Raising a niceness needs no privilege."""
    if os.getpriority(os.PRIO_PROCESS, 0) < 0:
        _set_every_thread(0)


def _set_every_thread(niceness: int) -> int:
    """Set ``niceness`` on every thread of this process (Linux: a niceness is per thread,
    and ``PRIO_PROCESS`` with a thread id sets that thread's); how many were set."""
    try:
        threads = [int(tid) for tid in os.listdir("/proc/self/task")]
    except OSError:
        threads = [0]
    done = 0
    for tid in threads:
        try:
            os.setpriority(os.PRIO_PROCESS, tid, niceness)
            done += 1
        except ProcessLookupError:
            continue        # a thread that ended meanwhile
    return done


def declare_niceness(node, health) -> None:
    """The ``niceness`` parameter of a node on the compensation path (read-only, 0 = as
    started), taken at once; what the process runs at goes to
    ``health.notes['scheduling']`` and, when the niceness could not be taken, a WARN."""
    from ._common import int_descriptor

    low, high = NICENESS_RANGE
    node.declare_parameter("niceness", 0, int_descriptor(
        "Niceness of this process' threads (-20..19; negative = the CPU first when the "
        "host is loaded; 0 = as started). Negative needs CAP_SYS_NICE or an RLIMIT_NICE; "
        "without, the node warns and runs as it is", low, high, read_only=True))
    asked = int(node.get_parameter("niceness").value)
    taken, text = take_niceness(asked)
    health.notes["scheduling"] = text
    if asked and not taken:
        health.warn(text)
    else:
        node.get_logger().info(f"scheduling: {text}")
