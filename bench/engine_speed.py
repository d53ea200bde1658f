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

3. **panel** (``--panel``): ``check`` on every shape of survey the issue names, at
   every size, each run a child process on one core: its CPU time (user + system,
   from ``wait4``: the host may be shared) and peak RSS, beside the goal for its size
   (500 readings 0.2 s, 3,000 0.4 s, 10,000 1 s, 100,000 10 s and 500 MB). Shapes:
   ``positions`` (time, X Y Z and the errors), ``full`` (with velocities,
   accelerations, the spindle speed and four temperatures), ``machine_3axis`` (the
   same with ``--model "{machine: kidani_hmc}"``), ``machine_5axis`` (a five-axis
   machine's survey with its description, ``khan_chen_rpppr``), ``thermal_log`` (the
   first N rows of ``data/fl_thermal``: 16 sensors, ``--target ch5_um``; the log holds
   11,115 rows). ``--baseline TREE`` runs the same commands on another checkout's
   code (``PYTHONPATH=TREE``) in alternation: the ratio of CPU times is measured in the
   same run, and the two JSON outputs are compared byte for byte. ``--bytecode``: each
   tree's modules are compiled once (untimed, into a folder of the run's) and every
   child reads them compiled, as from an installed package; without it, a child under
   ``PYTHONDONTWRITEBYTECODE`` compiles the package from source, ~0.2 s of CPU each.

Usage: ``python -m bench.engine_speed [--sizes 1000 10000 100000] [--repeats 3]
[--no-sklearn] [--sklearn-max 10000]``;
``python -m bench.engine_speed --panel [--sizes 500 3000 10000 100000] [--shapes ...]
[--baseline TREE] [--repeats 2]``
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
    from mt_accuracy_ros.commands.check import in_package_convention
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
    measured, _, _ = in_package_convention(measured, mask, {}, column_map.error_convention,
                                           model.machine, survey.positions)
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


# ---------------------------------------------------------------- the panel
ROOT = Path(__file__).resolve().parents[1]
#: The issue's goals on one core: readings -> (CPU seconds, peak RSS MB or None).
GOALS = {500: (0.2, None), 3000: (0.4, None), 10000: (1.0, None), 100000: (10.0, 500.0)}
PANEL_SHAPES = ("positions", "full", "machine_3axis", "machine_5axis", "thermal_log")
THERMAL_LOG = ROOT / "data" / "fl_thermal" / "fl_thermal.csv"


def panel_command(shape: str, readings: int, folder: Path) -> list[str] | None:
    """``check``'s arguments for ``shape`` at ``readings`` (its data written into
    ``folder`` once); None when the shape has fewer rows than asked (the thermal log)."""
    from studies.foreign_machine import make_trial
    from studies.survey_files import PANEL_SHAPES as SHAPES
    from studies.survey_files import write_panel_survey

    if shape == "thermal_log":
        log = folder / f"log_{readings}.csv"
        if not log.exists():
            lines = THERMAL_LOG.read_text().splitlines()
            if readings > len(lines) - 1:
                return None
            log.write_text("\n".join(lines[:readings + 1]) + "\n")
        return ["check", str(log), "--target", "ch5_um", "--inputs", "t*_C", "--driver",
                "spindle_rpm", "--auto", "3"]
    spec = SHAPES[shape]
    data = "full" if shape == "machine_3axis" else shape
    csv, mapping = folder / f"{data}_{readings}.csv", folder / f"{data}_{readings}.yaml"
    if not csv.exists():
        trial = make_trial(spec["machine"], ("ballscrew_pitch",), 1000, readings=readings)
        write_panel_survey(trial, csv, mapping, motion=spec["motion"],
                           temperatures=spec["temperatures"])
    model = ["--model", spec["model"]] if spec["model"] else []
    return ["check", str(csv), "--columns", str(mapping), *model, "--auto", "3"]


