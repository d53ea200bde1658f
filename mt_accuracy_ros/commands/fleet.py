"""``mt-accuracy fleet``: a plant's machines diagnosed on Dask, one task per machine and day.

The client finds the datasets (:mod:`~mt_accuracy_ros.io.fleet_inputs`), reads only
each bag's summary to tell its day, and submits one :func:`diagnose_day` per machine
and day to a Dask cluster: a local cluster of worker processes by default (a laptop
needs no set-up), or an existing scheduler (``--scheduler tcp://HOST:8786``), whose
workers must have this package installed. Each task runs ``mt-accuracy check``'s
engine on its files and *returns* a compact result; the client gathers them (nothing
passes through the file system), and :func:`summarise` builds the fleet's picture:
each machine's error over time with its named effects, the effects many machines
share, the machines that drift ranked (:mod:`~mt_accuracy_ros.core.fleet.trends`),
and every file refused with its reason. A file that fails (a truncated or foreign
bag, a survey without a column map) fails in its own task only; a task that dies
(a worker lost) is reported the same way and the rest goes on.

Dask is imported here only: the single-machine commands never need it.
"""
from __future__ import annotations

import argparse
import json
import os
import socket
import sys
import time
from pathlib import Path

import numpy as np

from ..core.errors import InputDataError, MtAccuracyError

#: Effects listed per day in the summary lines.
SHOWN_EFFECTS = 4


def _one_line(exc: BaseException) -> str:
    text = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
    return " ".join(str(text).split()) or type(exc).__name__


def _check_dataset(dataset: dict, auto: int, min_reduction: float):
    """``mt-accuracy check`` on one bag or survey (in a worker)."""
    from .check import check_bag, check_mapped_csv

    path = Path(dataset["path"])
    if dataset["kind"] == "bag":
        return check_bag(path, dataset["model"] or "demo", [], auto, "", min_reduction)
    if not dataset["columns"]:
        raise InputDataError(f"{path.name}: a survey needs its column map (columns: in the "
                             "manifest, columns.yaml beside it, or --columns)")
    import yaml

    from ..io.column_map import column_map_from_dict

    try:
        column_map = column_map_from_dict(yaml.safe_load(Path(dataset["columns"]).read_text()),
                                          dataset["columns"])
    except (OSError, yaml.YAMLError) as exc:
        raise InputDataError(f"column map {dataset['columns']}: {exc}") from exc
    return check_mapped_csv(path, column_map, dataset["model"], [], auto, min_reduction,
                            machine=dataset["machine_file"])


def _compact(result) -> dict:
    """What the fleet keeps of one check (a :class:`~.check_result.CheckResult`): figures
    [m] and the named effects."""
    return {"readings": int(result.readings),
            "rmse_m": float(result.baseline_rmse),
            "final_rmse_m": float(result.final_rmse),
            "band_m": float(result.band or 0.0),
            "machine_model": result.machine,
            # How a survey's error columns were read (None for a bag).
            "error_convention": result.source.error_convention,
            "named": [{"name": n["name"], "effect": n["effect"],
                       "display": n.get("display", {}),
                       "error_reduction": float(n["error_reduction"])}
                      for n in result.named],
            "added": list(result.added),
            "warnings": list(result.warnings or []),
            "localisation": result.localisation.get("sentence", "")}


