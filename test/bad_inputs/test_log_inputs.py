"""Bad thermal logs (`mt-accuracy check LOG.csv --target COL[:UNIT] ...`) through the real CLI.

Units, sensors, clocks and options: each is read in a known unit or refused, each sensor
is judged before use (dead, out of range, stuck, dropping out, jumping: named with its
rows, left out), each clock problem named. Each class builds its bad log in ``tmp_path``,
runs ``mt_accuracy_ros.cli.main`` and checks the outcome: a refusal is exit code 2, ONE
line on stderr with the key words, and no JSON written; an announced decision is exit
code 0 with the note printed and in the JSON's notes.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from mt_accuracy_ros.cli import main

#: (class, the input, the outcome: "refused: <key words of the one line>" or
#: "announced: <key words of the note>").
CLASSES = [
    ("log_kelvin_declared_celsius",
     "a log's sensor T3 in kelvin (293 ... 296), its name giving no unit (read as degC)",
     "refused: sensor T3: values 293.1 … 294.3 declared °C look like K (plausible temperature: "
     "-30 … +80 °C); give its unit in its name (T3_K) or a units row"),
    ("log_target_um_declared_m",
     "a log's target in micrometres declared as metres (--target dz:m)",
     "refused: target dz: values 0.06016 … 8.592 declared m look like µm (plausible error: "
     "|error| ≤ 5 mm); declare its unit: --target dz:um"),
    ("log_target_without_unit",
     "a log's target column dz with no unit in the flag, its name or a units row",
     "refused: target dz: no unit in --target, its name or a units row; give its unit as "
     "dz:UNIT, e.g. --target dz:um"),
    ("log_constant_target",
     "a log whose target reads 5 um on every row",
     "refused: target dz_um is constant (5 um on all 150 rows): nothing to model"),
    ("log_dead_thermocouple",
     "a log's thermocouple t3_C reads -180 degC with a little noise on every row (open "
     "circuit)",
     "announced: sensor t3_C: reads -180.5 degC, a physically absent value (dead) at data rows "
     "1-150 (150 of 150 rows) - left out of every model (its rows kept)"),
    ("log_sensor_dead_from_a_row",
     "a log's sensor t3_C reads -180 degC from data row 101 on",
     "announced: sensor t3_C: reads -180 degC, a physically absent value (dead) at data rows "
     "101-150 (50 of 150 rows) - left out of every model (its rows kept)"),
    ("log_sensor_zero_from_a_row",
     "a log's sensor t3_C reads exactly 0 from data row 100 on (a logger's empty value)",
     "announced: sensor t3_C: reads 0 degC, a physically absent value (dead) at data rows "
     "100-150 (51 of 150 rows) - left out of every model (its rows kept)"),
    ("log_sensor_out_of_range",
     "a log's sensor t2_C reads 95 degC on data rows 40-44 (a structure sensor)",
     "announced: sensor t2_C: reads 95 degC, outside a workshop's -30 ... 80 degC at data "
     "rows 40-44 (5 of 150 rows) - those rows left out"),
    ("log_sensor_stuck",
     "a log's sensor t3_C reads 21.5 degC on every row while the others warm up",
     "announced: sensor t3_C: stuck at 21.5 degC while the others move at data rows 1-150 "
     "(150 of 150 rows) - left out of every model (its rows kept)"),
    ("log_sensor_dropout",
     "a log's sensor t2_C has empty cells on data rows 20-22 and 90",
     "announced: sensor t2_C: no reading at data rows 20-22, 90 (4 of 150 rows) - those rows "
     "left out"),
    ("log_sensor_jump",
     "a log's sensor t3_C steps by +3 K at data row 81 (re-seated), no other sensor does",
     "announced: sensor t3_C: jumps by +3.18 K at data row 81 (its noise 0.011 K; no other "
     "sensor steps there) - left out of every model (which side is right cannot be told)"),
    ("log_inputs_star_matches_non_temperatures",
     "--inputs '*' on a log with a spindle_rpm and a ch1_um column",
     "announced: --inputs * also matched spindle_rpm (rpm), ch1_um (um): no temperatures, "
     "left out of the inputs"),
    ("log_inputs_pattern_matches_nothing",
     "--inputs 't*_C' 'x*': the second pattern matches no column",
     "refused: --inputs 'x*' matches no temperature column"),
    ("log_inputs_only_a_speed",
     "--inputs spindle_rpm: the only column asked for is a speed",
     "refused: --inputs 'spindle_rpm' matches no temperature column (it matched spindle_rpm "
     "(rpm))"),
    ("log_all_stamps_equal",
     "a log whose time column holds 0 on every row",
     "refused: time column time_s holds one stamp (0) on every row: no time to model lags "
     "with; give --row-period SECONDS"),
    ("log_clock_jump",
     "a log whose clock jumps by 10 days at data row 76 (no run column)",
     "announced: the clock jumps by 10 d at data row 76 (its usual step 60 s): taken as a "
     "break between runs"),
    ("log_clock_jump_inside_a_run",
     "a log of two runs whose clock jumps by 10 days inside run 'a'",
     "refused: the clock jumps by 10 d inside run 'a' at data row 40: start a new run there "
     "(a new value in the run column) or fix the stamps"),
    ("log_duplicate_stamps",
     "a log whose stamps repeat at data rows 11 and 31 (a coarse logger)",
     "announced: equal time stamps at data rows 11, 31 (2 rows): taken as the logger's "
     "resolution"),
    ("log_stamp_goes_back",
     "a log whose stamp at data row 51 lies before the row above it",
     "refused: the time goes back at data row 51"),
    ("log_auto_negative",
     "--auto -1 on a thermal log",
     "refused: --auto"),
    ("log_train_fraction_above_one",
     "--train-fraction 1.5 on a thermal log",
     "refused: --train-fraction"),
    ("log_run_in_fahrenheit",
     "a log of three runs whose second run's sensor was logged in degF",
     "refused: run 'r2': sensor t1_C reads 71.75 where the other runs read 21.72 - mixed units "
     "across runs? (degF: converted it reads 22.08 degC, as the others do)"),
    ("log_hotter_run_is_no_unit_slip",
     "a two-run log of a motion system: its motor sensor reads 105 degC one day, 62 the "
     "other",
     "announced: run 'd0': sensor T_motor_C reads 102.1 where the other runs read 59.08; no "
     "unit slip (K, degF) maps one onto the other: taken as a different process"),
    ("log_every_sensor_dead",
     "a log whose only sensor reads -180 degC on every row",
     "refused: every input sensor is left out"),
    ("log_target_is_a_position",
     "a log's target is an axis position read by re-homing (-224.8 mm, moving 0.36 mm)",
     "refused: target z_um sits -224.5 mm from zero but spans 0.36 mm: a position, not a "
     "displacement? Give its change from a reference (subtract its first reading) as the "
     "target"),
    ("log_target_failed_readings",
     "a log's target (re-homed every reading) misses its switch on data rows 30 and 95: "
     "+4300 um for one reading each, then back",
     "announced: target dz_um: 2 readings far from the readings either side and back (up to "
     "+4300 um beyond the nearer side's median; its noise 0.07 um) at data rows 30, 95 - "
     "failed readings (a missed homing or touch?), those rows left out"),
    ("log_absent_thermistor_asked_for_by_name",
     "a log's chamber sensor reads exactly -180 on every row (absent: the logger's "
     "default), asked for by name in --inputs",
     "announced: sensor chamber: reads -180 degC, a physically absent value (dead) at data "
     "rows 1-150 (150 of 150 rows) - left out of every model (its rows kept)"),
    ("log_bed_heater_above_a_structure_s_range",
     "a log's bed heater t3_C rising from the room's 20 degC to 105 degC (above a "
     "structure's 80)",
     "announced: sensor t3_C: reads up to 105 degC, above a structure's 80 degC, from 20 "
     "degC at its coolest as the other sensors (20 degC): taken as a heated part (a heater, "
     "a bed, a spindle) and kept"),
    ("log_kelvin_day_after_a_clock_jump",
     "a log of two days parted only by a clock jump of two days; on the second day its "
     "sensor was logged in kelvin",
     "refused: run '2': sensor t1_C reads 296.2 where the other runs read 22.08 - mixed "
     "units across runs? (K: converted it reads 23.08 degC, as the others do)"),
]

ROWS = 150


def _warm_up(rows: int = ROWS, seed: int = 0) -> dict[str, np.ndarray]:
    """A machine warming up, one row a minute: two structure sensors, the growth [um]."""
    rng = np.random.default_rng(seed)
    t = np.arange(rows) * 60.0
    t1 = 20 + 3.0 * (1 - np.exp(-t / 3000.0)) + rng.normal(0, 0.01, rows)
    t2 = 20 + 1.5 * (1 - np.exp(-t / 6000.0)) + rng.normal(0, 0.01, rows)
    growth = 3.0 * (t1 - t1[0]) + rng.normal(0, 0.05, rows)
    return {"time_s": t, "t1_C": t1, "t2_C": t2, "dz_um": growth}


def _write(path, columns: dict[str, np.ndarray]) -> None:
    names = list(columns)
    lines = [",".join(names)]
    for k in range(len(columns[names[0]])):
        lines.append(",".join("" if not np.isfinite(columns[n][k]) else f"{columns[n][k]:.6g}"
                              for n in names))
    path.write_text("\n".join(lines) + "\n")


def _with(**extra) -> dict[str, np.ndarray]:
    log = _warm_up()
    log.update(extra)
    return log


def _third_sensor(edit) -> dict[str, np.ndarray]:
    log = _warm_up()
    rng = np.random.default_rng(1)
    t3 = 20 + 2.0 * (1 - np.exp(-log["time_s"] / 4000.0)) + rng.normal(0, 0.01, ROWS)
    edit(t3)
    log["t3_C"] = t3
    return log


def _set(values, where, value):
    values[where] = value


def _runs(levels, rows: int = 60, slip=None) -> dict[str, np.ndarray]:
    """Runs of ``rows`` (clock restarting), the sensor's level per run; ``slip``: (run,
    function) applied to that run's readings."""
    rng = np.random.default_rng(3)
    t = np.arange(rows) * 60.0
    run, time, temp, growth = [], [], [], []
    for k, level in enumerate(levels):
        warm = level + 3.0 * (1 - np.exp(-t / 1500.0)) + rng.normal(0, 0.02, rows)
        growth.append(2.0 * (warm - warm[0]) + rng.normal(0, 0.05, rows))
        temp.append(slip[1](warm) if slip and slip[0] == k else warm)
        run += [k] * rows
        time.append(t)
    return {"run": np.array(run, float), "time_s": np.concatenate(time),
            "t1_C": np.concatenate(temp), "growth_um": np.concatenate(growth)}


