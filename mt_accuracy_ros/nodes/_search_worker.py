"""The model monitor's search worker: a process apart from the node, idle class first.

ROS-free (the worker process imports only the engine, not rclpy).
"""
from __future__ import annotations

from ..core.errors import MtAccuracyError
from ..core.workbench.diagnosis import Observations, diagnose
from ..core.workbench.refit import refit_effects, refittable_effects


#: Scheduling of the search worker process. The search takes a core for as long as it
#: runs, in a process of its own: the monitor node keeps its GIL for the readings, and
#: the compensation path (encoder -> estimator -> broadcaster -> CNC) is other
#: processes. By default the worker runs at normal priority: measured
#: (docs/benchmarks.md), an idle-class or niced search changed the path's p99 by
#: less than the run-to-run spread, while with two CPU burners a niced one made no
#: check at all in the demo's 90 s.
#:
#: ``MT_ACCURACY_SEARCH_IDLE_S`` > 0: a search starts in the idle scheduling class
#: (SCHED_IDLE: CPU time nothing else wants; any waking node preempts it) and is put
#: back in the normal class after that many wall seconds - which needs CAP_SYS_NICE
#: (or RLIMIT_NICE): an unprivileged thread cannot leave the idle class, so without
#: it a search stays idle (said once on the worker's stderr).
#: ``MT_ACCURACY_SEARCH_NICE``: the worker's niceness (0-19).
SEARCH_IDLE_S = 0.0
SEARCH_NICENESS = 0
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
    except (OSError, AttributeError) as exc:
        global _WARNED
        if not _WARNED:
            import sys

            _WARNED = True
            print(f"search worker: cannot change its scheduling ({exc}); it keeps the class "
                  "it has", file=sys.stderr)
        return False


_WARNED = False


def check(model, obs: Observations, min_reduction: float, max_effects: int,
          gate_refit: bool = False):
    """:func:`diagnose`, and - when the model holds fitted effects - their refit on the
    same readings (:func:`refit_effects`), carried as ``diagnosis.refit`` (None when
    there is nothing to refit). With ``gate_refit`` (the node would make a recommended
    refit live at once), the controller gate's verdict on it too (``refit.gate_problem``)."""
    import time

    started_wall, started_cpu = time.perf_counter(), time.process_time()
    diagnosis = diagnose(model, obs, min_reduction=min_reduction, max_effects=max_effects)
    if refittable_effects(model):
        try:
            diagnosis.refit = refit_effects(model, obs, min_reduction=min_reduction)
        except MtAccuracyError:
            diagnosis.refit = None
        refit = diagnosis.refit
        if gate_refit and refit is not None and refit.recommended:
            from ..core.compensation.limits import gate_problem

            refit.gate_problem = gate_problem(refit.apply(model, obs))
    # What the check cost, for /diagnostics: wall [s] and this process' CPU [s] (their
    # gap is the time other processes held the cores).
    diagnosis.search_wall_s = time.perf_counter() - started_wall
    diagnosis.search_cpu_s = time.process_time() - started_cpu
    return diagnosis


def search(model, obs: Observations, min_reduction: float, max_effects: int,
           gate_refit: bool = False):
    """The monitor's check (:func:`check`) - in the worker process, idle class first."""
    import threading

    if _WORKER_SCHEDULING is None or _WORKER_SCHEDULING[0] <= 0:
        return check(model, obs, min_reduction, max_effects, gate_refit)
    idle_s, niceness = _WORKER_SCHEDULING
    me = threading.get_native_id()
    _set_thread_scheduling(me, True, niceness)
    promote = threading.Timer(idle_s, _set_thread_scheduling, (me, False, niceness))
    promote.daemon = True
    promote.start()
    try:
        return check(model, obs, min_reduction, max_effects, gate_refit)
    finally:
        promote.cancel()
        _set_thread_scheduling(me, False, niceness)


def search_serialized(inputs: bytes, min_reduction: float, max_effects: int,
                      gate_refit: bool = False):
    """:func:`search` of pickled (model, observations): the monitor pickles them once, to
    know they can go to the worker, and the pool then only copies the bytes."""
    import pickle

    model, obs = pickle.loads(inputs)   # noqa: S301 - our own monitor's bytes
    return search(model, obs, min_reduction, max_effects, gate_refit)


def _search_worker(idle_s: float, niceness: int) -> None:
    import os

    global _WORKER_SCHEDULING
    from ..allocator import keep_freed_arrays

    # Searches allocate and free arrays of megabytes: from the heap, not fresh pages.
    keep_freed_arrays()
    # Import the engine now (at the caller's priority), not at the first check.
    from ..core.workbench import diagnosis  # noqa: F401

    if niceness > 0:
        try:
            os.nice(niceness)
        except OSError:
            pass
    # The niceness a promoted search thread takes: the process' own (the caller's + ours).
    _WORKER_SCHEDULING = (idle_s, os.nice(0))


def search_pool():
    """One spawned worker process for the searches, or a thread where processes cannot
    be made."""
    import multiprocessing
    import os
    from concurrent.futures import ProcessPoolExecutor

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
        return pool
    except (OSError, ValueError, NotImplementedError) as exc:
        return thread_fallback("diagnosis", "the diagnosis", "a long search now competes "
                               "with the node's callbacks", exc)


def thread_fallback(name: str, what: str, consequence: str, error: Exception):
    """A one-thread executor standing in for a worker process that could not start, with
    ``fallback_reason``: said, not silent, so that a search that ran slower than planned is
    explained - the node puts it on /diagnostics as a WARN."""
    from concurrent.futures import ThreadPoolExecutor

    pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix=name)
    pool.fallback_reason = (f"{what} runs in a thread of the node, not in its own process "
                            f"(the worker could not start: {error}): {consequence}")
    return pool
