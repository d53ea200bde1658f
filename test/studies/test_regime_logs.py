"""The regime-log generator's own invariants: every file says what its truth says.

Each log is read back with the ``csv`` module alone, as a stranger would read it, and held
against its truth JSON: columns, units, rows, runs, regimes, faults, unit slips, the target's
scale and sign. Logs are small (``max_rows=600``).
"""

import csv
import datetime
import json
import math

import numpy as np
import pytest

from studies.regime_logs import (
    DATETIME_FORMAT,
    UNIT_MAPS,
    draw_choices,
    first_order_lag,
    main,
    make_log,
)
from studies.regime_logs_panel import REQUIRED, make_panel

SMALL = {"max_rows": 600}


def read_log(truth: dict) -> tuple[list[str], list[str] | None, list[list[str]]]:
    """Header, units row and data rows of a log, located by its own comment lines."""
    with open(truth["csv_path"], encoding="utf-8", newline="") as handle:
        lines = handle.read().split("\n")
    comments = 0
    while lines[comments].startswith("#"):
        comments += 1
    rows = list(csv.reader(lines[comments:], delimiter=truth["format"]["separator"]))
    rows = [r for r in rows if r]
    units = rows[1] if truth["format"]["units_line"] else None
    assert comments == truth["format"]["comment_lines"]
    return rows[0], units, rows[2:] if units else rows[1:]


def column(truth: dict, rows: list[list[str]], role: str, k: int = 0) -> np.ndarray:
    """Values of the k-th column with ``role`` (empty and NaN cells as nan)."""
    index = [c["index"] for c in truth["columns"] if c["role"] == role][k]
    return np.array([float(r[index]) if r[index] not in ("", "NaN", "nan") else math.nan
                     for r in rows])


def seconds(truth: dict, rows: list[list[str]]) -> np.ndarray:
    """The time column as seconds since the first row (date-times parsed, resets undone)."""
    cells = [r[truth["columns"][0]["index"]] for r in rows]
    if truth["time"]["unit"] == "datetime":
        stamps = [datetime.datetime.strptime(s, DATETIME_FORMAT) for s in cells]
        return np.array([(s - stamps[0]).total_seconds() for s in stamps])
    scale = {"s": 1.0, "min": 60.0, "h": 3600.0}[truth["time"]["unit"]]
    t = np.array([float(s) for s in cells]) * scale
    if truth["time"]["resets_per_run"]:
        for run in truth["runs"]:
            t[run["row_start"]:run["row_end"]] += run["t_start_s"]
    return t


@pytest.fixture(scope="module")
def panel(tmp_path_factory):
    out = tmp_path_factory.mktemp("panel")
    truths = make_panel(2, len(REQUIRED) + 2, out, **SMALL)
    return [json.loads(open(t.truth_path, encoding="utf-8").read()) for t in truths]


def test_lag_is_the_first_order_step_response():
    t = np.cumsum(np.r_[0.0, np.random.default_rng(0).uniform(1.0, 90.0, 200)])
    u = np.where(t >= t[40], 3.0, 0.0)[:, None] * np.ones((1, 2))
    tau = np.array([300.0, 2000.0])
    y = first_order_lag(t, u, tau, y0=np.zeros(2))
    elapsed = np.clip(t - t[40], 0.0, None)[:, None]
    # Zhu 2008 eq. 3.10: a step of size xi * tau reached with 1 - exp(-t / tau)
    np.testing.assert_allclose(y, 3.0 * (1.0 - np.exp(-elapsed / tau)), atol=1e-12)


def test_panel_columns_units_and_rows_match_the_truth(panel):
    for truth in panel:
        header, units, rows = read_log(truth)
        assert header == [c["name"] for c in truth["columns"]]
        assert len(rows) == truth["format"]["n_rows"]
        assert all(len(r) == len(header) for r in rows)
        if units is not None:
            assert units == [c["unit_token"] for c in truth["columns"]]
        roles = [c["role"] for c in truth["columns"]]
        assert roles[0] == "time" and roles.count("target") == 1
        assert roles.count("temperature") == len(truth["sensors"])
        assert ("run" in roles) == (truth["choices"]["run_marking"] == "column")