def _build(name: str, tmp_path) -> tuple[dict[str, np.ndarray], list[str]]:
    """(the log's columns, the CLI flags after the file) of a class."""
    base = ["--target", "dz_um", "--inputs", "t*_C", "--auto", "1"]
    rng = np.random.default_rng(7)
    if name == "log_kelvin_declared_celsius":
        log = _warm_up()
        log["T3"] = log.pop("t2_C") + 273.15
        return log, ["--target", "dz_um", "--inputs", "t1_C", "T3"]
    if name == "log_target_um_declared_m":
        log = _warm_up()
        log["dz"] = np.abs(log.pop("dz_um"))
        return log, ["--target", "dz:m", "--inputs", "t*_C"]
    if name == "log_target_without_unit":
        log = _warm_up()
        log["dz"] = log.pop("dz_um")
        return log, ["--target", "dz", "--inputs", "t*_C"]
    if name == "log_constant_target":
        return _with(dz_um=np.full(ROWS, 5.0)), base
    if name == "log_dead_thermocouple":
        log = _third_sensor(lambda v: None)
        log["t3_C"] = -180.0 + rng.normal(0, 0.2, ROWS)
        return log, base
    if name == "log_sensor_dead_from_a_row":
        return _third_sensor(lambda v: _set(v, slice(100, None), -180.0)), base
    if name == "log_sensor_zero_from_a_row":
        return _third_sensor(lambda v: _set(v, slice(99, None), 0.0)), base
    if name == "log_sensor_out_of_range":
        log = _warm_up()
        log["t2_C"][39:44] = 95.0
        return log, base
    if name == "log_sensor_stuck":
        return _third_sensor(lambda v: _set(v, slice(None), 21.5)), base
    if name == "log_sensor_dropout":
        log = _warm_up()
        log["t2_C"][[19, 20, 21, 89]] = np.nan
        return log, base
    if name == "log_sensor_jump":
        return _third_sensor(lambda v: _set(v, slice(80, None), v[80:] + 3.0)), base
    if name == "log_inputs_star_matches_non_temperatures":
        log = _warm_up()
        log["spindle_rpm"] = np.where(np.arange(ROWS) < 20, 0.0, 4000.0)
        log["ch1_um"] = log["dz_um"] * 0.5
        return log, ["--target", "dz_um", "--inputs", "*", "--auto", "1"]
    if name == "log_inputs_pattern_matches_nothing":
        return _warm_up(), ["--target", "dz_um", "--inputs", "t*_C", "x*"]
    if name == "log_inputs_only_a_speed":
        return _with(spindle_rpm=np.full(ROWS, 3000.0)), \
            ["--target", "dz_um", "--inputs", "spindle_rpm"]
    if name == "log_all_stamps_equal":
        return _with(time_s=np.zeros(ROWS)), base
    if name == "log_clock_jump":
        log = _warm_up()
        log["time_s"][75:] += 10 * 86400.0
        return log, base
    if name == "log_clock_jump_inside_a_run":
        log = _runs([20.0, 20.5])
        log["time_s"][39:60] += 86400.0 * 10
        return log, ["--target", "growth_um", "--inputs", "t1_C", "--run", "run"]
    if name == "log_duplicate_stamps":
        log = _warm_up()
        log["time_s"][[10, 30]] = log["time_s"][[9, 29]]
        return log, base
    if name == "log_stamp_goes_back":
        log = _warm_up()
        log["time_s"][50] = 30.0
        return log, base
    if name == "log_auto_negative":
        return _warm_up(), ["--target", "dz_um", "--inputs", "t*_C", "--auto", "-1"]
    if name == "log_train_fraction_above_one":
        return _warm_up(), ["--target", "dz_um", "--inputs", "t*_C", "--train-fraction", "1.5"]
    if name == "log_run_in_fahrenheit":
        log = _runs([19.5, 20.0, 19.8], slip=(1, lambda v: v * 1.8 + 32.0))
        return log, ["--target", "growth_um", "--inputs", "t1_C", "--run", "run"]
    if name == "log_hotter_run_is_no_unit_slip":
        log = _runs([100.0, 57.0])
        log["T_motor_C"] = log.pop("t1_C")
        return log, ["--target", "growth_um", "--inputs", "T_motor_C", "--run", "run",
                     "--auto", "1"]
    if name == "log_target_is_a_position":
        log = _warm_up()
        growth = log.pop("dz_um")
        log["z_um"] = -224.8e3 + 360.0 * (growth - growth.min()) / np.ptp(growth)
        return log, ["--target", "z_um", "--inputs", "t*_C"]
    if name == "log_target_failed_readings":
        log = _warm_up()
        log["dz_um"][[29, 94]] += 4300.0
        return log, base
    if name == "log_absent_thermistor_asked_for_by_name":
        log = _warm_up()
        log["chamber"] = np.full(ROWS, -180.0)
        return log, ["--target", "dz_um", "--inputs", "t1_C", "t2_C", "chamber", "--auto", "1"]
    if name == "log_bed_heater_above_a_structure_s_range":
        return _third_sensor(lambda v: _set(v, slice(None), 20.0 + 85.0 * (
            1 - np.exp(-np.arange(ROWS) / 20.0)) + rng.normal(0, 0.05, ROWS))), base
    if name == "log_kelvin_day_after_a_clock_jump":
        log = _runs([20.0, 21.0], slip=(1, lambda v: v + 273.15))
        log["time_s"][60:] += 2 * 86400.0
        del log["run"]
        return log, ["--target", "growth_um", "--inputs", "t1_C", "--auto", "1"]
    if name == "log_every_sensor_dead":
        log = _warm_up()
        del log["t2_C"]
        log["t1_C"] = -180.0 + rng.normal(0, 0.2, ROWS)
        return log, base
    raise AssertionError(name)


