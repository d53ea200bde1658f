"""Every node process runs its linear algebra on one thread unless the user chose
otherwise (``mt_accuracy_ros/nodes/__init__.py``): BLAS pools spinning in many processes
held the cores a graph on a small machine needs."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PROBE = ("import mt_accuracy_ros.nodes as n, os, numpy; "
         "print(','.join(os.environ[v] for v in n.BLAS_THREAD_VARIABLES))")


def _run(extra: dict) -> str:
    env = {k: v for k, v in os.environ.items()
           if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}
    env.update(extra, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True,
                          text=True, check=True, timeout=120).stdout.strip()


def test_a_node_process_takes_one_blas_thread_and_keeps_a_users_choice():
    assert _run({}) == "1,1,1"
    assert _run({"OPENBLAS_NUM_THREADS": "2"}) == "2,1,1"


def test_every_node_module_lives_in_that_package():
    # python -m mt_accuracy_ros.nodes.<node> (and each console script) runs the package's
    # __init__ before the node module imports numpy.
    from mt_accuracy_ros.commands.processes import NODE_MODULES

    assert NODE_MODULES and all(m.startswith("mt_accuracy_ros.nodes.")
                                for m in NODE_MODULES.values())
