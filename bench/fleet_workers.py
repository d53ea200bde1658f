"""``mt-accuracy fleet`` throughput: 1 against 2 Dask worker processes (issue 42).

A plant of virtual machines (``--machines`` x ``--days`` bags of 240 reference
readings each, written by the simulator) is diagnosed by ``run_fleet`` on a local
cluster of 1 and of 2 worker processes, alternately, ``--repeats`` times each. The
baseline in the same run: the same machine-days checked one after the other in this
process (``check_bag`` in a loop, no Dask). Every run is printed, never the best:
machine-days per second from the first task submitted to the last result
(``tasks_s``), and the whole command's wall time with the cluster's start.

    .venv/bin/python -m bench.fleet_workers --machines 4 --days 4 --repeats 3
"""
from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path


def make_plant(root: Path, machines: int, days: int) -> list[Path]:
    from mt_accuracy_ros.sim.fleet import VirtualMachine, write_fleet

    drift = {"time_constant_s": 60, "rise_k": 4.0, "beta_m_per_k": [1.5e-6, 6.0e-6, 3.0e-6]}
    plant = [VirtualMachine(f"hmc-{k}", 100 + k, {"structural_thermal_drift": drift})
             for k in range(machines)]
    return write_fleet(root, plant, days)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--machines", type=int, default=4)
    parser.add_argument("--days", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)

    from mt_accuracy_ros.commands.check import check_bag
    from mt_accuracy_ros.commands.fleet import run_fleet

    with tempfile.TemporaryDirectory() as tmp:
        bags = make_plant(Path(tmp), args.machines, args.days)
        started = time.perf_counter()
        serial = [check_bag(bag, "demo", [], 3, "", 0.05)["baseline_rmse"] for bag in bags]
        serial_s = time.perf_counter() - started
        runs = {1: [], 2: []}
        for _ in range(args.repeats):
            for workers in (1, 2):
                started = time.perf_counter()
                summary = run_fleet([tmp], workers=workers, progress=False)
                wall = time.perf_counter() - started
                same = [d["rmse_m"] for r in [summary] for m in sorted(r["machines"])
                        for d in r["machines"][m]["days"]]
                difference = max(abs(a - b) / b for a, b in zip(same, serial))
                assert len(same) == len(serial) and difference < 1e-9, \
                    f"the fleet's figures differ from check's ({difference:.2g})"
                runs[workers].append({"tasks_s": summary["ran_on"]["tasks_s"], "wall_s": wall})
    tasks = len(bags)
    per_second = {w: [tasks / r["tasks_s"] for r in runs[w]] for w in runs}
    result = {
        "machine_days": tasks, "readings_per_day": 240, "repeats": args.repeats,
        "serial_in_process": {"seconds": serial_s, "machine_days_per_s": tasks / serial_s},
        "one_worker": {"machine_days_per_s": per_second[1],
                       "wall_s": [r["wall_s"] for r in runs[1]]},
        "two_workers": {"machine_days_per_s": per_second[2],
                        "wall_s": [r["wall_s"] for r in runs[2]]},
        "ratio_two_over_one_per_run": [b / a for a, b in zip(per_second[1], per_second[2])],
        "ratio_of_medians": statistics.median(per_second[2]) / statistics.median(per_second[1]),
        "figures_equal_to_check": "every day's RMS within 1e-9 relative, every run",
    }
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
