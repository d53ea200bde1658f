"""Every temperature sensor judged before use: dead, out of range, stuck, dropping out, jumping.

Each finding names the sensor, its kind and its rows, and says what was done: the sensor
left out (most of its rows bad, or a jump) or its few bad rows left out."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mt_accuracy_ros.core.inputs.sensor_health import (SensorFinding, judge_sensors,
                                                       noise_from_differences, row_ranges)

ROWS = 300


def _good(seed: int = 0) -> dict[str, np.ndarray]:
    """Two sensors warming up 3 K and 1.5 K, 0.01 K of noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(ROWS)
    return {"a": 20 + 3 * (1 - np.exp(-t / 100)) + rng.normal(0, 0.01, ROWS),
            "b": 20 + 1.5 * (1 - np.exp(-t / 200)) + rng.normal(0, 0.01, ROWS)}


def _third(edit, seed: int = 2) -> np.ndarray:
    rng = np.random.default_rng(seed)
    values = 21 + 2 * (1 - np.exp(-np.arange(ROWS) / 150)) + rng.normal(0, 0.01, ROWS)
    edit(values)
    return values


def _judge(values: np.ndarray, **kwargs):
    sensors = _good()
    sensors["c"] = values
    return judge_sensors(sensors, **kwargs)


def _only(health) -> SensorFinding:
    (finding,) = health.findings
    return finding


def test_good_sensors_and_the_real_fl_thermal_log_give_no_finding(data_dir: Path):
    assert judge_sensors(_good()).findings == []
    log = np.genfromtxt(data_dir / "fl_thermal" / "fl_thermal.csv", delimiter=",", names=True)
    sensors = {n: log[n] for n in log.dtype.names if n.endswith("_C")}
    health = judge_sensors(sensors)
    # t16_C's draught spikes (2.9 K for a few rows) are no step: it stays.
    assert health.findings == [] and list(health.kept) == list(sensors)


@pytest.mark.parametrize("edit, kind, rows, words", [
    (lambda v: v.__setitem__(slice(None), -180 + np.random.default_rng(1).normal(0, .3, ROWS)),
     "dead", (1, ROWS), "a physically absent value (dead) at data rows 1-300"),
    (lambda v: v.__setitem__(slice(200, None), -180.0), "dead", (201, ROWS),
     "reads -180 degC, a physically absent value (dead) at data rows 201-300 (100 of 300 rows)"),
    (lambda v: v.__setitem__(slice(100, None), 0.0), "dead", (101, ROWS),
     "reads 0 degC, a physically absent value (dead) at data rows 101-300"),
    (lambda v: v.__setitem__(slice(None), -273.15), "dead", (1, ROWS), "reads -273.1 degC"),
    (lambda v: v.__setitem__(slice(None), 21.5), "stuck", (1, ROWS),
     "stuck at 21.5 degC while the others move at data rows 1-300"),
    (lambda v: v.__setitem__(slice(0, 250), np.nan), "dropout", (1, 250),
     "sensor c: no reading in 250 of 300 rows - dead"),
])
def test_a_mostly_bad_sensor_is_named_with_its_rows_and_left_out(edit, kind, rows, words):
    health = _judge(_third(edit))
    finding = _only(health)
    assert (finding.sensor, finding.kind, finding.left_out) == ("c", kind, True)
    assert (finding.rows[0], finding.rows[-1]) == rows
    assert words in finding.text
    assert finding.text.endswith("left out of every model (its rows kept)")
    assert list(health.kept) == ["a", "b"] and health.left_out == ["c"]


@pytest.mark.parametrize("edit, kind, words", [
    (lambda v: v.__setitem__(slice(280, None), 850.0), "dead",
     "sensor c: reads 850 degC, a physically absent value (dead) at data rows 281-300 "
     "(20 of 300 rows) - those rows left out"),
    (lambda v: v.__setitem__(slice(10, 15), 95.0), "out_of_range",
     "sensor c: reads 95 degC, outside a workshop's -30 ... 80 degC at data rows 11-15 "
     "(5 of 300 rows) - those rows left out"),
    (lambda v: v.__setitem__([10, 11, 12, 77], np.nan), "dropout",
     "sensor c: no reading at data rows 11-13, 78 (4 of 300 rows) - those rows left out"),
])
def test_a_few_bad_rows_are_left_out_and_named_the_sensor_kept(edit, kind, words):
    health = _judge(_third(edit))
    finding = _only(health)
    assert finding.kind == kind and not finding.left_out and finding.text == words
    kept = health.kept["c"]
    assert np.isnan(kept[np.array(finding.rows) - 1]).all()
    assert np.isfinite(np.delete(kept, np.array(finding.rows) - 1)).all()


def test_a_stretch_stuck_within_its_quantisation_is_named():
    values = _third(lambda v: None)
    values = np.round(values, 1)
    values[50:150] = values[50] + np.tile([0.0, 0.1], 50)   # frozen, flickering one quantum
    finding = _only(_judge(values))
    # (the greedy stretch may start a row late: the row before still fits the one before)
    assert finding.kind == "stuck" and finding.rows[0] <= 52 and finding.rows[-1] == 150
    assert finding.left_out      # a third of the rows: the sensor goes


