"""Bad survey, column-map, laser-run, ball-bar and probing files through the real CLI.

Every quantity is read in a stated unit or refused; values implausible in their unit are
refused naming the unit they look like; a default that is taken is said. Each class
builds its bad input in ``tmp_path``, runs ``mt_accuracy_ros.cli.main`` and checks the
outcome: a refusal is exit code 2, ONE line on stderr with the key words, and no JSON
written; an announced decision is exit code 0 with the note printed and in the JSON.
"""
from __future__ import annotations

import json
import random

import numpy as np
import pytest
import yaml

from mt_accuracy_ros.cli import main

#: (class, the input, the outcome: "refused: <key words of the one line>" or
#: "announced: <key words of the note>").
CLASSES = [
    ("survey_error_column_without_unit",
     "a survey's column map names the error column dev_x with no unit (map or name)",
     "refused: column dev_x (err.x) has no unit: give it in the map ({column: dev_x, "
     "unit: um}), the flag (--col err.x=dev_x:um) or the name (dev_x_um)"),
    ("survey_position_flag_without_unit",
     "a survey's position given as --col pos.X=x (no :UNIT, no unit in the name)",
     "refused: column x (pos.X) has no unit"),
    ("survey_time_without_unit",
     "a survey's time column t mapped with no unit",
     "refused: column t (time) has no unit"),
    ("survey_temperature_without_unit",
     "a survey's temperature column T3 mapped with no unit",
     "refused: column T3 (temp.T3) has no unit"),
    ("survey_bare_uncertainty",
     "a column map's uncertainty: 1.4 without a unit",
     "refused: uncertainty: 1.4 has no unit; give it as uncertainty: {value: 1.4, unit: um}"),
    ("survey_bare_tool_offset",
     "a column map's tool_offset: -150 without a unit",
     "refused: tool_offset: -150 has no unit; give it as tool_offset: {value: -150, "
     "unit: mm}"),
    ("survey_errors_in_um_declared_m",
     "a survey's errors in micrometres declared as metres (a 48 m error)",
     "refused: column dev_x (err.x): values 3.2 … 48.1 declared m look like µm"),
    ("survey_positions_in_mm_declared_m",
     "a survey's positions in millimetres declared as metres (a 400 m travel)",
     "refused: column x (pos.X): values 0 … 400 declared m look like mm"),
    ("survey_kelvin_declared_celsius",
     "a survey's temperature T3 in kelvin (293 ... 310) declared as degC",
     "refused: column T3 (temp.T3): values 293.1 … 310 declared °C look like K"),
    ("survey_spindle_rpm_declared_rad_s",
     "a survey's spindle speed in rpm (24000) declared as rad/s",
     "refused: column S (spindle): value 2.4e+04 declared rad/s looks like rpm"),
    ("survey_feed_mm_min_declared_m_s",
     "a survey's feed in mm/min (3000) declared as m/s",
     "refused: column F (vel.X): value 3000 declared m/s looks like mm/min"),
    ("survey_uncertainty_in_m",
     "a column map's uncertainty {value: 1.4, unit: m}",
     "refused: uncertainty: value 1.4 declared m looks like µm"),
    ("survey_unknown_col_role",
     "a survey flag --col position.X=x:mm (no such role)",
     "refused: --col 'position.X=x:mm': unknown role 'position.X'; known roles: time, pos.X, "
     "err.x, temp.<sensor>"),
    ("survey_unknown_col_unit",
     "a survey flag --col err.x=dev_x:microns (no such unit)",
     "refused: --col 'err.x=dev_x:microns': unknown length unit 'microns'; known: m, mm, um"),
    ("survey_without_uncertainty",
     "a survey whose map states no instrument uncertainty",
     "announced: uncertainty: the column map states none; 1 um (k = 2) assumed"),
    ("laser_target_without_unit",
     "a laser run whose header says target (no unit) and no --col gives one",
     "refused: target column 'target' has no unit: give it in the header (target_mm, "
     "target [mm]) or the flag (--col target=target:mm)"),
    ("laser_deviation_without_unit",
     "a laser run whose header says deviation (no unit)",
     "refused: deviation column 'deviation' has no unit"),
    ("laser_targets_in_m_labelled_mm",
     "a laser run's targets in metres under target_mm (a 0.42 mm travel)",
     "refused: target column 'target_mm': values 0.0125 … 0.43 declared mm span 0.4175 mm, "
     "an implausible travel; look like m"),
    ("laser_deviations_in_mm_labelled_um",
     "a laser run's deviations in millimetres under deviation_um (nm figures)",
     "refused: deviation column 'deviation_um'"),
    ("laser_nan_deviation",
     "a laser run with nan in a deviation cell",
     "refused: run.csv: row 5 column deviation_um: nan is not finite"),
    ("laser_inf_target",
     "a laser run with inf in a target cell",
     "refused: run.csv: row 5 column target_mm: inf is not finite"),
    ("laser_sideways_direction",
     "a laser run with the direction 'sideways'",
     "refused: run.csv: row 5 column direction: 'sideways' is not a direction"),
    ("laser_unknown_col_role",
     "a laser run flag --col speed=x (no such role)",
     "refused: --col 'speed=x': expected ROLE=COLUMN[:UNIT] with ROLE one of target"),
    ("ballbar_bar_length_in_m",
     "a ball-bar file with the bar lengths in metres under bar_mm",
     "refused: column bar_mm: values 0.1 … 0.15 declared mm look like m"),
    ("ballbar_change_in_mm",
     "a ball-bar file with the length changes in millimetres under change_um",
     "refused: column change_um: values"),
    ("ballbar_header_without_units",
     "a ball-bar file whose header names no units (bar, angle, change)",
     "refused: missing column(s) bar_mm, angle_deg, change_um"),
    ("ballbar_units_said",
     "a ball-bar file in the format's units",
     "announced: units as the ball-bar format defines them: bar_mm in mm, angle_deg in deg, "
     "change_um in um"),
    ("probing_touches_in_um_labelled_mm",
     "a probing file with the touch points in micrometres under px/py/pz_mm",
     "refused: column px/py/pz_mm: values"),
]


