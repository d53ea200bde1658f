"""Thermal logs that change regime, made by independent code, checked as a user would.

The logs come from ``studies.regime_logs_panel`` (written from the physics and the seeds
alone, its conventions drawn at random: time in s, min, h or date-times; targets in um, mm,
nm with either sign; `;` or `,`; units rows; runs by a column or a clock jump; dead, stuck
and zero sensors; a true unit slip of one run; a run that only ran hotter). Each log is
checked twice with the package's command line, the flags a user would give knowing their
own file (the target's unit, the time column, the run column, the spindle speed):

1. one split (``--train-fraction 0.5``, the default): the held-out RMSE of the workbench,
   a constant and least squares on every input;
2. ``--walk-forward``: each eighth of the log (each run, with runs) predicted from every
   row before it.

What each log should give is read from its truth: a unit slip refused naming its run and
sensor; every dead, stuck or zero sensor named; a run that only ran hotter kept; a held-out
regime the training never held said. Every log is printed, the failures too.

Usage: ``python -m bench.regime_panel_proof [--seed 1] [--logs 12] [--out DIR] [--json F]``
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))


def _flags(truth: dict) -> list[str]:
    """The check's flags a user who knows the file would give."""
    by_role: dict[str, list[dict]] = {}
    for column in truth["columns"]:
        by_role.setdefault(column["role"], []).append(column)
    target = by_role["target"][0]
    unit = {"um": "um", "mm": "mm", "nm": "nm", "m": "m"}[target["unit"]]
    flags = ["--target", f"{target['name']}:{unit}", "--time-column", by_role["time"][0]["name"]]
    if by_role.get("run"):
        flags += ["--run", by_role["run"][0]["name"]]
    if by_role.get("speed"):
        flags += ["--driver", f"{by_role['speed'][0]['name']}:rpm"]
    return flags


def _run(args: list[str]) -> tuple[int, str, str]:
    """The command line in this process: (exit code, stdout, stderr)."""
    from mt_accuracy_ros.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(args)
        except SystemExit as stop:
            code = int(stop.code or 0)
    return code, out.getvalue(), err.getvalue()


def _expectations(truth: dict) -> dict:
    """What the log should give, from its truth."""
    slips = truth.get("unit_slips") or []
    faults = truth.get("faults") or []
    split = truth.get("split") or {}
    return {"refused_unit_slip": bool(slips),
            "faulty_sensors": sorted({f["column"] for f in faults}),
            "hot_run": bool(truth.get("hot_runs")),
            "new_regime_held_out": bool(split) and bool(
                set(split.get("test_regimes") or []) - set(split.get("train_regimes") or []))}


def check_one(csv_path: Path, truth: dict, workdir: Path) -> dict:
    """One log checked once split and once walking forward; what it gave against its truth."""
    flags = _flags(truth)
    expected = _expectations(truth)
    entry = {"log": csv_path.name, "rows": truth["format"]["n_rows"], "flags": flags,
             "expected": expected}
    json_path = workdir / f"{csv_path.stem}.json"
    started = time.process_time()
    code, out, err = _run(["check", str(csv_path), *flags, "--auto", "3", "--json",
                           str(json_path)])
    entry["exit"], entry["cpu_s"] = code, round(time.process_time() - started, 2)
    if code != 0:
        entry["refusal"] = err.strip().splitlines()[-1][:400] if err.strip() else out[-400:]
        entry["right"] = expected["refused_unit_slip"] and "unit" in entry["refusal"]
        return entry
    summary = json.loads(json_path.read_text())
    notes = " ".join(summary["notes"] + summary.get("warnings", []))
    baselines = summary["baselines_held_out_m"]
    entry.update({
        "model": summary["model_chosen"], "added": summary["added"],
        "held_out_um": {k: round(v * 1e6, 3) for k, v in baselines.items()},
        "named_faulty": [s for s in expected["faulty_sensors"] if f"sensor {s}" in notes],
        "regime_said": "the held-out rows hold" in notes,
        "never_silently_worse": baselines["model"] <= 1.1 * min(
            baselines["constant"], baselines["least squares on every input"]) or
        "warning: " in " ".join(summary.get("warnings", []))})
    period = "run" if summary.get("runs") else \
        f"{summary['rows'] * float(truth['time']['sampling_s']) / 8.0:.0f}s"
    code, out, err = _run(["check", str(csv_path), *flags, "--auto", "3", "--walk-forward",
                           period, "--json", str(json_path)])
    if code == 0:
        walk = json.loads(json_path.read_text())["walk_forward"]
        entry["walk_forward_um"] = {k: round(v * 1e6, 3) for k, v in walk["pooled_m"].items()}
        entry["walk_period"] = period
    else:
        entry["walk_refusal"] = err.strip()[:300]
    entry["right"] = (not expected["refused_unit_slip"]) and \
        len(entry["named_faulty"]) == len(expected["faulty_sensors"]) and \
        entry["never_silently_worse"] and \
        (entry["regime_said"] or not expected["new_regime_held_out"])
    return entry


def main(argv: list[str] | None = None) -> int:
    from studies.regime_logs_panel import make_panel

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--logs", type=int, default=12)
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args(argv)
    out = args.out or Path(tempfile.mkdtemp(prefix="regime_panel_"))
    truths = make_panel(args.seed, args.logs, out)
    results = []
    for truth in truths:
        csv_path = Path(truth.csv_path) if hasattr(truth, "csv_path") else \
            Path(truth["csv_path"])
        data = json.loads(Path(str(csv_path).replace(".csv", ".truth.json")).read_text())
        entry = check_one(csv_path, data, out)
        results.append(entry)
        print(json.dumps(entry), flush=True)
    right = sum(bool(e.get("right")) for e in results)
    print(f"{right} of {len(results)} logs as their truth says", flush=True)
    if args.json:
        args.json.write_text(json.dumps({"seed": args.seed, "results": results}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
