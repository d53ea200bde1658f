"""Thin rclpy nodes: each converts messages, calls the core and publishes.

Every node runs its linear algebra on one thread. A graph is many processes on a few
cores; a BLAS pool per process (as many threads as cores, spinning while it waits for
work) made each of them hold cores the others needed. Measured on the five-axis main
job at 3x real time on 2 cores (docs/benchmarks.md): with the pools, a check's search
took 0.64 s of CPU (median) and the corrections' p99 was 338-410 ms; on one thread,
0.22 s and 147 ms. Set ``OPENBLAS_NUM_THREADS`` (or ``OMP_NUM_THREADS``) yourself to
choose otherwise: a value already set is kept.
"""
import os as _os

#: The thread-count variables of the BLAS libraries numpy may be built with; read when
#: numpy loads, so set here, before any node module imports it.
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")

for _name in BLAS_THREAD_VARIABLES:
    _os.environ.setdefault(_name, "1")