# ------------------------------------------------------------------ surveys
def _survey(tmp_path, columns: dict[str, list], rows: int = 40) -> str:
    path = tmp_path / "survey.csv"
    path.write_text(",".join(columns) + "\n" + "\n".join(
        ",".join(f"{columns[c][k]:.6g}" for c in columns) for k in range(rows)) + "\n")
    return str(path)


def _survey_columns(rows: int = 40) -> dict[str, list]:
    x = np.linspace(0.0, 400.0, rows)
    # A scale error with a periodic part: 3.2 um at the first row, 48.1 um at the last.
    return {"t": list(np.arange(rows) * 10.0), "x": list(x),
            "dev_x": list(3.2 + 44.9 * x / 400.0 + 0.5 * np.sin(2 * np.pi * x / 50.0)),
            "T3": list(20.0 + np.linspace(0, 2, rows)), "S": [24000.0] * rows,
            "F": [3000.0] * rows}


GOOD_MAP = {"time": {"column": "t", "unit": "s"},
            "positions": {"X": {"column": "x", "unit": "mm"}},
            "errors": {"x": {"column": "dev_x", "unit": "um"}},
            "uncertainty": {"value": 1.4, "unit": "um"}}


def _with_map(tmp_path, change=None, columns=None) -> list[str]:
    data = json.loads(json.dumps(GOOD_MAP))
    if change:
        change(data)
    (tmp_path / "map.yaml").write_text(yaml.safe_dump(data))
    return [_survey(tmp_path, columns or _survey_columns()), "--columns",
            str(tmp_path / "map.yaml")]


def _check(tmp_path, change=None, columns=None, flags=()) -> list[str]:
    return ["check", *_with_map(tmp_path, change, columns), *flags]


def _flags_only(tmp_path, flags) -> list[str]:
    return ["check", _survey(tmp_path, _survey_columns()), *flags]


def _kelvin_columns():
    columns = _survey_columns()
    columns["T3"] = list(293.15 + np.linspace(0, 16.85, 40))
    return columns


SURVEYS = {
    "survey_error_column_without_unit":
        lambda p: _check(p, lambda m: m["errors"].update({"x": "dev_x"})),
    "survey_position_flag_without_unit":
        lambda p: _flags_only(p, ["--col", "pos.X=x", "--col", "err.x=dev_x:um"]),
    "survey_time_without_unit":
        lambda p: _check(p, lambda m: m.update({"time": {"column": "t"}})),
    "survey_temperature_without_unit":
        lambda p: _check(p, lambda m: m.update({"temperatures": {"T3": "T3"}})),
    "survey_bare_uncertainty": lambda p: _check(p, lambda m: m.update({"uncertainty": 1.4})),
    "survey_bare_tool_offset": lambda p: _check(p, lambda m: m.update({"tool_offset": -150})),
    "survey_errors_in_um_declared_m":
        lambda p: _check(p, lambda m: m["errors"]["x"].update({"unit": "m"})),
    "survey_positions_in_mm_declared_m":
        lambda p: _check(p, lambda m: m["positions"]["X"].update({"unit": "m"})),
    "survey_kelvin_declared_celsius":
        lambda p: _check(p, lambda m: m.update(
            {"temperatures": {"T3": {"column": "T3", "unit": "degC"}}}), _kelvin_columns()),
    "survey_spindle_rpm_declared_rad_s":
        lambda p: _check(p, lambda m: m.update(
            {"spindle_speed": {"column": "S", "unit": "rad/s"}})),
    "survey_feed_mm_min_declared_m_s":
        lambda p: _check(p, lambda m: m.update(
            {"velocities": {"X": {"column": "F", "unit": "m/s"}}})),
    "survey_uncertainty_in_m":
        lambda p: _check(p, lambda m: m.update({"uncertainty": {"value": 1.4, "unit": "m"}})),
    "survey_unknown_col_role":
        lambda p: _flags_only(p, ["--col", "position.X=x:mm", "--col", "err.x=dev_x:um"]),
    "survey_unknown_col_unit":
        lambda p: _flags_only(p, ["--col", "pos.X=x:mm", "--col", "err.x=dev_x:microns"]),
    "survey_without_uncertainty":
        lambda p: _check(p, lambda m: m.pop("uncertainty")),
}


