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


def _log_csv(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("time_s,t1_C,e_um\n" + "".join(f"{i},{20 + 0.1 * i},{i}\n"
                                                   for i in range(30)))
    return path


@pytest.mark.parametrize("argv_tail, words", [
    (["--json", "{log}/s.json"], "--json {log}/s.json: {log} is a file, not a directory"),
    (["--train-fraction", "1"], "--train-fraction 1.0: between 0.2 and 0.9"),
    (["--min-reduction", "-0.1"], "--min-reduction must be a fraction in [0, 1), got -0.1"),
    (["--row-period", "nan"], "--row-period must be a finite number > 0 [s], got nan"),
    (["--structure-length", "-1"], "--structure-length must be > 0 [m], got -1"),
    (["--namespace", "/mt1"], "--namespace applies to a bag, not to a thermal log"),
])
def test_check_refuses_before_any_work(tmp_path, capsys, monkeypatch, argv_tail, words):
    """A bad option or output path is refused before the log is even read: the engine
    is never called, nothing is written."""
    import mt_accuracy_ros.commands.check_log as check_log

    def must_not_run(*args, **kwargs):
        raise AssertionError("the check ran before its options were checked")

    monkeypatch.setattr(check_log, "check_csv", must_not_run)
    log = _log_csv(tmp_path)
    argv = ["check", str(log), "--target", "e_um", *[a.format(log=log) for a in argv_tail]]
    error = _one_line_error(capsys, argv)
    assert words.format(log=log) in error
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.csv"]


def test_simulate_refuses_an_existing_bag_before_simulating(tmp_path, capsys, monkeypatch):
    import mt_accuracy_ros.sim.machine_tool as machine_tool

    monkeypatch.setattr(machine_tool, "simulate", lambda *a, **k: pytest.fail("simulated"))
    (tmp_path / "out" / "bag").mkdir(parents=True)
    error = _one_line_error(capsys, ["simulate", "demo", "--out", str(tmp_path / "out")])
    assert "bag already exists (a bag is never overwritten); give another --out or --no-bag" \
        in error


def test_a_column_map_that_is_no_yaml_is_one_line(tmp_path, capsys):
    columns = tmp_path / "map.yaml"
    columns.write_text("columns: [unclosed\n  more: {\n")
    error = _one_line_error(capsys, ["check", str(_log_csv(tmp_path)), "--columns",
                                     str(columns)])
    assert error.startswith("mt-accuracy check: ") and "map.yaml" in error


def test_output_paths_rules(tmp_path):
    """One helper decides for every command: a file's directory must exist; a directory
    output may be created under a writable ancestor; a new directory must not exist."""
    from mt_accuracy_ros.core.errors import ParameterError
    from mt_accuracy_ros.io.output_paths import Output, check_output, check_outputs

    assert check_output(Output("--json", None)) is None
    assert check_output(Output("--json", tmp_path / "s.json")) == tmp_path / "s.json"
    # A file's missing directory is made by its writer: accepted, not made by the check.
    assert check_output(Output("--json", tmp_path / "new" / "s.json"))
    assert not (tmp_path / "new").exists()
    (tmp_path / "notes.txt").write_text("x")
    with pytest.raises(ParameterError, match="notes.txt is a file, not a directory"):
        check_output(Output("--report", tmp_path / "notes.txt" / "d" / "r.html"))
    assert check_output(Output("--out", tmp_path / "a" / "b", "directory")) == \
        tmp_path / "a" / "b"
    assert not (tmp_path / "a").exists()          # checked, not created
    (tmp_path / "bag").mkdir()
    with pytest.raises(ParameterError, match="OUTPUT .*bag already exists; give a new"):
        check_output(Output("OUTPUT", tmp_path / "bag", "new directory"))
    with pytest.raises(ParameterError, match="--report .* is a directory; give a file name"):
        check_output(Output("--report", tmp_path))
    with pytest.raises(ParameterError, match=r"--json: an empty path"):
        check_output(Output("--json", ""))
    with pytest.raises(ParameterError, match="is the input .*it would be overwritten"):
        check_outputs([Output("--json", tmp_path / "in.csv")], [tmp_path / "in.csv"])
