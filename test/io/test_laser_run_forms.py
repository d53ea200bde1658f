"""Laser runs as instruments write them (issue 42, item 2): direction words and arrows,
named runs, units in the header, both approaches in one run, every refused row named.
Each form must give the figures of the same run written plainly (+1/-1, mm, um)."""
from __future__ import annotations

import random

import pytest

from mt_accuracy_ros.commands.iso230 import evaluate_run
from mt_accuracy_ros.io.laser_run import direction_of, header_unit

TARGETS_MM = [10.0, 60.0, 125.0, 180.0, 240.0, 300.0]


def _readings(runs: int = 5, seed: int = 7):
    """(run, target_mm, direction, deviation_um) in the order a laser run takes them."""
    rng = random.Random(seed)
    out = []
    for run in range(runs):
        for direction in (1, -1):
            order = TARGETS_MM if direction > 0 else list(reversed(TARGETS_MM))
            for i, target in enumerate(order):
                out.append((run, target, direction,
                            0.8 * (i % 2) + 1.1 * direction + rng.gauss(0, 0.2)))
    return out


def _write(path, header, row_of):
    path.write_text(header + "\n" + "\n".join(row_of(*r) for r in _readings()) + "\n")
    return path


def _figures(path):
    result = evaluate_run(path, [])
    return result["figures_um"], result


@pytest.fixture
def plain(tmp_path):
    return _figures(_write(tmp_path / "plain.csv", "run,target_mm,direction,deviation_um",
                           lambda j, t, d, e: f"{j},{t},{d},{e:.5f}"))[0]


@pytest.mark.parametrize("up, down", [("+", "-"), ("up", "down"), ("fwd", "bwd"),
                                      ("forward", "backward"), ("↑", "↓"), ("UP", "Down")])
def test_direction_words_and_named_runs_give_the_plain_figures(tmp_path, plain, up, down):
    path = _write(tmp_path / "words.csv", "Run,Target [mm],Direction,Deviation (µm)",
                  lambda j, t, d, e: f"run {chr(65 + j)},{t},{up if d > 0 else down},{e:.5f}")
    figures, result = _figures(path)
    assert figures == pytest.approx(plain, abs=1e-9)
    assert result["runs"] == 5 and result["refused_rows"] == []


def test_a_header_in_any_unit_the_survey_map_knows(tmp_path, plain):
    # Targets in inches, deviations in nm: the same run.
    path = _write(tmp_path / "units.csv", "target (in),deviation [nm],direction",
                  lambda j, t, d, e: f"{t / 25.4:.9f},{e * 1000:.2f},{d}")
    assert _figures(path)[0] == pytest.approx(plain, abs=1e-6)
    assert header_unit("Target (mm)") == ("Target", "mm")
    assert header_unit("deviation [µm]") == ("deviation", "µm")
    assert header_unit("actual_um") == ("actual", "um") and header_unit("run") == ("run", "")


def test_both_approaches_of_one_run_are_read_as_bidirectional(tmp_path, plain):
    # A run column whose runs each go up and back, no direction column: the approach is
    # read off the moves, the two readings of a target in one run are its two sides.
    path = _write(tmp_path / "both.csv", "cycle,target_mm,deviation_um",
                  lambda j, t, d, e: f"{j + 1},{t},{e:.5f}")
    assert _figures(path)[0] == pytest.approx(plain, abs=1e-9)


@pytest.mark.parametrize("bad, column, shown", [
    ("5,10.0,sideways,1.0", "direction", "'sideways' is not a direction (+/-, up/down, "
     "fwd/bwd, forward/backward, ↑/↓, +1/-1)"),
    ("5,n/a,+,1.0", "target_mm", "'n/a' is not a number"),
    ("5,60.0,+,", "deviation_um", "'' is not a number"),
    ("5,60.0,+,nan", "deviation_um", "nan is not finite"),
    ("5,inf,+,1.0", "target_mm", "inf is not finite"),
    ("6,60.0,0,2.0", "direction", "'0' is not a direction"),
])
def test_a_bad_row_is_refused_naming_its_row_column_and_value(tmp_path, capsys, bad, column,
                                                             shown):
    """A positioning run needs every reading: a dropped one would only surface later as
    "unequal target sets" in some run. The row is numbered as an editor shows it (the
    header is row 1); nothing is written."""
    from mt_accuracy_ros.cli import main

    path = _write(tmp_path / "junk.csv", "run,target_mm,direction,deviation_um",
                  lambda j, t, d, e: f"{j},{t},{'+' if d > 0 else '-'},{e:.5f}")
    lines = path.read_text().splitlines()
    lines.insert(7, bad)
    lines.append("7,60.0,sideways,1.0")          # a later bad row: the first one is named
    path.write_text("\n".join(lines) + "\n")
    assert main(["iso230-2", str(path), "--json", str(tmp_path / "s.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"mt-accuracy iso230-2: junk.csv: row 8 column {column}: {shown}; a "
                   "positioning run needs every reading: correct or delete the row") \
        or (err.startswith(f"mt-accuracy iso230-2: junk.csv: row 8 column {column}: {shown}")
            and "\n" not in err)
    assert not (tmp_path / "s.json").exists()


def test_direction_of_reads_what_instruments_write():
    assert [direction_of(x) for x in ("+", "-", "↑", "↓", "+1", "-1", "2.0", "Forward",
                                      " bwd ")] == [1, -1, 1, -1, 1, -1, 1, 1, -1]
    assert direction_of("0") is None and direction_of("left") is None
