"""Whether the model monitor's checks kept up with the machine (the demo at a rate).

The monitor starts a check every ``check_every`` reference readings, one at a time;
a check still running when the next falls due postpones it. A check is **on time**
when it is published before the next is due: within ``check_every`` reading periods
of data time after the reading it ends with (its stamp).
"""
from __future__ import annotations

import numpy as np


def check_timeliness(stamps_s, arrivals_s, period_s: float) -> dict:
    """Each check's latency and whether it came before the next was due.

    Parameters
    ----------
    stamps_s : array_like, shape (K,)
        Data time of each check's last reading [s].
    arrivals_s : array_like, shape (K,)
        Data time at which the check was received [s] (wall time since the machine's
        start times the rate).
    period_s : float
        Data time between two checks when every one is on time [s]:
        ``check_every`` x the reference period.

    Returns
    -------
    dict
        ``checks``, ``late`` (latency above the period), ``period_s``, ``latency_s``
        (K,), ``latency_median_s`` and ``latency_max_s`` (NaN without checks).
    """
    stamps = np.asarray(stamps_s, float)
    arrivals = np.asarray(arrivals_s, float)
    if stamps.shape != arrivals.shape:
        raise ValueError(f"{stamps.size} check stamps but {arrivals.size} arrival times")
    if not period_s > 0:
        raise ValueError(f"the check period must be positive, not {period_s}")
    latency = arrivals - stamps
    return {"checks": int(latency.size), "late": int(np.sum(latency > period_s)),
            "period_s": float(period_s), "latency_s": [round(float(v), 3) for v in latency],
            "latency_median_s": float(np.median(latency)) if latency.size else float("nan"),
            "latency_max_s": float(np.max(latency)) if latency.size else float("nan")}


def timeliness_line(timing: dict, rate_factor: float) -> str:
    """One printed line: how late the checks came, in data and wall time."""
    if not timing["checks"]:
        return "model checks: none published"
    head = (f"model checks: {timing['checks']}, each published "
            f"{timing['latency_median_s']:.1f} s (median) and at most "
            f"{timing['latency_max_s']:.1f} s of data after its last reading "
            f"({timing['latency_max_s'] / rate_factor:.1f} s wall at {rate_factor:g}x); the "
            f"next is due {timing['period_s']:.1f} s after: ")
    cpu = timing.get("search_cpu_s") or []
    tail = (f"; each search took {np.median(cpu):.2f} s of CPU (median; at most "
            f"{max(cpu):.2f} s) in {np.median(timing['search_wall_s']):.2f} s wall"
            if cpu else "")
    if timing["late"]:
        return head + f"{timing['late']} of {timing['checks']} LATE (the next was " \
            f"postponed){tail}"
    return head + "every check on time" + tail
