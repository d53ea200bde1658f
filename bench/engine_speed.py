"""Diagnosis speed (issue 27): the whole check, and the selection engine against peers.

Everything runs pinned to one core (``sched_setaffinity``, BLAS single-threaded),
on surveys made by the independent foreign-machine generator
(``studies.foreign_machine``: a ball-screw pitch error hidden in kidani_hmc
surveys of 1k, 10k, 100k readings). Every run is printed, not the best.

0. **diagnosis**: one diagnosis of the survey over the full catalogue (the engine:
   selection, refinement, verdict, localisation), timed in a child process after the
   survey is read; its peak memory.
1. **check**: ``mt-accuracy check SURVEY.csv --columns MAP.yaml --auto 3`` as a
   user runs it (a subprocess; ``command: survey``, issue 41's targets: 1 s at 1e4
   readings, 10 s and 500 MB at 1e5), and the same with the machine's description
   (``--model "{machine: kidani_hmc}"``, ``command: machine``: its larger catalogue),
   alternating: wall time and peak memory (the child's max RSS), what it named.
   **start-up**: the command's imports alone.
2. **engine vs peers** on the *same candidate design matrix*: every catalogue
   candidate at one setting (its whole-record choice) is a block of columns;
   forward selection of 4 blocks, each step scoring every block by 5-fold
   time-blocked cross-validation, done
   - by this package's engine (``Selector``: per-fold normal equations, training
     blocks = whole - held-out),
   - by a naive loop refitting ``lstsq`` for every fold of every candidate,
   - and by scikit-learn's ``SequentialFeatureSelector`` (LinearRegression,
     ``TimeSeriesSplit(5)``, 4 columns) on the same matrix - a peer that scores
     single columns on expanding windows, i.e. a related but not identical
     search; its time is reported beside ours.
   Ours and the naive loop must choose the same blocks with the same scores.

Usage: ``python -m bench.engine_speed [--sizes 1000 10000 100000] [--repeats 3]
[--no-sklearn] [--sklearn-max 10000]``
"""
from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_name] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

CORE = 0


def _pin() -> None:
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {CORE})


def write_survey(readings: int, folder: Path, seed: int = 1000) -> tuple[Path, Path, str]:
    """A logger-style survey (mm, um, min) of kidani_hmc with a hidden ball-screw pitch."""
    from studies.foreign_machine import make_trial
    from studies.survey_files import write_logger_survey

    trial = make_trial("kidani_hmc", ("ballscrew_pitch",), seed, readings=readings)
    csv = folder / f"survey_{readings}.csv"
    mapping = folder / f"map_{readings}.yaml"
    write_logger_survey(trial, csv, mapping)
    (truth,) = trial.hidden[0].accepted
    return csv, mapping, truth


def _timed_child(command: list[str]) -> tuple[float, float, str]:
    """Wall [s], peak RSS [MB] and stdout of a child process pinned to one core."""
    started = time.perf_counter()
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             text=True, preexec_fn=_pin)
    output = child.stdout.read()
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - started
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{' '.join(command)} failed:\n{output}")
    return wall, usage.ru_maxrss / 1024.0, output


#: The two commands timed: the issue's (no machine given: a generic machine over the
#: surveyed travel, the issue-41 targets) and with the surveyed machine's description
#: (its larger catalogue).
CHECK_COMMANDS = {"survey": [], "machine": ["--model", "{machine: kidani_hmc}"]}


def check_runs(readings: int, folder: Path, repeats: int) -> list[dict]:
    csv, mapping, truth = write_survey(readings, folder)
    runs = []
    for _ in range(repeats):
        # The two commands alternate: a drift of the host's speed touches both alike.
        for command, extra in CHECK_COMMANDS.items():
            wall, rss, output = _timed_child([
                sys.executable, "-m", "mt_accuracy_ros.cli", "check", str(csv), "--columns",
                str(mapping), *extra, "--auto", "3"])
            named = [line.split()[1] for line in output.splitlines()
                     if line.startswith("named:")]
            runs.append({"readings": readings, "command": command, "wall_s": round(wall, 3),
                         "peak_rss_mb": round(rss), "named": named[:1], "truth": truth})
    return runs


