"""Thermal logs made by independent code (``studies.regime_logs``: its own conventions, drawn
at random) checked as a user would: what each log's truth says must come out - regimes
where the physics changed, a unit slip refused naming its run and sensor, a run that only
ran hotter kept, every dead, stuck or zero sensor named."""
from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest

from studies.regime_logs_panel import make_panel

#: The panel's seed and size: its first six logs are the required cases, in order (a
#: heating / dwell / cooling run, a training part of one regime, runs with a hotter one,
#: runs with a unit slip, a dead sensor, days parted by a clock jump).
SEED, LOGS, MAX_ROWS = 1, 6, 900


@pytest.fixture(scope="module")
def panel(tmp_path_factory):
    directory = tmp_path_factory.mktemp("regime_panel")
    truths = make_panel(SEED, LOGS, directory, max_rows=MAX_ROWS)
    return [json.loads(Path(t.truth_path).read_text()) for t in truths]


def _flags(truth: dict) -> list[str]:
    """The flags a user who knows the file gives: the target's unit, the time column, the
    run column and the spindle speed."""
    from bench.regime_panel_proof import _flags as user_flags

    return user_flags(truth)


def _check(truth: dict, *extra: str) -> tuple[int, str, str, dict | None]:
    from mt_accuracy_ros.cli import main

    json_path = Path(truth["csv_path"]).with_suffix(".summary.json")
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["check", truth["csv_path"], *_flags(truth), "--auto", "2", "--json",
                     str(json_path), *extra])
    summary = json.loads(json_path.read_text()) if code == 0 else None
    return code, out.getvalue(), err.getvalue(), summary


def test_the_regimes_found_are_the_truth_s(panel):
    """In the heating / dwell / cooling log: the rows found heating (cooling) are, nearly
    all, rows of a true heating (cooling) regime, and every true heating or cooling regime
    holds a stretch found of its kind. (The truth names the spindle's program; a cooling
    machine whose temperatures have settled is found dwelling, so a true regime's every row
    is not asked for.)"""
    from mt_accuracy_ros.commands.check_log import read_log
    from mt_accuracy_ros.core.workbench.regimes import find_regimes

    truth = panel[0]
    flags = dict(zip(_flags(truth)[::2], _flags(truth)[1::2]))
    log = read_log(Path(truth["csv_path"]), flags["--target"], flags["--time-column"], ["*"],
                   [flags["--driver"]] if "--driver" in flags else [], None, "z", None, None,
                   False)
    obs = log.obs
    # A row with an empty cell is left out (counted): the truth's regimes by their time.
    assert obs.n >= 0.99 * truth["format"]["n_rows"]
    found = np.empty(obs.n, dtype=object)
    for stretch in find_regimes(obs.time_s, obs.temperatures, obs.run_of_row).stretches:
        found[stretch.start:stretch.stop] = stretch.kind
    true = np.empty(obs.n, dtype=object)
    for regime in truth["regimes"]:
        true[(obs.time_s >= regime["t_start_s"] - 1e-6) &
             (obs.time_s <= regime["t_end_s"] + 1e-6)] = regime["kind"]
    for kind in ("heating", "cooling"):
        ours = found == kind
        assert ours.any() and np.mean(true[ours] == kind) >= 0.85, kind
        for regime in truth["regimes"]:
            if regime["kind"] == kind:
                inside = (obs.time_s >= regime["t_start_s"]) & \
                    (obs.time_s <= regime["t_end_s"])
                assert ours[inside].any(), regime


def test_a_unit_slip_of_one_run_is_refused_naming_the_run_and_the_sensor(panel):
    for truth in panel:
        for slip in truth["unit_slips"]:
            code, _, err, _ = _check(truth)
            assert code == 2
            unit = "K" if slip["unit_written"] == "K" else "degF"
            assert f"sensor {slip['column']} reads" in err and \
                f"mixed units across runs? ({unit}: converted it reads" in err


def test_a_run_that_only_ran_hotter_is_kept_and_said(panel):
    (truth,) = [t for t in panel if t["hot_runs"] and not t["unit_slips"]]
    code, out, err, summary = _check(truth)
    assert code == 0, err
    assert summary["rows"] == truth["format"]["n_rows"] - len(
        {c["row"] for c in truth["missing_cells"]}) or summary["rows"] > 0


def test_every_dead_stuck_or_zero_sensor_is_named(panel):
    for truth in panel:
        if truth["unit_slips"]:
            continue
        code, out, err, summary = _check(truth)
        assert code == 0, err
        said = " ".join(summary["notes"])
        for fault in truth["faults"]:
            assert f"sensor {fault['column']}" in said, (fault, said[:500])