def diagnose_day(task: dict) -> dict:
    """One machine's day: ``check`` on each of its files (run by a Dask worker).

    Parameters
    ----------
    task : dict
        :meth:`~mt_accuracy_ros.io.fleet_inputs.Day.as_task`.

    Returns
    -------
    dict
        ``machine``, ``day``, ``day_number``, ``files`` (one entry per file: ``ok``
        with its figures [m] and named effects, or ``reason``), the day's RMS error
        over every reading of its good files (``rmse_m``, ``final_rmse_m``, None if
        none was good), the ``worker`` (host:pid), the ``seconds`` it took (wall), its
        ``cpu_s`` (the worker process's CPU time) and its ``split`` [s]: ``reading_s``
        (the files, the models, the check's assembly), ``search_s`` (the diagnoses),
        ``result_s`` (the compact result).
    """
    from ..allocator import keep_freed_arrays

    keep_freed_arrays()
    started, cpu = time.perf_counter(), time.process_time()
    files = []
    split = {"reading_s": 0.0, "search_s": 0.0, "result_s": 0.0}
    for dataset in task["datasets"]:
        entry = {"file": dataset["path"], "kind": dataset["kind"]}
        try:
            begun = time.perf_counter()
            result = _check_dataset(dataset, task["auto"], task["min_reduction"])
            checked = time.perf_counter()
            entry.update(ok=True, **_compact(result))
            search = result.seconds.get("search", 0.0)
            # Reading: the file, the model and the check's own assembly around its search.
            split["reading_s"] += checked - begun - search
            split["search_s"] += search
            split["result_s"] += time.perf_counter() - checked
        except (MtAccuracyError, OSError, ValueError, KeyError) as exc:
            entry.update(ok=False, reason=_one_line(exc))
        files.append(entry)
    good = [f for f in files if f["ok"]]
    readings = sum(f["readings"] for f in good)

    def pooled(key: str):
        if not readings:
            return None
        return float(np.sqrt(sum(f["readings"] * f[key] ** 2 for f in good) / readings))

    return {"machine": task["machine"], "day": task["day"], "day_number": task["day_number"],
            "files": files, "readings": readings, "rmse_m": pooled("rmse_m"),
            "final_rmse_m": pooled("final_rmse_m"),
            "named": sorted({n["name"] for f in good for n in f["named"]}),
            "worker": f"{socket.gethostname()}:{os.getpid()}",
            "seconds": time.perf_counter() - started,
            "cpu_s": time.process_time() - cpu, "split": split}


def summarise(days: list[dict]) -> dict:
    """The fleet's picture from every task's result (see the module docstring)."""
    from ..core.fleet.trends import common_effects, error_trend, rank_by_drift

    machines: dict[str, dict] = {}
    refused = []
    for day in sorted(days, key=lambda d: (d["machine"], d["day_number"] is None,
                                           d["day_number"] or 0.0, d["day"])):
        entry = machines.setdefault(day["machine"], {"days": [], "refused": []})
        for f in day["files"]:
            if not f["ok"]:
                item = {"machine": day["machine"], "day": day["day"], "file": f["file"],
                        "reason": f["reason"]}
                entry["refused"].append(item)
                refused.append(item)
        if day["rmse_m"] is not None:
            entry["days"].append({k: day[k] for k in ("day", "day_number", "readings",
                                                      "rmse_m", "final_rmse_m", "named")}
                                 | {"effects": [n for f in day["files"] if f["ok"]
                                                for n in f["named"]]})
    trends = {}
    for name, entry in machines.items():
        good = entry["days"]
        if not good:
            entry["trend"] = None
            continue
        # Undated files follow the dated ones in their order, a day apart.
        last = max([d["day_number"] for d in good if d["day_number"] is not None], default=0.0)
        numbers, extra = [], 0
        for d in good:
            if d["day_number"] is None:
                extra += 1
            numbers.append(d["day_number"] if d["day_number"] is not None else last + extra)
        trends[name] = error_trend(numbers, [d["rmse_m"] for d in good])
        entry["trend"] = trends[name].as_dict()
        entry["named_effects"] = sorted({n for d in good for n in d["named"]})
    ranking = rank_by_drift(trends)
    shared = common_effects({n: e.get("named_effects", []) for n, e in machines.items()})
    return {"machines": machines,
            "drift_ranking": [{"machine": n, **trends[n].as_dict()} for n in ranking],
            "common_effects": [{"effect": e, "machines": m} for e, m in shared],
            "refused": refused,
            "machine_count": len(machines), "day_count": sum(len(e["days"]) for e in
                                                            machines.values())}


