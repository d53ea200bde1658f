"""The model monitor's search worker: a process apart from the node, idle class first.

ROS-free (the worker process imports only the engine, not rclpy).
"""
from __future__ import annotations

from ..core.workbench.diagnosis import Observations, diagnose


#: Scheduling of the search worker process. The search takes a core for as long as it
#: runs; the compensation path (encoder -> estimator -> broadcaster -> CNC) wakes every
#: batch and must not wait for it. So a search starts in the idle scheduling class
#: (SCHED_IDLE: it runs only on CPU time nothing else wants, and any waking node
#: preempts it at once). Measured (docs/benchmarks.md): a niced search still added
#: 10-20 ms to the compensation path's p99; an idle-class one nothing measurable.
#: Beside CPU burners an idle-class search would never finish, so one still running
#: after ``SEARCH_IDLE_S`` of wall time (environment ``MT_ACCURACY_SEARCH_IDLE_S``;
#: 0: never idle) continues as a normal process at niceness ``SEARCH_NICENESS``
#: (``MT_ACCURACY_SEARCH_NICE``).
SEARCH_IDLE_S = 5.0
SEARCH_NICENESS = 10
#: The worker's scheduling, set by its initializer: (idle seconds, niceness).
_WORKER_SCHEDULING: tuple[float, int] | None = None


def _set_thread_scheduling(thread_id: int, idle: bool, niceness: int) -> bool:
    """Put one thread in the idle class, or back in the normal one at ``niceness``."""
    import os

    try:
        if idle:
            os.sched_setscheduler(thread_id, os.SCHED_IDLE, os.sched_param(0))
        else:
            os.sched_setscheduler(thread_id, os.SCHED_OTHER, os.sched_param(0))
            os.setpriority(os.PRIO_PROCESS, thread_id, niceness)
        return True
    except (OSError, AttributeError):
        return False


def search(model, obs: Observations, min_reduction: float, max_effects: int):
    """The monitor's check, :func:`diagnose` - in the worker process, idle class first."""
    import threading

    if _WORKER_SCHEDULING is None or _WORKER_SCHEDULING[0] <= 0:
        return diagnose(model, obs, min_reduction=min_reduction, max_effects=max_effects)
    idle_s, niceness = _WORKER_SCHEDULING
    me = threading.get_native_id()
    _set_thread_scheduling(me, True, niceness)
    promote = threading.Timer(idle_s, _set_thread_scheduling, (me, False, niceness))
    promote.daemon = True
    promote.start()
    try:
        return diagnose(model, obs, min_reduction=min_reduction, max_effects=max_effects)
    finally:
        promote.cancel()
        _set_thread_scheduling(me, False, niceness)


def _search_worker(idle_s: float, niceness: int) -> None:
    import os

    global _WORKER_SCHEDULING
    if niceness > 0:
        try:
            os.nice(niceness)
        except OSError:
            pass
    # The niceness a promoted search thread takes: the process' own (the caller's + ours).
    _WORKER_SCHEDULING = (idle_s, os.nice(0))
    # Import the engine now, not at the first check.
    from ..core.workbench import diagnosis  # noqa: F401


def search_pool():
    """(executor, niceness): one spawned worker process for the searches, or a thread
    where processes cannot be made."""
    import multiprocessing
    import os
    from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

    try:
        niceness = min(19, max(0, int(os.environ.get("MT_ACCURACY_SEARCH_NICE",
                                                     SEARCH_NICENESS))))
    except ValueError:
        niceness = SEARCH_NICENESS
    try:
        idle_s = max(0.0, float(os.environ.get("MT_ACCURACY_SEARCH_IDLE_S", SEARCH_IDLE_S)))
    except ValueError:
        idle_s = SEARCH_IDLE_S
    if not idle_s < 1e6:   # inf, nan
        idle_s = SEARCH_IDLE_S
    try:
        pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"),
                                   initializer=_search_worker, initargs=(idle_s, niceness))
        pool.submit(int)   # start the worker and its imports now
        return pool, niceness
    except (OSError, ValueError, NotImplementedError):
        return ThreadPoolExecutor(max_workers=1, thread_name_prefix="diagnosis"), 0
