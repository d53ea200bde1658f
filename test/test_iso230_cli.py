"""``mt-accuracy iso230-2``: a laser run in, the standard's figures out (issue 30).

The run is written here (targets, five bidirectional runs, a reversal, a periodic
error and noise) and every figure is computed again by hand from ISO 230-2's
definitions with plain Python - loops and the statistics module, no numpy - so a
mistake in the package cannot cancel against the same mistake here.
"""
from __future__ import annotations

import json
import random
import statistics

import pytest

TARGETS_MM = [12.5, 70.0, 131.0, 190.5, 250.0, 312.0, 371.5, 430.0]


def _write_run(path, runs=5, seed=4, drop=None, actual_in_um=False, temperature=None):
    """Readings in the order a laser run takes them: up through every target, overrun,
    down through every target; ``drop`` = (run, target index, direction) left out."""
    rng = random.Random(seed)
    truth = {}
    lines = ["target_mm,actual_" + ("um" if actual_in_um else "mm") +
             (",T_C" if temperature is not None else "")]
    for run in range(runs):
        for direction in (1, -1):
            order = range(len(TARGETS_MM)) if direction > 0 else reversed(range(len(TARGETS_MM)))
            for i in order:
                if drop == (run, i, direction):
                    continue
                deviation_um = 1.8 * (i % 3) - 1.0 + 1.2 * direction + rng.gauss(0, 0.25)
                truth[(run, i, direction)] = deviation_um
                actual_mm = TARGETS_MM[i] + deviation_um * 1e-3
                cell = f"{actual_mm * 1e3:.4f}" if actual_in_um else f"{actual_mm:.7f}"
                extra = f",{temperature(run, i):.3f}" if temperature is not None else ""
                lines.append(f"{TARGETS_MM[i]:.3f},{cell}{extra}")
    path.write_text("\n".join(lines) + "\n")
    return truth


def _by_hand(truth, runs):
    """ISO 230-2's definitions, written out."""
    mean, s = {}, {}
    for d in (1, -1):
        for i in range(len(TARGETS_MM)):
            values = [truth[(j, i, d)] for j in range(runs)]
            mean[(i, d)] = statistics.fmean(values)
            s[(i, d)] = statistics.stdev(values)
    m = len(TARGETS_MM)
    up = [mean[(i, 1)] for i in range(m)]
    down = [mean[(i, -1)] for i in range(m)]
    b_i = [up[i] - down[i] for i in range(m)]
    r_up = [4 * s[(i, 1)] for i in range(m)]
    r_down = [4 * s[(i, -1)] for i in range(m)]
    r_i = [max(2 * s[(i, 1)] + 2 * s[(i, -1)] + abs(b_i[i]), r_up[i], r_down[i])
           for i in range(m)]
    bi_mean = [(up[i] + down[i]) / 2 for i in range(m)]
    high = lambda d: [mean[(i, d)] + 2 * s[(i, d)] for i in range(m)]  # noqa: E731
    low = lambda d: [mean[(i, d)] - 2 * s[(i, d)] for i in range(m)]   # noqa: E731
    return {"A": max(high(1) + high(-1)) - min(low(1) + low(-1)),
            "A↑": max(high(1)) - min(low(1)), "A↓": max(high(-1)) - min(low(-1)),
            "E": max(up + down) - min(up + down), "E↑": max(up) - min(up),
            "E↓": max(down) - min(down), "M": max(bi_mean) - min(bi_mean),
            "R": max(r_i), "R↑": max(r_up), "R↓": max(r_down),
            "B": max(abs(b) for b in b_i), "B̄": statistics.fmean(b_i)}


def test_the_figures_are_the_standards_definitions(tmp_path, capsys):
    from mt_accuracy_ros.cli import main

    truth = _write_run(tmp_path / "run.csv")
    assert main(["iso230-2", str(tmp_path / "run.csv"), "--axis", "y", "--json",
                 str(tmp_path / "s.json"), "--report", str(tmp_path / "r.html")]) == 0
    out = capsys.readouterr().out
    summary = json.loads((tmp_path / "s.json").read_text())
    expected = _by_hand(truth, 5)
    # Directions and runs were inferred from the order of the readings.
    assert summary["targets"] == len(TARGETS_MM) and summary["runs"] == 5
    for symbol, value in expected.items():
        assert summary["figures_um"][symbol] == pytest.approx(value, abs=2e-4), symbol
    assert summary["figures_m"]["accuracy"] == pytest.approx(expected["A"] * 1e-6, abs=2e-10)
    assert f"  A   {expected['A']:9.3f} um   accuracy, bidirectional" in out
    # The units each column was read in are said (here: the header's).
    assert "units: target 'target_mm' in mm, measured 'actual_mm' in mm" in out
    assert summary["units_note"] == "units: target 'target_mm' in mm, measured 'actual_mm' in mm"
    assert len(summary["per_target"]) == len(TARGETS_MM) and not summary["notes"]
    # The report: the figures, the per-target table and the standard's plot.
    titles = [s["title"] for s in summary["report"]["sections"]]
    assert titles == ["ISO 230-2 positioning"]
    assert (tmp_path / "r_iso230_2.png").is_file()
    from browser import validate_html

    validate_html(tmp_path / "r.html")


def test_deviations_are_referred_to_20c_with_the_material_temperature(tmp_path):
    from mt_accuracy_ros.cli import main

    alpha = 11.5e-6
    temperature = lambda run, i: 22.0 + 0.3 * run + 0.05 * i  # noqa: E731
    truth = _write_run(tmp_path / "run.csv", temperature=temperature)
    corrected = {(j, i, d): value - alpha * (temperature(j, i) - 20.0) * TARGETS_MM[i] * 1e3
                 for (j, i, d), value in truth.items()}       # um: alpha dT P[mm] x 1e3
    assert main(["iso230-2", str(tmp_path / "run.csv"), "--col", "temperature=T_C:degC",
                 "--expansion", "11.5", "--json", str(tmp_path / "s.json")]) == 0
    summary = json.loads((tmp_path / "s.json").read_text())
    for symbol, value in _by_hand(corrected, 5).items():
        assert summary["figures_um"][symbol] == pytest.approx(value, abs=2e-4), symbol
    assert "referred to 20" in summary["notes"][0]


@pytest.mark.parametrize("kwargs, flags, message", [
    ({"runs": 1}, [], "too few runs: 1"),
    # The third run (index 2) as the file counts runs: run 3.
    ({"drop": (2, 3, -1)}, [], "unequal target sets: target 190.5 mm has no reading going "
                               "down in run 3"),
    # Micrometres declared as millimetres: a 430 m position, refused naming the unit.
    ({"actual_in_um": True}, ["--col", "measured=actual_um:mm"],
     "measured column 'actual_um': values 1.25e+04 … 4.3e+05 declared mm look like µm"),
    ({}, ["--expansion", "11.5"], "no temperature column"),
    ({}, ["--col", "speed=x"], "ROLE one of"),
])
def test_bad_runs_are_one_line_errors(tmp_path, capsys, kwargs, flags, message):
    from mt_accuracy_ros.cli import main

    _write_run(tmp_path / "run.csv", **kwargs)
    assert main(["iso230-2", str(tmp_path / "run.csv"), *flags]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err
