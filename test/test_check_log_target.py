"""A thermal log's failed target readings (a missed homing, a probe's miss): named by their
file rows and left out, the check then the same as on the file without those rows."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.cli import main
from mt_accuracy_ros.commands.check_log import check_csv

from test_check_walk import _heat_then_idle, _log

ARGS = dict(target="d_um", time_column="time_s", inputs=["*"], drivers=[], add=[], auto=2,
            train_fraction=0.5, min_reduction=0.05, model_terms=[], uncertainty_m=0.6e-6)
FAILED = {40: 6300.0, 41: 6300.0, 250: -900.0, 480: 2500.0}      # data row -> added [um]


def _with_failed_readings(tmp_path):
    """The walk-forward tests' heating / part-load / cooling log, and the same with four
    failed readings of the target (data rows 40, 41, 250, 480: far off, then back)."""
    clean = _log(tmp_path / "clean.csv", _heat_then_idle())
    lines = clean.read_text().splitlines()
    for row, offset in FAILED.items():
        values = lines[row].split(",")                 # lines[0] is the header
        values[-1] = f"{float(values[-1]) + offset:.4f}"
        lines[row] = ",".join(values)
    failed = tmp_path / "failed.csv"
    failed.write_text("\n".join(lines) + "\n")
    kept = tmp_path / "kept.csv"
    kept.write_text("\n".join(line for k, line in enumerate(lines) if k not in FAILED) + "\n")
    return failed, kept


def test_failed_target_readings_are_named_left_out_and_change_nothing_else(tmp_path):
    failed, kept = _with_failed_readings(tmp_path)
    with_failed = check_csv(failed, **ARGS)
    without = check_csv(kept, **ARGS)
    (note,) = [n for n in with_failed["notes"] if n.startswith("target d_um:")]
    assert "4 readings far from the readings either side and back" in note
    assert "at data rows 40-41, 250, 480" in note and "those rows left out" in note
    # 6.3 mm is beyond a plausible error: judged after the failed readings, no unit slip.
    largest = float(note.split("(up to ", 1)[1].split(" um", 1)[0])
    assert largest == pytest.approx(6300.0, abs=5.0)
    assert with_failed["rows_dropped"] == 4
    # Every dropped row has its reason: no "..." for rows left unexplained.
    assert with_failed["rows_note"].endswith("4 dropped (4 with a failed target reading (see "
                                             "the notes))"), with_failed["rows_note"]
    # The check's figures: those of the file without the four rows.
    for key in ("held_out_baseline_rmse", "constant_held_out_rmse",
                "all_inputs_least_squares_held_out_rmse", "final_rmse"):
        assert with_failed[key] == pytest.approx(without[key], rel=1e-12), key
    assert with_failed["added"] == without["added"]


def test_a_target_that_spikes_on_many_rows_is_refused_in_one_line(tmp_path, capsys):
    clean = _log(tmp_path / "clean.csv", _heat_then_idle())
    lines = clean.read_text().splitlines()
    rng = np.random.default_rng(5)
    for row in rng.choice(np.arange(1, len(lines)), size=60, replace=False):
        values = lines[row].split(",")
        values[-1] = f"{float(values[-1]) + 3000.0:.4f}"
        lines[row] = ",".join(values)
    noisy = tmp_path / "noisy.csv"
    noisy.write_text("\n".join(lines) + "\n")
    assert main(["check", str(noisy), "--target", "d_um", "--auto", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "too many to be failed readings" in err


def test_a_failed_reading_on_a_row_with_a_sensor_gap_is_one_row_dropped(tmp_path):
    """Data row 40 reads a failed target and lacks t2_C: one row left out, not two."""
    failed, _ = _with_failed_readings(tmp_path)
    lines = failed.read_text().splitlines()
    values = lines[40].split(",")
    values[2] = ""                                     # t2_C
    lines[40] = ",".join(values)
    failed.write_text("\n".join(lines) + "\n")
    result = check_csv(failed, **ARGS)
    assert result["rows_dropped"] == 4 and result["rows"] == 600 - 4
