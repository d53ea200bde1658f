"""Report sections on data built for them: ISO 230-2 when positioning runs exist."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest


def _reading(x: float, error_x: float, direction: int):
    from mt_accuracy_msgs.msg import ReferenceMeasurement

    message = ReferenceMeasurement()
    message.command_axes = ["x", "y", "z"]
    message.command_positions = [x, -0.2, 0.1]
    message.command_directions = [direction, 0, 0]
    message.error.x = error_x
    message.measured = [True, False, False]
    message.uncertainty = 1e-6
    return message


def test_iso230_2_section_from_stop_and_measure_readings(tmp_path):
    from mt_accuracy_ros.core.scales.repeatability import iso230_2
    from mt_accuracy_ros.report.bag_data import BagData
    from mt_accuracy_ros.report.sections import _iso_section

    rng = np.random.default_rng(2)
    targets = np.linspace(0.0, 0.4, 5)
    up, down, references = [], [], []
    for run in range(3):
        for sign in (1, -1):
            for target in targets[::sign]:
                deviation = 3e-6 * target + sign * 0.5e-6 + rng.normal(0, 1e-7)
                (up if sign > 0 else down).append(deviation)
                references.append((len(references), _reading(target, deviation, sign)))
    data = BagData(Path("synthetic"), {"message_count": 0, "topics": {}, "duration_s": 0}, 0,
                   references=references)
    section = _iso_section(data, tmp_path, "r")
    row = {c: cell.text for c, cell in zip(section.tables[0].columns,
                                           section.tables[0].rows[0].cells)}
    expected = iso230_2(targets, np.array(up).reshape(3, 5).T,
                        np.array(down).reshape(3, 5)[:, ::-1].T)
    assert row["axis"] == "X"
    assert float(row["B"]) == pytest.approx(expected.reversal_value * 1e6, rel=1e-3)
    assert float(row["A"]) == pytest.approx(expected.accuracy * 1e6, rel=1e-3)
    assert float(row["R↑"]) == pytest.approx(expected.repeatability_up_axis * 1e6, rel=1e-3)
    # The standard's plot is written beside the report, never into the working directory.
    assert (tmp_path / "r_iso230_2.png").is_file()


def test_iso230_2_section_says_so_without_positioning_runs(tmp_path):
    from mt_accuracy_ros.report.bag_data import BagData
    from mt_accuracy_ros.report.sections import _iso_section

    continuous = [(k, _reading(0.2 + 0.2 * np.sin(k / 7), 0.0, 1 if np.cos(k / 7) > 0 else -1))
                  for k in range(300)]
    data = BagData(Path("synthetic"), {"message_count": 0, "topics": {}, "duration_s": 0}, 0,
                   references=continuous)
    section = _iso_section(data, tmp_path, "r")
    assert not section.tables and "no positioning runs" in section.paragraphs[0]