@pytest.mark.parametrize("name, description, outcome", CLASSES, ids=[c[0] for c in CLASSES])
def test_a_bad_log_is_refused_or_announced(name, description, outcome, tmp_path, capsys):
    columns, flags = _build(name, tmp_path)
    if "run" in columns:
        columns["run"] = np.array([f"{int(k)}" for k in columns["run"]], dtype=object)
    path = tmp_path / "log.csv"
    _write_any(path, columns, name)
    out_json = tmp_path / "s.json"
    code = main(["check", str(path), *flags, "--json", str(out_json)])
    captured = capsys.readouterr()
    kind, words = outcome.split(": ", 1)
    if kind == "refused":
        err = captured.err.strip()
        assert code == 2, captured
        assert words in err and "\n" not in err, err
        assert not out_json.exists()
    else:
        assert code == 0, captured.err
        assert words in captured.out, captured.out
        notes = json.loads(out_json.read_text())["notes"]
        assert any(words in note for note in notes), notes


#: Run names the run-column classes write (a run column holds text).
RUN_NAMES = {"log_clock_jump_inside_a_run": "ab", "log_run_in_fahrenheit": ["r1", "r2", "r3"],
             "log_hotter_run_is_no_unit_slip": ["d0", "d1"]}


def _write_any(path, columns: dict, name: str) -> None:
    """Write the log; a run column gets the class's run names."""
    if "run" not in columns:
        _write(path, columns)
        return
    runs = [RUN_NAMES[name][int(k)] for k in columns.pop("run")]
    names = ["run"] + list(columns)
    lines = [",".join(names)]
    for k, label in enumerate(runs):
        lines.append(",".join([label] + [f"{columns[n][k]:.6g}" for n in names[1:]]))
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("auto, fraction, words", [
    (-1, 0.5, "--auto -1: give a count of terms to add, 0 or more"),
    (1, 1.5, "--train-fraction 1.5: between 0.2 and 0.9"),
    (1, float("nan"), "--train-fraction nan: between 0.2 and 0.9")])
def test_the_log_entry_refuses_its_options_whatever_the_parser_let_by(tmp_path, auto, fraction,
                                                                      words):
    """check_csv validates its own options (another front end than the CLI's parser may
    call it), before the file is read."""
    from mt_accuracy_ros.commands.check_log import check_csv
    from mt_accuracy_ros.core.errors import ParameterError

    with pytest.raises(ParameterError, match=words.replace("+", r"\+")):
        check_csv(tmp_path / "never_read.csv", "dz_um", "time_s", ["t*_C"], [], [], auto,
                  fraction, 0.05, [])


def test_the_corpus_has_sixteen_classes_or_more():
    assert len(CLASSES) >= 16 and len({c[0] for c in CLASSES}) == len(CLASSES)
