"""A log made of many runs: run labels, stitched time, splits and blocks at run boundaries,
unit slips and dead sensors (issue 40)."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.effects.variables import (Variables, first_order_lag, run_starts_of,
                                                    subset_run_starts)
from mt_accuracy_ros.core.errors import InputDataError
from mt_accuracy_ros.core.workbench.log_runs import (clock_breaks, leave_out_dead_sensors,
                                                     run_level_notes,
                                                     mixed_units_problem, run_blocks, run_labels,
                                                     split_at_run, stitched_time)


def test_run_labels_keep_the_file_order_and_refuse_a_gap_or_a_one_row_run():
    index, names = run_labels(["mon", "mon", "tue", "tue", "tue", "2024-05-01", "2024-05-01"])
    assert names == ["mon", "tue", "2024-05-01"]
    assert index.tolist() == [0, 0, 1, 1, 1, 2, 2]
    with pytest.raises(InputDataError) as gap:
        run_labels(["a", "a", "b", "b", "a", "a"], data_rows=np.arange(10, 16), column="day")
    assert str(gap.value).startswith("the day column has a gap: run 'a' at data rows 10-11, "
                                     "again at data row 14")
    with pytest.raises(InputDataError) as single:
        run_labels(["a", "a", "b", "c", "c"], data_rows=np.arange(1, 6))
    assert "run 'b' of the run column has 1 row (data row 3): a run needs at least 2" \
        in str(single.value)


def test_time_may_restart_between_runs_never_inside_one():
    runs = np.array([0, 0, 0, 1, 1, 1])
    t = stitched_time(np.array([0.0, 60, 120, 0, 60, 60]), runs, ["d1", "d2"])
    # Run 2 starts one of run 1's median steps (60 s) after its end; equal stamps stay.
    assert t.tolist() == [0, 60, 120, 180, 240, 240]
    with pytest.raises(InputDataError, match="the time goes back inside run 'd2' at data row 6"):
        stitched_time(np.array([0.0, 60, 120, 0, 60, 30]), runs, ["d1", "d2"])


def test_the_split_falls_on_the_nearest_run_boundary_and_blocks_are_whole_runs():
    runs = np.repeat(np.arange(5), [10, 30, 10, 40, 10])        # starts 0, 10, 40, 50, 90
    train = split_at_run(runs, 0.5)                               # 50 rows: boundary 50
    assert train.sum() == 50 and runs[train].max() == 2
    assert split_at_run(runs, 0.3).sum() == 40
    with pytest.raises(InputDataError, match="one run"):
        split_at_run(np.zeros(20, dtype=int), 0.5)
    blocks = run_blocks(runs, 6)
    # Every run inside one block, blocks numbered 0, 1, ... in time order.
    for k in range(5):
        assert np.unique(blocks[runs == k]).size == 1
    assert blocks[0] == 0 and np.all(np.diff(blocks) >= 0) and np.all(np.diff(blocks) <= 1)
    assert run_blocks(np.repeat(np.arange(12), 5), 6)[-1] == 5       # at most 6 blocks
    assert run_blocks(np.zeros(10, dtype=int), 6) is None


def test_a_run_in_other_units_is_named():
    rng = np.random.default_rng(1)
    runs = np.repeat(np.arange(4), 50)
    target = rng.normal(0, 2e-6, 200)
    target[100:150] *= 1000.0                                    # a day logged in mm as um
    temperatures = {"t1": 20 + rng.normal(0, 0.3, 200)}
    assert mixed_units_problem(target, temperatures, runs, list("abcd"), False).startswith(
        "run 'c': its target spans")
    target[100:150] /= 1000.0
    assert mixed_units_problem(target, temperatures, runs, list("abcd"), False) == ""
    temperatures["t1"][50:100] = temperatures["t1"][50:100] * 1.8 + 32.0   # degF
    problem = mixed_units_problem(target, temperatures, runs, list("abcd"), False)
    assert problem.startswith("run 'b': sensor t1 reads 67.9") and "degF" in problem


def test_a_dead_sensor_is_left_out_not_its_rows():
    runs = np.repeat(np.arange(3), 100)
    good = np.linspace(20, 22, 300)
    dead = good.copy()
    dead[100:200] = np.nan                                       # run 'tue' open-circuit
    holes = good.copy()
    holes[[5, 250]] = np.nan                                     # two glitches
    kept, notes = leave_out_dead_sensors({"a": good, "b": dead, "c": holes}, runs,
                                         ["mon", "tue", "wed"])
    assert list(kept) == ["a", "c"]
    # The glitches are named too (never silent): their rows go, the sensor stays.
    assert notes == ["sensor b: no reading in 100 of 300 rows (run tue) - dead, left out of "
                     "every model (its rows kept)",
                     "sensor c: no reading at data rows 6, 251 (2 of 300 rows) - those rows "
                     "left out"]


def test_lags_restart_at_each_run_from_its_first_reading():
    rng = np.random.default_rng(3)
    t = np.concatenate([np.arange(50) * 60.0, np.arange(40) * 30.0 + 7 * 86400.0])
    u = rng.normal(0, 1, 90).cumsum()
    variables = Variables({"X": np.zeros(90)}, t, run_starts=[0, 50])
    lagged = variables.lag("k", u, 900.0)
    # Each run on its own, as if it were the only record (a second formulation).
    assert np.allclose(lagged[:50], first_order_lag(t[:50], u[:50], 900.0), rtol=0, atol=1e-12)
    assert np.allclose(lagged[50:], first_order_lag(t[50:], u[50:], 900.0), rtol=0, atol=1e-12)
    assert lagged[50] == u[50]                                    # steady state at its start
    from_rest = variables.lag("s", np.abs(u), 900.0, from_rest=True)
    assert from_rest[0] == 0.0 and from_rest[50] == 0.0           # a cold start each run
    relative = variables.relative_time()
    assert relative[0] == 0.0 and relative[50] == 0.0 and relative[-1] == 39 * 30.0
    assert variables.span_s() == 49 * 60.0
    assert variables.subset(np.arange(45, 60)).run_starts.tolist() == [0, 5]
    assert subset_run_starts(np.array([0, 50]), 90, np.arange(60, 90)) .tolist() == [0]
    assert run_starts_of(["a", "a", "b", "c", "c"]).tolist() == [0, 2, 3]
    with pytest.raises(InputDataError, match="run starts"):
        Variables({"X": np.zeros(10)}, np.arange(10.0), run_starts=[1, 5])


def _two_days(levels, slip=None, rows: int = 60, seed: int = 3):
    """Runs warming 3 K from their ``levels`` [degC]; ``slip``: (run, map) of its readings."""
    rng = np.random.default_rng(seed)
    t = np.arange(rows) * 60.0
    days = []
    for k, level in enumerate(levels):
        warm = level + 3.0 * (1 - np.exp(-t / 1500.0)) + rng.normal(0, 0.02, rows)
        days.append(slip[1](warm) if slip and slip[0] == k else warm)
    return np.concatenate(days), np.repeat(np.arange(len(levels)), rows)


@pytest.mark.parametrize("slip, unit", [(lambda v: v * 1.8 + 32.0, "degF"),
                                         (lambda v: v + 273.15, "K")])
def test_a_run_in_degf_or_kelvin_is_a_unit_slip(slip, unit):
    values, runs = _two_days([20.0, 20.5, 19.8], (1, slip))
    problem = mixed_units_problem(np.zeros(values.size), {"t1": values}, runs,
                                  ["a", "b", "c"], False)
    assert problem.startswith("run 'b': sensor t1 reads") and \
        f"mixed units across runs? ({unit}: converted it reads 2" in problem


def test_a_hotter_run_of_a_motion_system_is_no_unit_slip_and_is_said():
    """A motor at 105 degC one day and 62 the other: 40 K apart, but neither run mapped by
    degF or K lies where the other does - a different process, kept and said."""
    values, runs = _two_days([102.0, 59.0])
    assert mixed_units_problem(np.zeros(values.size), {"T_motor": values}, runs,
                               ["1", "2"], False) == ""
    (note,) = run_level_notes({"T_motor": values}, runs, ["1", "2"])
    assert note.startswith("run '1': sensor T_motor reads 104.") and \
        note.endswith("no unit slip (K, degF) maps one onto the other: taken as a different "
                      "process")


def test_a_clock_jump_is_a_break_named_with_its_row_and_equal_stamps_with_theirs():
    t = np.arange(100) * 60.0
    t[40:] += 10 * 86400.0
    t[[70, 71]] = t[69]
    breaks, notes = clock_breaks(t, np.arange(100) + 1)
    assert np.flatnonzero(breaks).tolist() == [40]
    assert notes == ["the clock jumps by 10 d at data row 41 (its usual step 60 s): taken as a "
                     "break between runs (lags and time restart there)",
                     "equal time stamps at data rows 71-72 (2 rows): taken as the logger's "
                     "resolution (the lags hold still over them)"]
    assert clock_breaks(np.arange(100) * 15.0)[1] == []