class _Cluster:
    """A Dask client on ``scheduler`` (an address) or on a new local cluster of
    ``workers`` processes with one thread each; closed on exit."""

    def __init__(self, scheduler: str | None, workers: int) -> None:
        self.scheduler, self.workers = scheduler, workers
        self.cluster = self.client = None

    def __enter__(self):
        import logging

        from distributed import Client, LocalCluster

        if self.scheduler:
            self.client = Client(self.scheduler, timeout="30s")
        else:
            # Everything on loopback: the scheduler, its workers and the HTTP server the
            # scheduler always runs (on a free port, no dashboard).
            self.cluster = LocalCluster(n_workers=self.workers, threads_per_worker=1,
                                        processes=True, host="127.0.0.1",
                                        dashboard_address=None,
                                        scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                                        silence_logs=logging.ERROR)
            self.client = Client(self.cluster)
        return self.client

    def __exit__(self, *exc) -> None:
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def run_days(tasks: list[dict], *, scheduler: str | None = None, workers: int = 2,
             progress: bool = True) -> tuple[list[dict], dict]:
    """Every task on the cluster; (results in task order, what ran them: the scheduler,
    its worker count and ``tasks_s``, the seconds from the first submission to the last
    result).

    A task that raised or whose worker died comes back as a day whose files are
    all refused with that reason."""
    from distributed import as_completed
    from tqdm import tqdm

    results: list[dict | None] = [None] * len(tasks)
    with _Cluster(scheduler, workers) as client:
        info = client.scheduler_info()
        ran_on = {"scheduler": scheduler or "local cluster",
                  "workers": len(info.get("workers", {}))}
        submitted = time.perf_counter()
        futures = {client.submit(diagnose_day, task, pure=False,
                                 key=f"diagnose-{k}-{task['machine']}-{task['day']}"): k
                   for k, task in enumerate(tasks)}
        bar = tqdm(total=len(tasks), desc="fleet", unit="day", disable=not progress,
                   file=sys.stderr)
        for future in as_completed(futures):
            k = futures[future]
            try:
                results[k] = future.result()
            except Exception as exc:  # noqa: BLE001 - a lost task is reported, not fatal
                task = tasks[k]
                results[k] = {"machine": task["machine"], "day": task["day"],
                              "day_number": task["day_number"], "readings": 0,
                              "rmse_m": None, "final_rmse_m": None, "named": [],
                              "worker": "", "seconds": 0.0, "cpu_s": 0.0, "split": {},
                              "files": [{"file": d["path"], "kind": d["kind"], "ok": False,
                                         "reason": f"the task failed: {_one_line(exc)}"}
                                        for d in task["datasets"]]}
            bar.update(1)
            bar.set_postfix_str(f"{tasks[k]['machine']} {tasks[k]['day']}")
        bar.close()
        # From the first task submitted to the last result in: the fleet's throughput,
        # without the cluster's start.
        ran_on["tasks_s"] = time.perf_counter() - submitted
    return [r for r in results if r is not None], ran_on


def run_fleet(inputs: list[str], *, model: str | None = None, columns: str | None = None,
              scheduler: str | None = None, workers: int = 2, auto: int = 3,
              min_reduction: float = 0.05, progress: bool = True) -> dict:
    """Find the fleet's data, diagnose every machine's days on Dask, summarise."""
    from ..core.inputs.options import in_range
    from ..io.fleet_inputs import discover, plan_days

    # The command line checked these already; a caller from Python gets the same words.
    if scheduler is None:
        in_range("--workers", workers, low=1, what="an integer")
    in_range("--auto", auto, low=0, what="an integer")
    in_range("--min-reduction", min_reduction, low=0, high=1, high_open=True,
             what="a fraction")
    days = plan_days(discover(inputs, model, columns))
    tasks = [d.as_task(auto, min_reduction) for d in days]
    started = time.perf_counter()
    results, ran_on = run_days(tasks, scheduler=scheduler, workers=workers, progress=progress)
    summary = summarise(results)
    summary.update(inputs=list(inputs), tasks=len(tasks), ran_on=ran_on,
                   wall_s=time.perf_counter() - started,
                   failed_tasks=sum(1 for r in results if r["rmse_m"] is None),
                   results=results)
    return summary


def print_summary(summary: dict, out=None) -> None:
    """The fleet in lines: each machine's days, the drift ranking, shared effects,
    refused files. Lengths in micrometres. ``out``: a text stream (default: the
    ``sys.stdout`` of the moment, not of the import)."""
    out = sys.stdout if out is None else out
    um = 1e6
    print(f"fleet: {summary['machine_count']} machines, {summary['tasks']} machine-days on "
          f"{summary['ran_on']['workers']} workers ({summary['ran_on']['scheduler']}) in "
          f"{summary['wall_s']:.1f} s; {len(summary['refused'])} files refused", file=out)
    for name, entry in summary["machines"].items():
        for day in entry["days"]:
            named = ", ".join(day["named"][:SHOWN_EFFECTS]) or "nothing"
            more = f" (+{len(day['named']) - SHOWN_EFFECTS})" if len(day["named"]) > \
                SHOWN_EFFECTS else ""
            print(f"  {name} {day['day']}: {day['readings']} readings, model "
                  f"{day['rmse_m'] * um:.3g} um RMS, with the named effects "
                  f"{day['final_rmse_m'] * um:.3g} um; named: {named}{more}", file=out)
    print("drift, ranked:", file=out)
    for rank, item in enumerate(summary["drift_ranking"], 1):
        spread = item["slope_standard_error_m_per_day"]
        spread_text = f" ± {spread * um:.2g}" if spread is not None else ""
        print(f"  {rank}. {item['machine']}: {item['slope_m_per_day'] * um:+.3g}{spread_text} "
              f"um/day over {item['days']} days ({item['first_m'] * um:.3g} -> "
              f"{item['last_m'] * um:.3g} um){' DRIFTING' if item['drifting'] else ''}",
              file=out)
    for item in summary["common_effects"]:
        print(f"common: {item['effect']} on {len(item['machines'])} machines "
              f"({', '.join(item['machines'])})", file=out)
    for item in summary["refused"]:
        print(f"refused: {item['machine']} {item['day']} {Path(item['file']).name}: "
              f"{item['reason']}", file=out)