def test_a_quiet_stretch_while_the_others_rest_too_is_not_stuck():
    sensors = {name: np.round(np.full(ROWS, level), 1) for name, level in
               (("a", 20.0), ("b", 21.0), ("c", 22.0))}
    sensors["a"][200:] += 0.1            # one quantum: resting, not moving
    assert judge_sensors(sensors).findings == []


def test_a_step_no_other_sensor_shares_is_a_jump_and_the_sensor_goes():
    values = _third(lambda v: v.__setitem__(slice(150, None), v[150:] + 3.0))
    finding = _only(_judge(values))
    assert finding.kind == "jumping" and finding.left_out and finding.rows[0] == 151
    assert finding.text.startswith("sensor c: jumps by +3")
    assert "at data row 151" in finding.text


def test_a_step_every_sensor_shares_or_at_a_run_start_is_no_jump():
    sensors = {name: values.copy() for name, values in _good().items()}
    sensors["c"] = _third(lambda v: None)
    for values in sensors.values():
        values[150:] += 3.0                  # a door opened on the whole machine
    assert judge_sensors(sensors).findings == []
    alone = _third(lambda v: v.__setitem__(slice(150, None), v[150:] + 3.0))
    runs = np.repeat([0, 1], 150)
    assert _judge(alone, run_of_row=runs, run_names=["mon", "tue"]).findings == []
    breaks = np.zeros(ROWS, bool)
    breaks[150] = True                       # a clock jump between the two halves
    assert _judge(alone, breaks=breaks).findings == []


def test_a_sensor_dead_in_one_run_is_left_out_naming_the_run_and_file_rows():
    values = _third(lambda v: v.__setitem__(slice(100, 200), -180.0))
    runs = np.repeat([0, 1, 2], 100)
    rows = np.arange(ROWS) + 10          # the file's data rows (some dropped before)
    finding = _only(_judge(values, run_of_row=runs, run_names=["mon", "tue", "wed"],
                           data_rows=rows))
    assert finding.rows == tuple(range(110, 210)) and finding.left_out
    assert "at data rows 110-209 (100 of 300 rows) (run tue) - left out" in finding.text


def test_row_ranges_and_the_noise_rule():
    assert row_ranges([3, 4, 5, 9, 12, 13, 20, 30]) == "3-5, 9, 12-13 and 2 more ranges"
    assert row_ranges([]) == "no row"
    rng = np.random.default_rng(0)
    smooth = np.linspace(0, 5, 5000) + rng.normal(0, 0.02, 5000)
    assert noise_from_differences(smooth) == pytest.approx(0.02, rel=0.05)


def test_a_fast_warm_up_of_one_sensor_alone_is_no_jump():
    # A spindle sensor (0.03 K noise) rising 6 K with a time constant of 3 readings: +2.2 K
    # in its first row, then +1.6, +1.2 K ... - far beyond 30 noises, but over several
    # readings; the signal a thermal model needs, never a re-seated sensor.
    rng = np.random.default_rng(41)
    t = np.arange(ROWS)
    spindle = 22 + 6 * (1 - np.exp(-np.clip(t - 3, 0, None) / 3)) + rng.normal(0, 0.03, ROWS)
    assert spindle[4] - spindle[3] > 1.5
    assert _judge(spindle).findings == []
    # The same sensor re-seated at row 200 (a 3 K step between two readings) still is one.
    spindle[200:] += 3.0
    finding = _only(_judge(spindle))
    assert finding.kind == "jumping" and finding.rows[0] == 201


def test_a_heated_part_above_a_structure_s_range_is_kept_and_said():
    """A printer's bed heater rising from the room's 20 degC to 105 degC: above a structure's
    80 degC but starting where the other sensors start, so in their unit - kept, said.
    A degF sensor (68 ... 221 as declared degC) starts 48 K above them: left out, named."""
    t = np.arange(ROWS)
    rng = np.random.default_rng(4)
    heater = 20 + 85 * (1 - np.exp(-t / 30)) + rng.normal(0, 0.05, ROWS)
    health = _judge(heater)
    finding = _only(health)
    assert (finding.kind, finding.left_out, finding.rows) == ("heated", False, ())
    assert finding.text.startswith("sensor c: reads up to 10") and \
        "above a structure's 80 degC, from 19.9" in finding.text and \
        finding.text.endswith("taken as a heated part (a heater, a bed, a spindle) and kept - "
                              "give its unit if it is not degC")
    assert list(health.kept) == ["a", "b", "c"] and np.isfinite(health.kept["c"]).all()
    in_fahrenheit = _judge(heater * 1.8 + 32.0)
    kinds = [f.kind for f in in_fahrenheit.findings]
    assert "out_of_range" in kinds and "heated" not in kinds       # (above 200: dead too)
    assert in_fahrenheit.left_out == ["c"]


def test_a_finding_names_only_the_runs_its_own_rows_lie_in():
    """Out of range in run x, silent in run y: each line names its own run."""
    values = _third(lambda v: None)
    values[:120] = 95.0 + np.linspace(0, 1, 120)          # run x: a wrong channel
    values[200:] = np.nan                                 # run y: no reading
    runs = np.repeat([0, 1], [150, 150])
    health = _judge(values, run_of_row=runs, run_names=["x", "y"])
    texts = {f.kind: f.text for f in health.findings}
    assert "(run x)" in texts["out_of_range"] and "(run y)" not in texts["out_of_range"]
    assert "(run y)" in texts["dropout"] and "(run x)" not in texts["dropout"]