def test_runs_and_regimes_tile_the_rows_in_time_order(panel):
    for truth in panel:
        _, _, rows = read_log(truth)
        t = seconds(truth, rows)
        runs, regimes = truth["runs"], truth["regimes"]
        assert runs[0]["row_start"] == 0 and runs[-1]["row_end"] == len(rows)
        assert [r["row_start"] for r in runs[1:]] == [r["row_end"] for r in runs[:-1]]
        assert regimes[0]["row_start"] == 0 and regimes[-1]["row_end"] == len(rows)
        assert [r["row_start"] for r in regimes[1:]] == [r["row_end"] for r in regimes[:-1]]
        np.testing.assert_allclose(t[[r["row_start"] for r in runs]],
                                   [r["t_start_s"] for r in runs], atol=1.0)
        for run in runs:
            assert np.all(np.diff(t[run["row_start"]:run["row_end"]]) > 0)
        for reg in regimes:
            inside = t[reg["row_start"]:reg["row_end"]]
            assert reg["t_start_s"] - 1.0 <= inside.min() and inside.max() < reg["t_end_s"] + 1.0
            assert runs[reg["run"]]["row_start"] <= reg["row_start"] < runs[reg["run"]]["row_end"]


def test_speed_follows_the_regime_kind(tmp_path):
    truth = make_log(5, tmp_path, scenario="hdc", speed_column=True, faults=(), **SMALL)
    truth = truth.to_dict()
    _, _, rows = read_log(truth)
    rpm = column(truth, rows, "speed")
    for reg in truth["regimes"]:
        part = rpm[reg["row_start"]:reg["row_end"]]
        if reg["kind"] == "cooling":
            assert np.all(part == 0)
        elif reg["kind"] == "dwell":
            assert np.all(part == reg["speeds_rpm"][0]) and part[0] > 0
        else:
            assert set(np.unique(part)) <= set(reg["speeds_rpm"]) and part.max() > 0


def test_clock_jump_logs_show_runs_only_by_the_clock(panel):
    jumped = [t for t in panel if t["choices"]["run_marking"] == "clock_jump"]
    assert jumped
    for truth in jumped:
        _, _, rows = read_log(truth)
        t = seconds(truth, rows)
        steps = np.diff(t)
        big = np.flatnonzero(steps > 3600.0) + 1
        assert list(big) == [r["row_start"] for r in truth["runs"][1:]]
        assert all(r["clock_jump_before_s"] > 6 * 3600.0 for r in truth["runs"][1:])


def test_faults_read_as_recorded(panel):
    dead = [t for t in panel if any(f["kind"] == "dead" for f in t["faults"])]
    assert dead
    for truth in panel:
        _, _, rows = read_log(truth)
        names = [c["name"] for c in truth["columns"]]
        for fault in truth["faults"]:
            k = names.index(fault["column"])
            values = np.array([float(r[k]) for r in rows[fault["row_start"]:fault["row_end"]]])
            if fault["kind"] == "dead":
                assert np.all(np.abs(values - -180.0) < 5.0)
            else:
                assert np.all(values == fault["value"])
        for cell in truth["missing_cells"]:
            assert rows[cell["row"]][names.index(cell["column"])] == cell["written"]


def test_unit_slip_is_affine_over_one_run(panel):
    slipped = [t for t in panel if t["unit_slips"]]
    assert slipped
    for truth in slipped:
        _, _, rows = read_log(truth)
        slip = truth["unit_slips"][0]
        k = [c["index"] for c in truth["columns"] if c["name"] == slip["column"]][0]
        values = np.array([float(r[k]) if r[k] not in ("", "NaN", "nan") else math.nan
                           for r in rows])
        inside = np.zeros(len(rows), bool)
        inside[slip["row_start"]:slip["row_end"]] = True
        run = truth["runs"][slip["run"]]
        assert (slip["row_start"], slip["row_end"]) == (run["row_start"], run["row_end"])
        scale, offset = UNIT_MAPS[slip["unit_written"]]
        back = (values[inside] - offset) / scale
        assert np.nanmin(values[inside]) > 55.0 and np.nanmax(values[~inside]) < 50.0
        assert abs(np.nanmean(back) - np.nanmean(values[~inside])) < 15.0


def test_hot_run_is_real_heat_in_degrees_celsius(panel):
    hot = [t for t in panel if t["hot_runs"]]
    assert hot
    for truth in hot:
        _, _, rows = read_log(truth)
        record = truth["hot_runs"][0]
        sensor = [s["sensor"] for s in truth["sensors"] if s["column"] == record["sensor"]][0]
        values = column(truth, rows, "temperature", sensor - 1)
        inside = np.zeros(len(rows), bool)
        run = truth["runs"][record["run"]]
        inside[run["row_start"]:run["row_end"]] = True
        shift = np.nanmean(values[inside]) - np.nanmean(values[~inside])
        assert shift > 0.5 and abs(shift - record["sensor_mean_shift_K"][record["sensor"]]) < 0.05
        assert np.nanmin(values) > 5.0 and np.nanmax(values) < 60.0  # degC: no unit change
        assert record["heating_share"] > record["typical_heating_share"] + 0.3


