"""Dead, stuck, gappy and jumping temperature sensors in surveys and bags, through the real CLI.

A survey's temperature columns (column map, role ``temperatures``) and a bag's
``/temperatures`` are judged by the one rule the thermal logs use
(:func:`mt_accuracy_ros.core.inputs.sensor_health.judge_sensors`): each problem named with
its rows - a survey's by the file's row numbers (the header is row 1), a bag's by the
reference readings' indices (1-based, in stamp order) - and the sensor or its rows left
out. A dead sensor's -180 is a sensor problem (named, left out), never refused as a
unit: the unit is refused only when most readings fit another one (kelvin, in
``test_survey_inputs.py``). Each class builds its input in ``tmp_path``, runs
``mt_accuracy_ros.cli.main`` and checks the exit code 0, the note printed and the same
note in the JSON's warnings, and which sensors the model was given.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

from mt_accuracy_ros.cli import main

ROWS = 150

#: (class, the input, the outcome: "refused: <key words of the one line>" or
#: "announced: <key words of the note>").
CLASSES = [
    ("survey_sensor_dead_on_every_row",
     "a survey's temperature column T3 reads -180 degC with a little noise on every row "
     "(an open thermocouple)",
     "announced: sensor T3: reads -180 degC, a physically absent value (dead) at file rows "
     "2-151 (150 of 150 rows) - left out of every model (its rows kept)"),
    ("survey_sensor_dead_from_a_row",
     "a survey's temperature column T3 reads -180 degC from file row 101 on",
     "announced: sensor T3: reads -180 degC, a physically absent value (dead) at file rows "
     "101-151 (51 of 150 rows) - left out of every model (its rows kept)"),
    ("survey_sensor_zero_from_a_row",
     "a survey's temperature column T3 reads exactly 0 from file row 121 on (a logger's "
     "empty value)",
     "announced: sensor T3: reads 0 degC, a physically absent value (dead) at file rows "
     "121-151 (31 of 150 rows) - left out of every model (its rows kept)"),
    ("survey_sensor_stuck",
     "a survey's temperature column T3 reads 21.5 degC on every row while T1 and T2 warm up",
     "announced: sensor T3: stuck at 21.5 degC while the others move at file rows 2-151 "
     "(150 of 150 rows) - left out of every model (its rows kept)"),
    ("survey_sensor_gaps",
     "a survey's temperature column T3 has empty cells on file rows 21-23 and a nan on 91",
     "announced: sensor T3: no reading at file rows 21-23, 91 (4 of 150 rows) - those rows "
     "left out; the survey: 146 of 150 rows used; 4 dropped (4 with a bad sensor reading)"),
    ("survey_sensor_jump",
     "a survey's temperature column T3 steps by +3 K at file row 82 (re-seated), no other "
     "sensor does",
     "announced: sensor T3: jumps by +3 K at file row 82 (no other sensor steps there) - "
     "left out of every model (which side is right cannot be told)"),
    ("bag_sensor_dead",
     "a bag whose /temperatures sensor T3 reads -180 degC in every message",
     "announced: sensor T3: reads -180 degC, a physically absent value (dead) at readings "
     "1-80 (80 of 80 readings) - left out of every model; readings numbered 1.. in stamp "
     "order"),
    ("bag_sensor_stuck",
     "a bag whose /temperatures sensor T3 reads 21.5 degC in every message while T1 and T2 "
     "warm up",
     "announced: sensor T3: stuck at 21.5 degC while the others move at readings 1-80 "
     "(80 of 80 readings) - left out of every model (its readings kept)"),
    ("bag_sensor_dropout",
     "a bag whose /temperatures sensor T3 gives NaN in the messages of readings 11-12",
     "announced: sensor T3: no reading at readings 11-12 (2 of 80 readings) - those "
     "readings left out; 2 reference readings with a bad sensor reading left out"),
]


# ------------------------------------------------------------------ the inputs
def _warming(rows: int, seed: int = 3) -> dict[str, np.ndarray]:
    """Three structure sensors warming up by about 2 K with 0.01 K of noise [degC]."""
    rng = np.random.default_rng(seed)
    rise = 2.0 * (1.0 - np.exp(-np.arange(rows) / 50.0))
    return {name: 20.0 + offset + scale * rise + rng.normal(0.0, 0.01, rows)
            for name, offset, scale in (("T1", 0.0, 1.0), ("T2", 0.4, 0.8),
                                        ("T3", 0.2, 0.9))}


def _survey(tmp_path, t3) -> list[str]:
    """A survey of ROWS rows (X travel, a scale error in um, T1..T3) with a column map;
    ``t3(values)`` makes T3 bad (a list of cell texts, or an array)."""
    x = np.linspace(0.0, 400.0, ROWS)
    dev = 3.2 + 44.9 * x / 400.0 + 0.5 * np.sin(2 * np.pi * x / 50.0)
    temps = _warming(ROWS)
    cells = {"t": [f"{v:g}" for v in np.arange(ROWS) * 10.0], "x": [f"{v:.4f}" for v in x],
             "dev_x": [f"{v:.4f}" for v in dev],
             **{n: [f"{v:.4f}" for v in temps[n]] for n in ("T1", "T2")}}
    bad = t3(temps["T3"].copy())
    cells["T3"] = bad if isinstance(bad, list) else [f"{v:.4f}" for v in bad]
    path = tmp_path / "survey.csv"
    path.write_text(",".join(cells) + "\n" + "\n".join(
        ",".join(cells[c][k] for c in cells) for k in range(ROWS)) + "\n")
    column_map = {"time": {"column": "t", "unit": "s"},
                  "positions": {"X": {"column": "x", "unit": "mm"}},
                  "errors": {"x": {"column": "dev_x", "unit": "um"}},
                  "temperatures": {n: {"column": n, "unit": "degC"} for n in ("T1", "T2", "T3")},
                  "uncertainty": {"value": 1.4, "unit": "um"}}
    (tmp_path / "map.yaml").write_text(yaml.safe_dump(column_map))
    return ["check", str(path), "--columns", str(tmp_path / "map.yaml")]


def _file_row(row: int) -> int:
    """The index of a file row's value among the data (the header is file row 1)."""
    return row - 2