def diagnosis_child(csv: str, mapping: str) -> None:
    """(In a child process) one diagnosis of the survey over the full catalogue - the
    engine's figure, without the CLI's reading, second diagnosis and report: prints JSON."""
    import resource

    import yaml

    from mt_accuracy_ros.allocator import keep_freed_arrays
    from mt_accuracy_ros.core.compensation.error_model import resolve_model
    from mt_accuracy_ros.core.workbench.diagnosis import Observations, diagnose
    from mt_accuracy_ros.io.column_map import column_map_from_dict, read_mapped_csv

    keep_freed_arrays()     # as the command line and the monitor's worker do
    column_map = column_map_from_dict(yaml.safe_load(Path(mapping).read_text()))
    survey = read_mapped_csv(Path(csv), column_map)
    model = resolve_model("{machine: kidani_hmc}")
    n = survey.time_s.size
    measured, mask = np.zeros((n, 3)), np.zeros((n, 3), dtype=bool)
    for c, component in enumerate("xyz"):
        if component in survey.errors:
            measured[:, c], mask[:, c] = survey.errors[component], True
    obs = Observations(survey.positions, measured, mask, survey.time_s, survey.velocities,
                       survey.temperatures, column_map.uncertainty_m,
                       directions=survey.directions, accelerations=survey.accelerations,
                       spindle_speed_rad_s=survey.spindle_speed_rad_s)
    for sensor, values in obs.temperatures.items():
        model.reference_temperatures_c.setdefault(sensor, float(values[0]))
    started = time.perf_counter()
    result = diagnose(model, obs)
    wall = time.perf_counter() - started
    print(json.dumps({"diagnose_s": round(wall, 3),
                      "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
                                           / 1024),
                      "named": [c.name for c in result.selected][:1]}))


def diagnosis_runs(readings: int, folder: Path, repeats: int) -> list[dict]:
    csv, mapping, truth = write_survey(readings, folder)
    runs = []
    for _ in range(repeats):
        _, _, output = _timed_child([sys.executable, "-m", "bench.engine_speed",
                                     "--diagnosis-child", str(csv), str(mapping)])
        run = {"readings": readings, **json.loads(output.strip().splitlines()[-1]),
               "truth": truth}
        runs.append(run)
        print(json.dumps(run), flush=True)
    return runs


def startup_runs(repeats: int) -> list[float]:
    code = ("import mt_accuracy_ros.cli, mt_accuracy_ros.commands.check, "
            "mt_accuracy_ros.core.workbench.diagnosis, mt_accuracy_ros.io.column_map")
    return [round(_timed_child([sys.executable, "-c", code])[0], 3) for _ in range(repeats)]


# ---------------------------------------------------------------- engine vs peers
def candidate_blocks(readings: int):
    """The Selector of a survey and every candidate at its whole-record setting."""
    from mt_accuracy_ros.core.compensation.error_model import ErrorModel
    from mt_accuracy_ros.core.effects import Context
    from mt_accuracy_ros.core.kinematics.machine import load_machine
    from mt_accuracy_ros.core.workbench.diagnosis import candidate_terms, residuals
    from mt_accuracy_ros.core.workbench.selection import Selector, Term
    from studies.catalogue_trials import observations
    from studies.foreign_machine import make_trial

    trial = make_trial("kidani_hmc", ("ballscrew_pitch",), 1000, readings=readings)
    obs = observations(trial)
    model = ErrorModel(load_machine("kidani_hmc"), {})
    variables = obs.variables(model.reference_temperatures_c)
    orientation = model.tcp_error(obs.positions, **obs.model_inputs(), fresh=True)[1]
    ctx = Context(model.machine, variables, model._kinematics, orientation)
    selector = Selector(ctx, residuals(model, obs), obs.measured_mask, obs.uncertainty_m / 2)
    base = selector.base_columns()
    fixed = []
    for term in candidate_terms(model, ctx, None):
        setting = term.settings[0] if len(term.settings) == 1 else \
            selector.choose_setting_all(term, base)
        fixed.append(Term(term.family, term.variant, [setting]))
    return selector, fixed


def forward_ours(selector, terms, steps: int = 4) -> tuple[list[str], list[float]]:
    chosen, scores = [], []
    remaining = list(terms)
    selector.selected = []
    for _ in range(steps):
        stats = selector.base_statistics(selector.base_columns())
        best = None
        for term in remaining:
            per_sample, _ = selector.out_of_fold(stats, term)
            mse = float(per_sample.sum())
            if best is None or mse < best[0]:
                best = (mse, term)
        selector.selected.append((best[1], best[1].settings[0]))
        remaining.remove(best[1])
        chosen.append(best[1].name)
        scores.append(best[0])
    selector.selected = []
    return chosen, scores