def test_target_scale_sign_and_zero(tmp_path):
    for unit, sign in (("mm", -1), ("nm", 1), ("um", -1)):
        truth = make_log(11, tmp_path, target_unit=unit, sign=sign, target_zero="log_start",
                         faults=(), scenario="hdc", **SMALL).to_dict()
        _, _, rows = read_log(truth)
        target = truth["target"]
        elong = column(truth, rows, "target") / (target["sign"] * target["per_um"])
        noise = target["noise_um"]
        assert abs(elong[0]) < 5 * noise
        assert abs(np.max(np.abs(elong)) - target["amplitude_um"]) < 5 * noise
        assert np.mean(elong) > 0  # the loop grows when the spindle heats it


def test_train_split_holds_one_regime_in_its_first_part(panel):
    split = [t for t in panel if t["split"]]
    assert split
    for truth in split:
        s = truth["split"]
        first = truth["regimes"][0]
        assert (first["row_start"], first["row_end"]) == (0, s["train_end_row"])
        assert 0.45 <= s["train_fraction"] <= 0.75
        assert s["test_regimes"] == [r["index"] for r in truth["regimes"][1:]]
        rest = {(r["kind"], r["program"]) for r in truth["regimes"][1:]}
        assert (first["kind"], first["program"]) not in rest


def test_odd_unit_sensor_carries_its_unit_in_its_name(tmp_path):
    for unit in ("K", "degF"):
        truth = make_log(4, tmp_path, odd_unit=unit, odd_sensor=0, units_row=False,
                         faults=(), unit_slip=None, **SMALL).to_dict()
        _, _, rows = read_log(truth)
        sensor = truth["sensors"][0]
        assert sensor["unit_written"] == unit
        assert sensor["column"].endswith(("_K", "[K]") if unit == "K" else ("_degF", "[°F]"))
        values = column(truth, rows, "temperature", 0)
        scale, offset = UNIT_MAPS[unit]
        assert np.all(np.abs((values - offset) / scale - 22.0) < 20.0)


def test_off_path_sensors_do_not_follow_the_target_in_a_still_room(tmp_path):
    """Off the path a sensor reads the (still) air and its noise; on it, the spindle's heat."""
    for seed in (3, 4, 5):
        truth = make_log(seed, tmp_path, ambient_amplitude_K=0.0, faults=(),
                         sources=("spindle_bearings", "spindle_motor", "ambient"),
                         **SMALL).to_dict()
        on = [s["corr_with_target"] for s in truth["sensors"] if s["on_path"]]
        off = [s["corr_with_target"] for s in truth["sensors"] if not s["on_path"]]
        assert max(np.abs(off)) < 0.35 and max(on) > max(np.abs(off)) + 0.2


