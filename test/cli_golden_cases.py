"""The ``mt-accuracy`` command's output on the README's cheap examples, pinned.

Each :class:`Case` is one command line; :func:`run_cases` runs them in order in one
directory (a later case may read what an earlier one wrote: the short simulation's bag)
and returns, per case, its exit code, stdout, stderr and - for a case with ``json`` - the
JSON summary it wrote. ``test/golden/cli/`` holds what they gave before the commands were
reshaped (one typed check result, command modules that raise): ``test_cli_golden.py``
compares the printed text byte for byte and the JSON key for key.

Run as a script to (re)write the goldens from the source tree on ``PYTHONPATH``::

    PYTHONPATH=. .venv/bin/python test/cli_golden_cases.py test/golden/cli

Do so only when an output changes on purpose, and say so in the commit.
"""
from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import sys
from dataclasses import dataclass
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent
GOLDEN = Path(__file__).resolve().parent / "golden" / "cli"
#: The terminal width argparse wraps help at (it reads COLUMNS).
COLUMNS = "100"
#: Stands for the run's directory in the outputs (the goldens hold no machine's paths).
TMP = "<tmp>"


@dataclass(frozen=True)
class Case:
    """One command line. ``{tmp}`` in an argument is the run's directory (the generated
    inputs are there: survey.csv, survey_map.yaml, days.csv); ``json``: ``--json
    {tmp}/<name>.json`` is added and its content compared."""

    name: str
    argv: tuple[str, ...]
    json: bool = False


FL = ("check", "data/fl_thermal/fl_thermal.csv")
SURVEY_COLUMNS = ("--col", "time=minutes:min", "--col", "pos.X=X_mm:mm", "--col",
                  "pos.Y=Y_mm:mm", "--col", "pos.Z=Z_mm:mm", "--col", "err.x=dev_x_um:um",
                  "--col", "err.y=dev_y_um:um", "--col", "err.z=dev_z_um:um", "--col",
                  "temp.column=T_col:degC")

HELP_CASES = [Case("help", ("--help",))] + [
    Case(f"help_{'_'.join(words).replace('-', '_')}", (*words, "--help")) for words in (
        ("demo",), ("info",), ("recover",), ("record",), ("simulate",), ("check",),
        ("fleet",), ("iso230-2",), ("play",), ("topic",), ("topic", "list"),
        ("topic", "info"), ("topic", "echo"), ("topic", "hz"), ("model",),
        ("model", "add"), ("model", "remove"), ("model", "refit"), ("model", "show"),
        ("ballbar",), ("probe",), ("export",))]

REFUSAL_CASES = [
    Case("usage_abbreviation", ("demo", "--rat", "2")),
    Case("demo_lockstep_rate", ("demo", "--lockstep", "--rate", "2")),
    Case("demo_niceness", ("demo", "--niceness", "30", "--out", "{tmp}/demo")),
    Case("info_talker", ("info", "data/rosbag2_samples/talker")),
    Case("info_multiple_files", ("info", "data/rosbag2_samples/multiple_files")),
    Case("recover_onto_itself", ("recover", "data/rosbag2_samples/talker",
                                 "data/rosbag2_samples/talker")),
    Case("record_negative_size", ("record", "--max-bag-size", "-1")),
    Case("play_bad_remap", ("play", "data/rosbag2_samples/talker", "--remap", "bad")),
    Case("play_zero_rate", ("play", "data/rosbag2_samples/talker", "-r", "0")),
    Case("simulate_stride_without_csv", ("simulate", "x.yaml", "--out", "{tmp}/o", "--no-csv",
                                         "--csv-stride", "2")),
    Case("check_csv_without_target", FL),
    Case("check_log_with_namespace", (*FL, "--target", "ch5_um", "--namespace", "/mt1")),
    Case("check_log_train_fraction", (*FL, "--target", "ch5_um", "--train-fraction", "0.95")),
    Case("check_log_zeroed_without_run", (*FL, "--target", "ch5_um", "--zeroed-runs")),
    Case("check_negative_auto", ("check", "{tmp}/no_bag", "--auto", "-1")),
    Case("check_survey_with_target", ("check", "{tmp}/survey.csv", "--columns",
                                      "{tmp}/survey_map.yaml", "--target", "dev_x_um")),
    Case("check_bag_without_references", ("check", "data/rosbag2_samples/talker")),
    Case("fleet_workers_with_scheduler", ("fleet", "x", "--scheduler", "tcp://h:1",
                                          "--workers", "2")),
    Case("iso230_expansion_per_k", ("iso230-2", "run.csv", "--expansion", "1e-5")),
    Case("iso230_axis_with_space", ("iso230-2", "run.csv", "--axis", "X Y")),
    Case("ballbar_zero_radius", ("ballbar", "runs.csv", "--radius-mm", "0")),
    Case("export_unilateral_without_twincat", ("export", "m.yaml", "--unilateral", "--out",
                                               "{tmp}/tables")),
]