def _cpu_child(command: list[str], tree: Path, bytecode: Path | None = None
               ) -> tuple[float, float, str]:
    """CPU time [s] (user + system), peak RSS [MB] and stdout of a child on one core that
    imports the package from ``tree``; with ``bytecode``, its compiled modules are read
    from (and written to) that folder, as an installed package's are."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    if bytecode is not None:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = str(bytecode)
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             text=True, preexec_fn=_pin, env=env, cwd=tempfile.gettempdir())
    output = child.stdout.read()
    _, status, usage = os.wait4(child.pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{' '.join(command)} failed:\n{output}")
    return usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0, output


def _package_file(tree: Path) -> str:
    """Where a child with ``PYTHONPATH=tree`` imports the package from."""
    return _cpu_child([sys.executable, "-c", "import mt_accuracy_ros; "
                       "print(mt_accuracy_ros.__file__)"], tree)[2].strip()


def panel_runs(shapes: list[str], sizes: list[int], folder: Path, repeats: int,
               baseline: Path | None, bytecode: bool = False) -> list[dict]:
    """Every (shape, size) ``repeats`` times, this tree and ``baseline`` alternating;
    ``bytecode``: each tree's modules compiled once before (untimed) and read compiled,
    else as the environment says (PYTHONDONTWRITEBYTECODE: compiled from source in
    every child)."""
    trees = {"after": ROOT} | ({"before": baseline} if baseline else {})
    caches = {label: folder / f"bytecode_{label}" if bytecode else None for label in trees}
    for label, tree in trees.items():
        if bytecode:
            _cpu_child([sys.executable, "-m", "compileall", "-q", str(tree / "mt_accuracy_ros")],
                       tree, caches[label])
        print(json.dumps({"tree": label, "imports": _package_file(tree),
                          "bytecode": "compiled once, read by every child" if bytecode else
                          "compiled from source in every child"
                          if os.environ.get("PYTHONDONTWRITEBYTECODE") else
                          "the tree's own __pycache__"}), flush=True)
    runs = []
    for readings in sizes:
        for shape in shapes:
            arguments = panel_command(shape, readings, folder)
            if arguments is None:
                print(json.dumps({"shape": shape, "readings": readings,
                                  "skipped": "the log holds fewer rows"}), flush=True)
                continue
            goal_s, goal_mb = GOALS.get(readings, (None, None))
            for _ in range(repeats):
                outputs = {}
                for label, tree in trees.items():
                    out = folder / f"{label}.json"
                    cpu, rss, text = _cpu_child([sys.executable, "-m", "mt_accuracy_ros.cli",
                                                 *arguments, "--json", str(out)], tree,
                                                caches[label])
                    outputs[label] = out.read_bytes()
                    named = [line.split()[1] for line in text.splitlines()
                             if line.startswith("named:")]
                    run = {"shape": shape, "readings": readings, "tree": label,
                           "cpu_s": round(cpu, 3), "peak_rss_mb": round(rss),
                           "goal_s": goal_s, "goal_mb": goal_mb,
                           "met": cpu <= goal_s and (goal_mb is None or rss <= goal_mb)
                           if goal_s else None, "named": named[:1]}
                    if label == "before":
                        run["same_json"] = outputs["before"] == outputs["after"]
                    runs.append(run)
                    print(json.dumps(run), flush=True)
    return runs


def panel_table(runs: list[dict]) -> str:
    """The panel as a markdown table: every run's CPU time, the ratio of medians."""
    import statistics

    def seconds(rows: list[dict]) -> str:
        return ", ".join(f"{r['cpu_s']:.2f}" for r in rows) or "-"

    lines = ["| shape | readings | after: CPU [s], every run | before [s] | before / after "
             "| peak RSS after [MB] | goal | met | same JSON |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    keys = list(dict.fromkeys((r["shape"], r["readings"]) for r in runs))
    for shape, readings in keys:
        mine = [r for r in runs if (r["shape"], r["readings"]) == (shape, readings)]
        after = [r for r in mine if r["tree"] == "after"]
        before = [r for r in mine if r["tree"] == "before"]
        goal_s, goal_mb = after[0]["goal_s"], after[0]["goal_mb"]
        goal = "-" if goal_s is None else f"{goal_s:g} s" + (f", {goal_mb:g} MB" if goal_mb
                                                             else "")
        met = "-" if goal_s is None else ("yes" if all(r["met"] for r in after) else "no")
        ratio, same = "-", "-"
        if before:
            ratio = statistics.median(r["cpu_s"] for r in before) / \
                statistics.median(r["cpu_s"] for r in after)
            ratio = f"{ratio:.2f}x"
            same = "yes" if all(r["same_json"] for r in before) else "NO"
        rss = [r["peak_rss_mb"] for r in after]
        lines.append(f"| {shape} | {readings:,} | {seconds(after)} | {seconds(before)} | "
                     f"{ratio} | {min(rss)}-{max(rss)} | {goal} | {met} | {same} |")
    return "\n".join(lines)


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
    parser.add_argument("--panel", action="store_true",
                        help="check on every shape of survey at every size (CPU time, peak RSS)")
    parser.add_argument("--shapes", nargs="+", choices=PANEL_SHAPES, default=list(PANEL_SHAPES))
    parser.add_argument("--baseline", type=Path, default=None, metavar="TREE",
                        help="--panel: also run another checkout's code, alternating")
    parser.add_argument("--bytecode", action="store_true",
                        help="--panel: each tree's modules compiled once, untimed, and read "
                             "compiled by every child, as an installed package's are (else a "
                             "child under PYTHONDONTWRITEBYTECODE compiles them from source)")
    args = parser.parse_args(argv)
    if args.diagnosis_child:
        diagnosis_child(*args.diagnosis_child)
        return 0
    _pin()
    if args.panel:
        with tempfile.TemporaryDirectory() as folder:
            runs = panel_runs(args.shapes, args.sizes, Path(folder), args.repeats,
                              args.baseline, args.bytecode)
        print(panel_table(runs))
        return 0
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