def rebuild(truth: dict, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Noise-free temperatures (degC) and elongation (um) at ``t`` from the truth alone."""
    c = truth["choices"]
    steps = [s for b in truth["prehistory"] for s in b["steps"]]
    for reg in truth["regimes"]:
        steps += reg["steps"]
        if reg["index"] + 1 == len(truth["regimes"]) or truth["regimes"][reg["index"] + 1]["run"] \
                != reg["run"]:
            steps.append((reg["t_end_s"], 0.0))  # idle after each run
    step_t, step_rpm = np.array(steps).T
    feed = [s["schedule"] for s in truth["sources"] if s["schedule"]]
    feed_t, duty = np.array(feed[0]).T if feed else (np.zeros(1), np.zeros(1))
    start = steps[0][0]
    grid = np.unique(np.concatenate([t, step_t, feed_t, np.arange(start, t[-1], 300.0)]))
    grid = grid[(grid >= start) & (grid <= t[-1])]
    rpm = step_rpm[np.searchsorted(step_t, grid, side="right") - 1]
    x = rpm / c["spindle_max_rpm"]
    mid = np.append(0.5 * (grid[1:] + grid[:-1]), grid[-1])
    clock0 = datetime.datetime.strptime(c["start_datetime"], DATETIME_FORMAT)
    clock_h = clock0.hour + clock0.minute / 60 + clock0.second / 3600 + mid / 3600
    gains = {s["name"]: s["gain_K"] for s in truth["sources"]}
    rise = {
        "spindle_bearings": gains["spindle_bearings"] * x ** c["bearing_exponent"],
        "spindle_motor": gains.get("spindle_motor", 0.0) * (0.3 + 0.7 * x) * (x > 0),
        "ambient": c["ambient_amplitude_K"]
        * np.cos(2 * np.pi * (clock_h - c["ambient_peak_h"]) / 24),
    }
    if feed:
        rise["feed_drive"] = gains["feed_drive"] * duty[
            np.clip(np.searchsorted(feed_t, grid, side="right") - 1, 0, None)]
    mixes = [s["weights"] for s in truth["sensors"]] + [e["weights"]
                                                        for e in truth["target"]["elements"]]
    u = np.column_stack([sum(w[k] * rise[k] for k in w) for w in mixes])
    tau = [s["tau_s"] for s in truth["sensors"]] + [e["tau_s"] for e in truth["target"]["elements"]]
    at_rest = np.array([w["ambient"] * rise["ambient"][0] for w in mixes])
    y = first_order_lag(grid, u, np.array(tau), y0=at_rest)[np.searchsorted(grid, t)]
    n = len(truth["sensors"])
    temps = c["ambient_mean_C"] + np.array([s["offset_K"] for s in truth["sensors"]]) + y[:, :n]
    alpha = np.array([e["alpha_L_um_per_K"] for e in truth["target"]["elements"]])
    return temps, y[:, n:] @ alpha


def test_the_truth_alone_rebuilds_the_recorded_values(panel):
    """A second formulation of the physics, fed only with the truth, meets the file within
    its noise: the truth holds every draw that shaped the values."""
    for truth in panel:
        _, _, rows = read_log(truth)
        t = seconds(truth, rows) + truth["runs"][0]["t_start_s"]
        temps, elong = rebuild(truth, t)
        target = truth["target"]
        written = column(truth, rows, "target") / (target["sign"] * target["per_um"])
        zero = np.zeros(len(t))
        for run in truth["runs"] if target["zeroed"] == "run_start" else [truth["runs"][0]]:
            end = run["row_end"] if target["zeroed"] == "run_start" else len(t)
            zero[run["row_start"]:end] = elong[run["row_start"]]
        assert np.nanmax(np.abs(written - (elong - zero))) < 6 * target["noise_um"] + 0.05
        for j, sensor in enumerate(truth["sensors"]):
            if sensor["faults"] or sensor["unit_written"] != "degC":
                continue
            values = column(truth, rows, "temperature", j)
            limit = 6 * truth["noise"]["temperature_K"] + 0.01
            assert np.nanmax(np.abs(values - temps[:, j])) < limit, sensor["column"]


def test_lead_or_lag_is_set_by_the_time_constants(tmp_path):
    for lead in ("leads", "lags"):
        truth = make_log(8, tmp_path, target_lead=lead, **SMALL).to_dict()
        taus = [s["tau_s"] for s in truth["sensors"] if s["on_path"]]
        elements = [e["tau_s"] for e in truth["target"]["elements"]]
        if lead == "leads":
            assert max(elements) < np.median(taus)
        else:
            assert min(elements) > np.median(taus) or min(elements) == 4 * 3600.0


def test_same_seed_same_files_and_forcing_one_choice_keeps_the_others(tmp_path):
    a = make_log(21, tmp_path / "a", **SMALL)
    b = make_log(21, tmp_path / "b", **SMALL)
    assert open(a.csv_path, "rb").read() == open(b.csv_path, "rb").read()
    sep = ";" if a.choices.separator == "," else ","
    c = draw_choices(21, separator=sep, **SMALL)
    assert c.separator == sep
    assert {k: v for k, v in vars(c).items() if k != "separator"} == \
        {k: v for k, v in vars(a.choices).items() if k != "separator"}


def test_bad_choices_are_refused(tmp_path):
    with pytest.raises(ValueError, match="unknown choices"):
        make_log(1, tmp_path, colour="red")
    with pytest.raises(ValueError, match="several runs"):
        make_log(1, tmp_path, scenario="hdc", hot_run=True)
    with pytest.raises(ValueError, match="max_rows"):
        make_log(1, tmp_path, max_rows=10)


def test_command_line_writes_a_log_and_its_truth(tmp_path, capsys):
    assert main(["--seed", "3", "--out", str(tmp_path), "--choice", "max_rows=600"]) == 0
    truth = json.loads((tmp_path / "regime_log_s3.truth.json").read_text(encoding="utf-8"))
    assert truth["file"] == "regime_log_s3.csv" and truth["seed"] == 3
    assert (tmp_path / truth["file"]).exists()
    assert "regime_log_s3.csv" in capsys.readouterr().out