CHECK_CASES = [
    # README: the thermal log of the FL_THERMAL data.
    Case("check_fl_thermal", (*FL, "--target", "ch5_um", "--inputs", "t*_C", "--driver",
                              "spindle_rpm", "--auto", "3", "--report", "{tmp}/fl/report.html"),
         json=True),
    # README: a log of many runs, the gauge zeroed every morning.
    Case("check_days_zeroed", ("check", "{tmp}/days.csv", "--run", "day", "--zeroed-runs",
                               "--target", "gauge_um", "--inputs", "T*_C", "--driver",
                               "spindle_rpm", "--auto", "3", "--report",
                               "{tmp}/days/report.html")),
    # README: a survey with a column map, on a named machine.
    Case("check_survey_machine", ("check", "{tmp}/survey.csv", "--columns",
                                  "{tmp}/survey_map.yaml", "--machine", "kidani_hmc", "--auto",
                                  "3", "--report", "{tmp}/survey/report.html"), json=True),
    # README: a survey mapped by --col flags, no machine (a generic one over its travel),
    # no uncertainty (the documented default taken, said).
    Case("check_survey_col_flags", ("check", "{tmp}/survey.csv", *SURVEY_COLUMNS, "--auto",
                                    "3")),
    # README: a simulation with a reference probe, then its bag checked.
    Case("simulate_short", ("simulate", "test/golden/short.yaml", "--out", "{tmp}/sim",
                            "--no-csv", "--reference-period", "0.25", "-q")),
    Case("check_bag", ("check", "{tmp}/sim/bag", "--auto", "2", "--report",
                       "{tmp}/bag/report.html"), json=True),
]

CASES = HELP_CASES + REFUSAL_CASES + CHECK_CASES


def write_inputs(tmp: Path) -> dict[str, str]:
    """The generated inputs in ``tmp`` (a logger's survey and a log of six zeroed days, from
    the studies' seeded generators); returns each file's SHA-256."""
    from studies.foreign_machine import make_trial
    from studies.multirun_logs import write_log
    from studies.survey_files import write_logger_survey

    trial = make_trial("kidani_hmc", ("ballscrew_pitch",), 1000, readings=400)
    write_logger_survey(trial, tmp / "survey.csv", tmp / "survey_map.yaml")
    write_log(tmp / "days.csv", 3, days=6, zeroed=True)
    return {name: hashlib.sha256((tmp / name).read_bytes()).hexdigest()
            for name in ("survey.csv", "survey_map.yaml", "days.csv")}


def run_case(case: Case, tmp: Path) -> dict:
    """(exit code, stdout, stderr, JSON summary or None) of one case, run in-process from
    the repository's root with the run's directory written as :data:`TMP`."""
    from mt_accuracy_ros.cli import main

    argv = [a.replace("{tmp}", str(tmp)) for a in case.argv]
    if case.json:
        argv += ["--json", str(tmp / f"{case.name}.json")]
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:      # --help, and argparse's own usage errors
            code = exc.code if isinstance(exc.code, int) else 1
    summary = None
    if case.json and (tmp / f"{case.name}.json").is_file():
        summary = json.loads((tmp / f"{case.name}.json").read_text().replace(str(tmp), TMP))
    return {"code": code, "stdout": out.getvalue().replace(str(tmp), TMP),
            "stderr": err.getvalue().replace(str(tmp), TMP), "json": summary}


def transcript(case: Case, outcome: dict) -> str:
    """A case's printed outcome as the golden file holds it."""
    return (f"$ mt-accuracy {' '.join(case.argv)}\nexit: {outcome['code']}\n--- stdout\n"
            f"{outcome['stdout']}--- stderr\n{outcome['stderr']}")


@contextlib.contextmanager
def environment(tmp: Path):
    """The cases' surroundings: the repository's root as the working directory, argparse
    wrapping at :data:`COLUMNS`."""
    before, columns = os.getcwd(), os.environ.get("COLUMNS")
    os.chdir(REPO_ROOT)
    os.environ["COLUMNS"] = COLUMNS
    try:
        yield
    finally:
        os.chdir(before)
        if columns is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = columns


def run_cases(tmp: Path) -> tuple[dict[str, str], dict[str, dict]]:
    """(the inputs' SHA-256, each case's outcome by name), every case run in order."""
    with environment(tmp):
        digests = write_inputs(tmp)
        return digests, {case.name: run_case(case, tmp) for case in CASES}


def write_goldens(directory: Path) -> None:
    """Every case's transcript (``<name>.txt``), JSON summary (``<name>.json``) and the
    inputs' digests (``inputs.json``) into ``directory``."""
    import tempfile

    directory.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as name:
        digests, outcomes = run_cases(Path(name))
    (directory / "inputs.json").write_text(json.dumps(digests, indent=1) + "\n")
    for case in CASES:
        (directory / f"{case.name}.txt").write_text(transcript(case, outcomes[case.name]))
        if case.json:
            # The schema's version is compared by its own rule, not held as a value.
            summary = {k: v for k, v in outcomes[case.name]["json"].items()
                       if k != "schema_version"}
            (directory / f"{case.name}.json").write_text(json.dumps(summary, indent=1) + "\n")


if __name__ == "__main__":
    sys.path.insert(0, str(REPO_ROOT))
    write_goldens(Path(sys.argv[1]) if len(sys.argv) > 1 else GOLDEN)
