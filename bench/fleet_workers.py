"""``mt-accuracy fleet`` throughput: 1 against 2 Dask worker processes (issues 42, 54).

A plant of at least 100 machine-days, half from the virtual machine and half from
surveys: ``--vm-machines`` x ``--days`` bags of 240 reference readings each (written by
the simulator, ``mt_accuracy_ros.sim.fleet``) and ``--survey-machines`` x ``--days``
logger surveys of ``--readings`` readings in the speed panel's shape (positions,
velocities, accelerations, spindle speed, four temperatures and a hidden ball-screw
pitch: ``studies.survey_files.write_panel_survey``), every other survey machine with
its description (the column map's ``machine: kidani_hmc``). ``run_fleet`` diagnoses
it on a local cluster of 1 and of 2 worker processes, alternately, ``--repeats`` times
each. Every run is printed, never the best:

* machine-days per second from the first task submitted to the last result
  (``tasks_s``), and the whole command's wall time with the cluster's start;
* the ratio 2 / 1 workers of each pair of runs;
* each task's time split as its worker measured it: ``reading`` (the files, the
  models, the check's assembly), ``search`` (the diagnoses), ``result`` (the compact
  result), and the workers' CPU time; what is left of workers x ``tasks_s`` beyond
  the tasks' own time is scheduling, serialisation, the client's gathering and the
  workers' idle tail (``overhead_s``);
* whether every day's figures are the same in every run (1e-9 relative).

``--serial`` also checks every task in this process one after another (no Dask), the
baseline of issue 42's bench.

    PYTHONPATH=. .venv/bin/python -m bench.fleet_workers --repeats 2
"""
from __future__ import annotations

import os

# One BLAS thread per process: the workers inherit it (two workers on two cores).
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import argparse  # noqa: E402
import datetime as dt  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import yaml  # noqa: E402


def make_plant(root: Path, vm_machines: int, survey_machines: int, days: int,
               readings: int) -> dict[str, int]:
    """Bags of virtual machines and surveys of surveyed machines under ``root`` (a folder
    per machine); how many machine-days of each kind."""
    from mt_accuracy_ros.sim.fleet import FIRST_DAY, VirtualMachine, write_fleet
    from studies.foreign_machine import make_trial
    from studies.survey_files import write_panel_survey

    drift = {"time_constant_s": 60, "rise_k": 4.0, "beta_m_per_k": [1.5e-6, 6.0e-6, 3.0e-6]}
    plant = [VirtualMachine(f"hmc-{k}", 100 + k, {"structural_thermal_drift": drift})
             for k in range(vm_machines)]
    bags = write_fleet(root, plant, days)
    surveys = 0
    for k in range(survey_machines):
        folder = root / f"surveyed-{k}"
        folder.mkdir(parents=True)
        for day in range(days):
            name = f"survey_{(FIRST_DAY + dt.timedelta(days=day)).date().isoformat()}.csv"
            trial = make_trial("kidani_hmc", ("ballscrew_pitch",), 2000 + 100 * k + day,
                               readings=readings)
            write_panel_survey(trial, folder / name, folder / "map.tmp.yaml", motion=True,
                               temperatures=True)
            surveys += 1
        mapping = yaml.safe_load((folder / "map.tmp.yaml").read_text())
        (folder / "map.tmp.yaml").unlink()
        if k % 2:
            mapping["machine"] = "kidani_hmc"
        (folder / "columns.yaml").write_text(yaml.safe_dump(mapping))
    return {"bags": len(bags), "surveys": surveys}


def _figures(summary: dict) -> list[float]:
    return [d["rmse_m"] for m in sorted(summary["machines"])
            for d in summary["machines"][m]["days"]]


def _split(results: list[dict], kind: str) -> dict:
    """Median seconds per task of each part, over the tasks of one kind of data."""
    mine = [r for r in results if r["files"] and r["files"][0]["kind"] == kind]
    if not mine:
        return {}
    out = {part: round(statistics.median(r["split"][part] for r in mine), 3)
           for part in ("reading_s", "search_s", "result_s")}
    out["task_s"] = round(statistics.median(r["seconds"] for r in mine), 3)
    out["cpu_s"] = round(statistics.median(r["cpu_s"] for r in mine), 3)
    out["tasks"] = len(mine)
    return out


def one_run(root: str, workers: int) -> tuple[dict, list[float]]:
    """``run_fleet`` on ``workers`` local worker processes: the run's figures."""
    from mt_accuracy_ros.commands.fleet import run_fleet

    started = time.perf_counter()
    summary = run_fleet([root], workers=workers, progress=False)
    wall = time.perf_counter() - started
    results = summary["results"]
    tasks_s = summary["ran_on"]["tasks_s"]
    busy = sum(r["seconds"] for r in results)
    run = {"workers": workers, "machine_days": len(results),
           "machine_days_per_s": round(len(results) / tasks_s, 3),
           "tasks_s": round(tasks_s, 2), "wall_s": round(wall, 2),
           "task_seconds_sum": round(busy, 2),
           "workers_cpu_s": round(sum(r["cpu_s"] for r in results), 2),
           "overhead_s": round(workers * tasks_s - busy, 2),
           "per_task_bag": _split(results, "bag"),
           "per_task_survey": _split(results, "survey_csv"),
           "failed": summary["failed_tasks"], "refused": len(summary["refused"])}
    return run, _figures(summary)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vm-machines", type=int, default=5)
    parser.add_argument("--survey-machines", type=int, default=5)
    parser.add_argument("--days", type=int, default=10)
    parser.add_argument("--readings", type=int, default=500,
                        help="readings per survey")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--serial", action="store_true",
                        help="also every task in this process, one after another")
    args = parser.parse_args(argv)

    with tempfile.TemporaryDirectory() as tmp:
        made = make_plant(Path(tmp), args.vm_machines, args.survey_machines, args.days,
                          args.readings)
        print(json.dumps({"plant": made}), flush=True)
        runs, reference = [], None
        for _ in range(args.repeats):
            pair = {}
            for workers in (1, 2):
                run, figures = one_run(tmp, workers)
                reference = reference or figures
                difference = max(abs(a - b) / b for a, b in zip(figures, reference))
                run["same_figures"] = len(figures) == len(reference) and difference < 1e-9
                pair[workers] = run
                runs.append(run)
                print(json.dumps(run), flush=True)
            ratio = pair[2]["machine_days_per_s"] / pair[1]["machine_days_per_s"]
            print(json.dumps({"ratio_two_over_one": round(ratio, 3)}), flush=True)
        result = {"plant": made, "readings_per_survey": args.readings,
                  "runs": runs,
                  "ratio_two_over_one_per_pair": [
                      round(b["machine_days_per_s"] / a["machine_days_per_s"], 3)
                      for a, b in zip(runs[0::2], runs[1::2])]}
        if args.serial:
            from mt_accuracy_ros.commands.fleet import diagnose_day
            from mt_accuracy_ros.io.fleet_inputs import discover, plan_days

            tasks = [d.as_task(3, 0.05) for d in plan_days(discover([tmp], None, None))]
            started, cpu = time.perf_counter(), time.process_time()
            serial = [diagnose_day(task) for task in tasks]
            result["serial_in_process"] = {
                "seconds": round(time.perf_counter() - started, 2),
                "cpu_s": round(time.process_time() - cpu, 2),
                "per_task_bag": _split(serial, "bag"),
                "per_task_survey": _split(serial, "survey_csv")}
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
