"""Run every benchmark (``make bench``); each prints JSON with its same-run baseline."""
from __future__ import annotations

import subprocess
import sys

BENCHES = [
    ["bench.knn_vs_sklearn"],
    ["bench.volumetric_map"],
    ["bench.volumetric_map", "--machine", "khan_chen_rpppr"],
    ["bench.bag_throughput"],
    ["bench.sim_speed"],
    ["bench.thesis_results"],
    ["bench.thermal_report"],
    ["bench.graph_throughput"],
    ["bench.fleet_workers"],
]


def main() -> int:
    failed = 0
    for args in BENCHES:
        print(f"== python -m {' '.join(args)}", flush=True)
        failed += subprocess.run([sys.executable, "-m", *args]).returncode != 0
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