# ------------------------------------------------------------------ laser runs
TARGETS_MM = [12.5, 70.0, 131.0, 190.5, 250.0, 312.0, 371.5, 430.0]


def _laser(tmp_path, header="target_mm,deviation_um", target_scale=1.0,
           deviation_scale=1.0, bad_row=None, directions=False) -> list[str]:
    """Five bidirectional runs; ``bad_row`` replaces the 4th data row (file row 5)."""
    rng = random.Random(4)
    lines = [header + (",direction" if directions else "")]
    for _ in range(5):
        for direction in (1, -1):
            order = TARGETS_MM if direction > 0 else list(reversed(TARGETS_MM))
            for i, target in enumerate(order):
                deviation = 1.8 * (i % 3) - 1.0 + 1.2 * direction + rng.gauss(0, 0.25)
                lines.append(f"{target * target_scale:.7g},{deviation * deviation_scale:.7g}"
                             + (f",{'+' if direction > 0 else '-'}" if directions else ""))
    if bad_row is not None:
        lines[4] = bad_row
    (tmp_path / "run.csv").write_text("\n".join(lines) + "\n")
    return ["iso230-2", str(tmp_path / "run.csv")]


LASER = {
    "laser_target_without_unit": lambda p: _laser(p, "target,deviation_um"),
    "laser_deviation_without_unit": lambda p: _laser(p, "target_mm,deviation"),
    "laser_targets_in_m_labelled_mm": lambda p: _laser(p, target_scale=1e-3),
    "laser_deviations_in_mm_labelled_um": lambda p: _laser(p, deviation_scale=1e-3),
    "laser_nan_deviation": lambda p: _laser(p, bad_row="190.5,nan"),
    "laser_inf_target": lambda p: _laser(p, bad_row="inf,1.0"),
    "laser_sideways_direction":
        lambda p: _laser(p, bad_row="190.5,1.0,sideways", directions=True),
    "laser_unknown_col_role": lambda p: _laser(p) + ["--col", "speed=x"],
}


# ------------------------------------------------------------------ ball bar, probing
def _ballbar(tmp_path, bar_scale=1.0, change_scale=1.0, header=None) -> list[str]:
    rng = np.random.default_rng(3)
    lines = [header or "bar_mm,repetition,angle_deg,change_um"]
    for bar in (100.0, 150.0):
        for repetition in (1, 2):
            for angle in range(0, 360, 30):
                change = 2.0 * np.cos(np.radians(angle)) + rng.normal(0, 0.1)
                lines.append(f"{bar * bar_scale:g},{repetition},{angle},"
                             f"{change * change_scale:.6g}")
    (tmp_path / "ballbar.csv").write_text("\n".join(lines) + "\n")
    return ["ballbar", str(tmp_path / "ballbar.csv")]


def _probing_in_um(tmp_path) -> list[str]:
    path = tmp_path / "probe.csv"
    assert main(["probe", str(path), "--simulate", "1"]) == 0
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    touch = [header.index(c) for c in ("px_mm", "py_mm", "pz_mm")]
    scaled = [",".join(f"{float(v) * 1e3:.6f}" if j in touch else v
                       for j, v in enumerate(line.split(","))) for line in lines[1:]]
    path.write_text("\n".join([lines[0], *scaled]) + "\n")
    return ["probe", str(path)]


ROTARY = {
    "ballbar_bar_length_in_m": lambda p: _ballbar(p, bar_scale=1e-3),
    "ballbar_change_in_mm": lambda p: _ballbar(p, change_scale=1e-3),
    "ballbar_header_without_units":
        lambda p: _ballbar(p, header="bar,repetition,angle,change"),
    "ballbar_units_said": lambda p: _ballbar(p),
    "probing_touches_in_um_labelled_mm": _probing_in_um,
}

BUILDERS = {**SURVEYS, **LASER, **ROTARY}


def test_every_class_has_a_builder():
    assert sorted(BUILDERS) == sorted(name for name, _, _ in CLASSES)
    assert len(CLASSES) >= 22


@pytest.mark.parametrize("name, description, outcome", CLASSES, ids=[c[0] for c in CLASSES])
def test_bad_survey_input(tmp_path, capsys, name, description, outcome):
    argv = BUILDERS[name](tmp_path)
    capsys.readouterr()                      # what a builder's own run printed
    out_json = tmp_path / "summary.json"
    code = main([*argv, "--json", str(out_json)])
    captured = capsys.readouterr()
    kind, _, words = outcome.partition(": ")
    if kind == "refused":
        err = captured.err.strip()
        assert code == 2, captured.out + captured.err
        assert words in err and "\n" not in err, err
        assert "Traceback" not in err
        assert not out_json.exists()
    else:
        assert code == 0, captured.err
        assert words in captured.out
        assert words in out_json.read_text()