def forward_naive(selector, terms, steps: int = 4) -> tuple[list[str], list[float]]:
    """Refit everything: lstsq on the training rows of every fold of every candidate."""
    y = selector.y
    blocks = {t.name: selector.design_rows(t, t.settings[0]) for t in terms}
    base = [selector.offsets]
    chosen, scores = [], []
    remaining = [t.name for t in terms]
    for _ in range(steps):
        best = None
        for name in remaining:
            x = np.column_stack(base + [blocks[name]])
            total = 0.0
            for a, b in selector.fold_bounds:
                train = np.ones(y.size, dtype=bool)
                train[a:b] = False
                coefficients, *_ = np.linalg.lstsq(x[train], y[train], rcond=None)
                total += float(np.sum((x[a:b] @ coefficients - y[a:b]) ** 2))
            if best is None or total < best[0]:
                best = (total, name)
        base.append(blocks[best[1]])
        remaining.remove(best[1])
        chosen.append(best[1])
        scores.append(best[0])
    return chosen, scores


def forward_sklearn(selector, terms, steps: int = 4) -> list[int]:
    from sklearn.feature_selection import SequentialFeatureSelector
    from sklearn.linear_model import LinearRegression
    from sklearn.model_selection import TimeSeriesSplit

    x = np.column_stack([selector.offsets] + [selector.design_rows(t, t.settings[0])
                                              for t in terms])
    search = SequentialFeatureSelector(LinearRegression(), n_features_to_select=steps,
                                       direction="forward", cv=TimeSeriesSplit(5),
                                       scoring="neg_mean_squared_error", n_jobs=1)
    search.fit(x, selector.y)
    return [int(i) for i in np.flatnonzero(search.get_support())]


def engine_runs(readings: int, repeats: int, with_sklearn: bool) -> list[dict]:
    selector, terms = candidate_blocks(readings)
    columns = sum(selector.design_rows(t, t.settings[0]).shape[1] for t in terms)
    runs = []
    for _ in range(repeats):
        started = time.perf_counter()
        ours, ours_scores = forward_ours(selector, terms)
        ours_s = time.perf_counter() - started
        started = time.perf_counter()
        naive, naive_scores = forward_naive(selector, terms)
        naive_s = time.perf_counter() - started
        run = {"readings": readings, "blocks": len(terms), "columns": columns,
               "ours_s": round(ours_s, 3), "naive_s": round(naive_s, 3),
               "naive_over_ours": round(naive_s / ours_s, 1),
               "same_choice": ours == naive,
               "max_score_difference": float(np.max(np.abs(np.subtract(ours_scores,
                                                                        naive_scores)) /
                                                 np.abs(naive_scores))),
               "chosen": ours}
        if with_sklearn:
            started = time.perf_counter()
            run["sklearn_columns"] = forward_sklearn(selector, terms)
            run["sklearn_s"] = round(time.perf_counter() - started, 3)
            run["sklearn_over_ours"] = round(run["sklearn_s"] / ours_s, 1)
        runs.append(run)
        print(json.dumps(run), flush=True)
    return runs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000, 100000])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-sklearn", action="store_true")
    parser.add_argument("--sklearn-max", type=int, default=10000,
                        help="largest survey scikit-learn runs on (it takes ~20 min at 1e5)")
    parser.add_argument("--skip-check", action="store_true")
    parser.add_argument("--skip-engine", action="store_true")
    parser.add_argument("--diagnosis-child", nargs=2, metavar=("CSV", "MAP"),
                        help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.diagnosis_child:
        diagnosis_child(*args.diagnosis_child)
        return 0
    _pin()
    report = {"machine": f"{platform.machine()}, {platform.python_version()}, 1 core",
              "startup_s": [], "diagnosis": [], "check": [], "engine": []}
    if not args.skip_check:
        report["startup_s"] = startup_runs(args.repeats)
        print(json.dumps({"startup_s": report["startup_s"]}), flush=True)
        with tempfile.TemporaryDirectory() as folder:
            for n in args.sizes:
                report["diagnosis"] += diagnosis_runs(n, Path(folder), args.repeats)
            for n in args.sizes:
                for run in check_runs(n, Path(folder), args.repeats):
                    print(json.dumps(run), flush=True)
                    report["check"].append(run)
    if not args.skip_engine:
        for n in args.sizes:
            report["engine"] += engine_runs(n, args.repeats,
                                            not args.no_sklearn and n <= args.sklearn_max)
    print(json.dumps(report))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