def write_fleet_outputs(summary: dict, json_path: str | None, report_path: str | None) -> None:
    if report_path:
        from ..report.fleet import write_fleet_report

        summary["report"] = write_fleet_report(summary, Path(report_path)).as_dict()
    if json_path:
        Path(json_path).parent.mkdir(parents=True, exist_ok=True)
        Path(json_path).write_text(json.dumps(summary, indent=2, default=float))


# ------------------------------------------------------------------ the command line
def validate_fleet(args: argparse.Namespace) -> None:
    """--workers only for the local cluster; counts and fractions in range; the outputs."""
    from ..core.inputs.options import in_range, not_applicable
    from ..io.output_paths import Output, check_outputs

    if args.scheduler and args.workers is not None:
        raise not_applicable("--workers", "the local cluster", "--scheduler (its workers "
                             "are the scheduler's)")
    in_range("--workers", args.workers, low=1, what="an integer")
    in_range("--auto", args.auto, low=0, what="an integer")
    in_range("--min-reduction", args.min_reduction, low=0, high=1, high_open=True,
             what="a fraction")
    check_outputs([Output("--json", args.json), Output("--report", args.report)],
                  [*args.inputs, args.columns])


def fleet_command(args: argparse.Namespace) -> int:
    """Diagnose the fleet, write its outputs and print its summary; exit 1 when no file
    could be read at all (refused files are findings of the fleet, not a failure)."""
    workers = args.workers if args.workers is not None else os.cpu_count() or 1
    summary = run_fleet(args.inputs, model=args.model, columns=args.columns,
                        scheduler=args.scheduler, workers=workers, auto=args.auto,
                        min_reduction=args.min_reduction, progress=not args.quiet)
    write_fleet_outputs(summary, args.json, args.report)
    print_summary(summary)
    if args.report:
        print(f"report: {args.report}")
    return 0 if summary["day_count"] else 1


def add_parser(commands) -> None:
    """``fleet`` on the subcommands ``commands``."""
    fleet = commands.add_parser("fleet", help="diagnose many machines' bags and surveys on "
                                "Dask: error over time, shared effects, drift ranked")
    fleet.add_argument("inputs", nargs="+", metavar="INPUT",
                       help="a directory (a folder per machine), a glob (the folder holding "
                            "each match names its machine) or a manifest YAML (machines: "
                            "{NAME: {data: [globs], model:, machine:, columns:}})")
    fleet.add_argument("--scheduler", metavar="ADDRESS",
                       help="an existing Dask scheduler (tcp://host:8786) whose workers have "
                            "this package; default: a local cluster of --workers processes")
    fleet.add_argument("--workers", type=int, default=None,
                       help="worker processes of the local cluster (default: one per core; "
                            "not with --scheduler)")
    fleet.add_argument("--model", default=None,
                       help="model of the machines that have none of their own (bags: "
                            "default 'demo'; a folder's model.yaml or the manifest's model: "
                            "wins)")
    fleet.add_argument("--columns", metavar="FILE.yaml",
                       help="column map of the surveys whose machine has none of its own")
    fleet.add_argument("--auto", type=int, default=3, metavar="N",
                       help="name up to N effects per machine-day (default 3)")
    fleet.add_argument("--min-reduction", type=float, default=0.05,
                       help="smallest CV error reduction that counts")
    fleet.add_argument("--json", help="JSON summary path (every machine-day's result)")
    fleet.add_argument("--report", help="HTML fleet report path")
    fleet.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    fleet.set_defaults(handler=fleet_command, validate=validate_fleet)