def _dead_from(row: int, value: float):
    def make(t3):
        t3[_file_row(row):] = value
        return t3
    return make


def _gaps(t3):
    cells = [f"{v:.4f}" for v in t3]
    for row in (21, 22, 23):
        cells[_file_row(row)] = ""
    cells[_file_row(91)] = "nan"
    return cells


def _jump(t3):
    t3[_file_row(82):] += 3.0
    return t3


SURVEYS = {
    "survey_sensor_dead_on_every_row":
        lambda t3: -180.0 + np.random.default_rng(5).normal(0.0, 0.3, t3.size),
    "survey_sensor_dead_from_a_row": _dead_from(101, -180.0),
    "survey_sensor_zero_from_a_row": _dead_from(121, 0.0),
    "survey_sensor_stuck": lambda t3: np.full(t3.size, 21.5),
    "survey_sensor_gaps": _gaps,
    "survey_sensor_jump": _jump,
}

BAG_READINGS = 80


def _bag(tmp_path, t3) -> list[str]:
    """A bag of BAG_READINGS reference readings on a VMC (a Y-dependent error) and one
    /temperatures message at each reading's stamp (T1..T3, ``t3`` making T3 bad)."""
    from rclpy.serialization import serialize_message

    from mt_accuracy_msgs.msg import ReferenceMeasurement, TemperatureArray
    from mt_accuracy_ros.io.bag_writer import BagWriter
    from mt_accuracy_ros.io.fields import nanoseconds_to_stamp, pack_float64

    rng = np.random.default_rng(7)
    temps = _warming(BAG_READINGS)
    temps["T3"] = t3(temps["T3"].copy())
    names = ["T1", "T2", "T3"]
    t0 = 1_700_000_000 * 10**9
    with BagWriter(tmp_path / "bag") as bag:
        bag.add_topic("/reference/tcp_error", "mt_accuracy_msgs/msg/ReferenceMeasurement")
        bag.add_topic("/temperatures", "mt_accuracy_msgs/msg/TemperatureArray")
        for i in range(BAG_READINGS):
            stamp = t0 + i * 30 * 10**9
            message = TemperatureArray(sensor_names=names)
            message.header.stamp = nanoseconds_to_stamp(stamp)
            message.temperatures = pack_float64([temps[n][i] for n in names])
            bag.write("/temperatures", serialize_message(message), stamp)
            position = [rng.uniform(-0.3, 0.3), rng.uniform(-0.15, 0.15),
                        rng.uniform(-0.4, -0.05)]
            reading = ReferenceMeasurement(instrument="probe", command_axes=["x", "y", "z"])
            reading.header.stamp = nanoseconds_to_stamp(stamp)
            reading.command_positions = position
            reading.command_velocities = [0.0, 0.0, 0.0]
            reading.error.x = 20e-6 * position[1] + rng.normal(0.0, 0.5e-6)
            reading.error.y = rng.normal(0.0, 0.5e-6)
            reading.error.z = rng.normal(0.0, 0.5e-6)
            reading.measured = [True, True, True]
            reading.uncertainty = 1e-6
            bag.write("/reference/tcp_error", serialize_message(reading), stamp)
    return ["check", str(tmp_path / "bag"), "--model", "{machine: vmc}"]


