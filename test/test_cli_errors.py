"""Every CLI error is one line on stderr and exit status 2; CSV rows left out are counted."""
from __future__ import annotations

import subprocess
import sys

import pytest

from conftest import DATA
from mt_accuracy_ros.cli import main


def _one_line_error(capsys, argv) -> str:
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert "Traceback" not in captured.err
    return lines[0]


def test_ragged_csv_names_the_row(tmp_path, capsys):
    path = tmp_path / "log.csv"
    path.write_text("time_s,t1_C,e_um\n" + "".join(f"{i},{20 + i},{i}\n" for i in range(20))
                    + "21,3\n")
    error = _one_line_error(capsys, ["check", str(path), "--target", "e_um"])
    assert "row 22 has 2 fields" in error


def test_csv_rows_with_nan_or_text_are_counted(tmp_path, capsys):
    path = tmp_path / "log.csv"
    rows = [f"{i},{20 + 0.1 * i},{0.5 * i}" for i in range(40)]
    rows[5] = "5,nan,2.5"
    rows[9] = "9,broken,4.5"
    path.write_text("time_s,t1_C,e_um\n" + "\n".join(rows) + "\n")
    assert main(["check", str(path), "--target", "e_um", "--json", str(tmp_path / "s.json")]) == 0
    out = capsys.readouterr().out
    assert "38 of 40 rows used; 2 dropped" in out
    assert "row 7 column t1_C: nan is not finite" in out
    assert "row 11 column t1_C: 'broken' is not a number" in out


@pytest.mark.parametrize("argv_tail,words", [
    (["--target", "no_such_column"], "no_such_column"),
    (["--target", "ch5_um", "--time-column", "clock"], "no time column"),
])
def test_csv_column_errors(capsys, argv_tail, words):
    error = _one_line_error(capsys, ["check", str(DATA / "fl_thermal" / "fl_thermal.csv"),
                                     *argv_tail])
    assert words in error


def test_binary_files_are_refused_in_one_line(tmp_path, capsys):
    binary = tmp_path / "scenario.yaml"
    binary.write_bytes(bytes(range(256)) * 8)
    assert "not a text file" in _one_line_error(capsys, ["simulate", str(binary), "--out",
                                                         str(tmp_path / "o")])
    csv = tmp_path / "log.csv"
    csv.write_bytes(bytes(range(256)) * 8)
    assert "not a text CSV" in _one_line_error(capsys, ["check", str(csv), "--target", "x"])


def test_check_with_a_bad_model_is_one_line(tmp_path, capsys):
    error = _one_line_error(capsys, ["check", str(tmp_path / "bag"), "--model",
                                     "machine: kidani_hmc\neffects: [squareness]\n"])
    assert "'effects' must map" in error


@pytest.mark.parametrize("arguments,words", [
    (["-p", "machine:=no_such_machine"], "no bundled machine 'no_such_machine'"),
    (["-p", "window:=-5"], "window"),
])
def test_bad_startup_parameters_of_a_node_are_one_line_and_exit_2(arguments, words):
    result = subprocess.run([sys.executable, "-m", "mt_accuracy_ros.nodes.yaw_estimator",
                             "--ros-args", *arguments], capture_output=True, text=True,
                            timeout=60)
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    assert words in result.stderr
    assert len([line for line in result.stderr.splitlines() if line.strip()]) == 1


def test_a_batch_too_large_for_best_effort_delivery_is_refused_at_start(tmp_path):
    """Issue 29: a ScaleBatch the best-effort scales topic would drop (measured: > ~0.5 MB)
    is refused when the CNC starts, naming the limit - not lost in silence."""
    scenario = tmp_path / "fast.yaml"
    scenario.write_text("machine: kidani_hmc\nduration_s: 10\nsample_rate_hz: 20000\n")
    result = subprocess.run([sys.executable, "-m", "mt_accuracy_ros.nodes.encoder_publisher",
                             "--ros-args", "-p", f"scenario:={scenario}", "-p",
                             "batch_period_s:=1.0"], capture_output=True, text=True, timeout=60)
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    assert "best-effort 'scales' topic delivers batches up to 0.45 MB" in result.stderr


def test_playing_nothing_is_an_error():
    result = subprocess.run([sys.executable, "-m", "mt_accuracy_ros.nodes.player", "--ros-args",
                             "-p", f"bag:={DATA / 'rosbag2_samples' / 'talker'}",
                             "-p", "topics:=[/no_such_topic]"],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert "nothing to play" in result.stderr and "/no_such_topic" in result.stderr


@pytest.mark.parametrize("argv", [["demo", "--rat", "2"], ["check", "x.csv", "--targ", "e_um"]])
def test_abbreviated_options_are_refused(argv, capsys):
    # `--rat 2` once ran the demo at rate 2 without a word (issue 26): no guessing.
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert f"unrecognized arguments: {argv[-2]}" in capsys.readouterr().err
