"""Shared fixtures. ROS traffic of a test run stays on this host and its own domain."""
from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

#: Two workers on two cores: each worker's linear algebra on one thread (OpenBLAS' pool
#: of one thread per core in each worker spun against the other's, a third of the
#: suite's CPU). Read by numpy when it loads, which no plugin has done yet: a user's
#: choice is kept. The node processes take one already (mt_accuracy_ros/nodes).
BLAS_IMPORTED_BEFORE = "numpy" in sys.modules
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")


def _blas_kernel() -> str | None:
    """The OpenBLAS kernel the seeded figures and the CLI's goldens were computed with:
    OpenBLAS picks its kernels by the CPU (an Intel with AVX-512 takes SkylakeX's, an AMD
    EPYC Zen's), and their sums round differently in the last bit, which a selection's
    near-tie or a printed digit can turn into another answer. Haswell's (AVX2 and FMA) run
    on every x86-64 CPU that has those; None elsewhere (another architecture, an older
    CPU), where the CPU's own are used and the report header says so."""
    try:
        flags = next((line for line in Path("/proc/cpuinfo").read_text().splitlines()
                      if line.startswith("flags")), "").split()
    except OSError:
        return None
    return "Haswell" if {"avx2", "fma"} <= set(flags) else None


_KERNEL = _blas_kernel()
if _KERNEL is not None:
    os.environ.setdefault("OPENBLAS_CORETYPE", _KERNEL)



def _domain_of_this_run() -> int:
    """A ROS domain of this test process's own: parallel workers of one run (pytest-xdist
    names them gw0, gw1, ...) share a parent, so each takes its parent's pair of domains
    plus its index - two workers never meet, whatever their pids."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")
    if worker.startswith("gw") and worker[2:].isdigit():
        return 20 + (os.getppid() % 20) * 4 + int(worker[2:]) % 4
    return 20 + os.getpid() % 80


# Every process started by the tests inherits these: a domain of its own so that
# two test runs (or a developer's demo) on one machine do not hear each other. A domain
# the user set is kept; one this file chose in pytest's main process (which xdist's
# workers inherit) is replaced by each worker's own.
if "ROS_DOMAIN_ID" not in os.environ or os.environ.get("MT_ACCURACY_TEST_DOMAIN") == \
        os.environ["ROS_DOMAIN_ID"]:
    os.environ["ROS_DOMAIN_ID"] = os.environ["MT_ACCURACY_TEST_DOMAIN"] = \
        str(_domain_of_this_run())
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
os.environ.setdefault("AMENT_PREFIX_PATH", sys.prefix)

REPO_ROOT = Path(__file__).resolve().parent.parent
# studies/ (outside the installed package) imports from the repository root.
if str(REPO_ROOT) not in sys.path:
    sys.path.insert(0, str(REPO_ROOT))
#: Third-party data the tests read, copied into the repository with its licences:
#: a clone needs nothing beside it.
DATA = REPO_ROOT / "data"


@pytest.fixture
def rclpy_context():
    """``rclpy.init(); yield; rclpy.shutdown()`` as in rclpy's own tests."""
    import rclpy

    rclpy.init()
    try:
        yield
    finally:
        rclpy.try_shutdown()


@pytest.fixture
def data_dir() -> Path:
    """The repository's ``data/`` folder (fl_thermal, rosbag2 samples)."""
    return DATA


#: Test files that take longest, longest first: they start first, so that parallel workers
#: (``-n 2``) do not end with one of them running alone (longest-first packing: the last
#: files to start are the shortest). The order of their wall times in a loaded
#: ``make test`` (docs/benchmarks.md, 2026-11-27, third session); the files not named
#: take seconds each and follow in collection order.
SLOWEST_FILES = (
    "test_demo_trunnion.py", "test_demo_5axis.py", "test_demo_vmc.py", "test_demo.py",
    "test_hidden_effects.py", "test_closed_loop.py", "test_check_log_runs.py",
    "test_catalogue_trials.py", "test_record_play.py", "test_model_tools.py",
    "test_bad_input.py", "test_graph.py", "test_check_cli.py", "test_thesis_results.py",
    "test_selection_issue28.py", "test_cli_golden.py", "test_fleet.py",
    "test_survey_conventions.py", "test_monitor_refit.py", "test_model_gate.py",
    "test_cnc_bridge.py", "test_lockstep.py", "test_controller_tables.py", "test_fuzz.py",
    "test_diagnosis.py", "test_tool_direction.py", "test_cartesian_surveys.py",
    "test_thermal_studies.py", "test_virtual_machine.py", "test_context_memo.py",
)


def pytest_collection_modifyitems(session, config, items):
    rank = {name: i for i, name in enumerate(SLOWEST_FILES)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


def pytest_report_header(config):
    """Say the test processes' BLAS threads, and whether numpy loaded before they were
    set (then the setting came too late for this process)."""
    late = " (numpy was loaded before: not applied here)" if BLAS_IMPORTED_BEFORE else ""
    kernel = os.environ.get("OPENBLAS_CORETYPE", "the CPU's own (seeded figures may differ)")
    return (f"BLAS threads per test process: {os.environ['OPENBLAS_NUM_THREADS']}; "
            f"OpenBLAS kernel: {kernel}{late}")