def _nan_at(readings: tuple[int, ...]):
    def make(t3):
        t3[[r - 1 for r in readings]] = np.nan
        return t3
    return make


BAGS = {
    "bag_sensor_dead": lambda t3: np.full(t3.size, -180.0),
    "bag_sensor_stuck": lambda t3: np.full(t3.size, 21.5),
    "bag_sensor_dropout": _nan_at((11, 12)),
}

#: The exact words each class's note must carry (the outcome's key words, split where the
#: note says more in between: a measured level, the noise).
NOTES = {
    "survey_sensor_dead_on_every_row": [
        "sensor T3: reads -180", "degC, a physically absent value (dead) at file rows 2-151 "
        "(150 of 150 rows) - left out of every model (its rows kept)"],
    "survey_sensor_dead_from_a_row": [
        "sensor T3: reads -180 degC, a physically absent value (dead) at file rows 101-151 "
        "(51 of 150 rows) - left out of every model (its rows kept)"],
    "survey_sensor_zero_from_a_row": [
        "sensor T3: reads 0 degC, a physically absent value (dead) at file rows 121-151 "
        "(31 of 150 rows) - left out of every model (its rows kept)"],
    "survey_sensor_stuck": [
        "sensor T3: stuck at 21.5 degC while the others move at file rows 2-151 "
        "(150 of 150 rows) - left out of every model (its rows kept)"],
    "survey_sensor_gaps": [
        "sensor T3: no reading at file rows 21-23, 91 (4 of 150 rows) - those rows left out"],
    "survey_sensor_jump": [
        "sensor T3: jumps by +3", "K at file row 82 (its noise",
        "no other sensor steps there) - left out of every model (which side is right cannot "
        "be told)"],
    "bag_sensor_dead": [
        "sensor T3: reads -180 degC, a physically absent value (dead) at readings 1-80 "
        "(80 of 80 readings) - left out of every model (its readings kept)",
        "numbered 1.. in stamp order; reading 1 at stamp 1700000000000000000 ns"],
    "bag_sensor_stuck": [
        "sensor T3: stuck at 21.5 degC while the others move at readings 1-80 (80 of 80 "
        "readings) - left out of every model (its readings kept)"],
    "bag_sensor_dropout": [
        "sensor T3: no reading at readings 11-12 (2 of 80 readings) - those readings left out",
        "2 reference readings with a bad sensor reading left out"],
}

#: The sensors each class's model is given: the bad one left out, or kept with its rows gone.
KEPT = {name: ["T1", "T2"] for name in NOTES} | {"survey_sensor_gaps": ["T1", "T2", "T3"],
                                                 "bag_sensor_dropout": ["T1", "T2", "T3"]}


@pytest.mark.parametrize("name, described, outcome", CLASSES, ids=[c[0] for c in CLASSES])
def test_bad_sensor(name, described, outcome, tmp_path, capsys):
    args = _survey(tmp_path, SURVEYS[name]) if name in SURVEYS else _bag(tmp_path, BAGS[name])
    out_json = tmp_path / "out" / "summary.json"
    assert main([*args, "--json", str(out_json)]) == 0, capsys.readouterr().err
    printed = capsys.readouterr().out
    summary = json.loads(out_json.read_text())
    warnings = "\n".join(summary["warnings"])
    for words in NOTES[name]:
        assert words in printed and words in warnings, (words, printed)
    assert summary["sensors_kept"] == KEPT[name]
    # One note per finding: the healthy sensors are never named.
    assert "sensor T1" not in warnings and "sensor T2" not in warnings
    if name == "survey_sensor_gaps":
        # The four rows are left out and counted, as a log's are.
        assert summary["readings"] == 146 and summary["rows_dropped"] == 4
        assert "146 of 150 rows used; 4 dropped (4 with a bad sensor reading (see the " \
            "notes))" in printed
    elif name == "bag_sensor_dropout":
        assert summary["readings"] == BAG_READINGS - 2
    elif name.startswith("survey"):
        # A sensor left out keeps its rows: every row is used.
        assert summary["readings"] == ROWS and summary["rows_dropped"] == 0
    else:
        assert summary["readings"] == BAG_READINGS
