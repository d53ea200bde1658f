"""Bad files and bad options: each refused in one line naming the problem and the mend,
before any work and with nothing written - or read, when it can be, and said.

Each class of :data:`CLASSES` is built in ``tmp_path`` by its builder (:data:`BUILDERS`:
the command line and the outputs it names) and run through the real command line
(:func:`mt_accuracy_ros.cli.main`).
"""
from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

from conftest import DATA
from mt_accuracy_ros.cli import main

#: (class name, the bad input as a user would meet it, the outcome's key words).
CLASSES = [
    ("utf16_csv", "a thermal log saved by Excel as \"Unicode text\" (UTF-16 with a "
     "byte-order mark)", "announced: read as UTF-16 (BOM)"),
    ("utf16_big_endian_csv", "a thermal log in big-endian UTF-16 with its byte-order mark",
     "announced: read as UTF-16 (BOM)"),
    ("utf16_csv_without_bom", "a UTF-16 CSV whose byte-order mark was lost (every other "
     "byte NUL)", "refused: holds NUL bytes); a UTF-16 export without a byte-order mark? "
     "save it as UTF-8 CSV"),
    ("png_as_bag", "a PNG image given to check as its data",
     "refused: is a PNG image, not an MCAP bag or a CSV"),
    ("random_bytes_as_bag", "a file of random bytes given to check",
     "refused: is not an MCAP file (no MCAP magic) nor text"),
    ("empty_bag_file", "an empty .mcap file given to info",
     "refused: is empty (0 bytes), not an MCAP bag"),
    ("truncated_mcap", "an MCAP bag cut short (a recorder killed mid-run) given to check",
     "refused: is a truncated MCAP file (it ends without its footer and summary: a recorder "
     "killed mid-run?); `mt-accuracy recover"),
    ("foreign_mcap", "an MCAP file of JSON messages written by another tool (no ros2 "
     "profile) given to check",
     "refused: is an MCAP file of another kind (profile '', json messages), not a ROS 2 bag"),
    ("csv_given_to_info", "a CSV log given to info (which reads bags)",
     "refused: is a CSV, not an MCAP bag; `mt-accuracy check"),
    ("png_named_csv", "a PNG image named log.csv given to check as a thermal log",
     "refused: is a PNG image, not a CSV"),
    ("sqlite_bag_to_play", "a rosbag2 SQLite bag (a directory of .db3) given to play",
     "refused: is a rosbag2 SQLite bag: `ros2 bag convert` it to MCAP"),
    ("mcap_damaged_inside", "an MCAP bag whose first chunk is overwritten (magic and footer "
     "intact) given to topic list", "refused: damaged MCAP file, no topic readable before "
     "the damage"),
    ("ballbar_simulation_option_on_a_measured_file", "ballbar of a measured file with "
     "--backlash (only a simulated table has one)",
     "refused: --backlash applies to a simulated measurement (--simulate SEED), not to a "
     "measured file"),
    ("export_option_of_another_controller", "export for a SINUMERIK with --fanuc-step-limit",
     "refused: --fanuc-step-limit applies to --controller fanuc, not to --controller "
     "siemens"),
    ("train_fraction_out_of_range", "check of a thermal log with --train-fraction 2",
     "refused: --train-fraction 2.0: between 0.2 and 0.9 (the rows after it judge the "
     "model)"),
    ("uncertainty_flag_in_nanometres", "check of a thermal log with --uncertainty-um 5000 "
     "(meant as nanometres)", "refused: --uncertainty-um: value 5000 declared µm looks like "
     "nm (plausible uncertainty: 1 nm … 1 mm); the flag is in micrometres"),
    ("log_flag_with_a_survey", "check of a survey (a column map) with --train-fraction, "
     "which only a thermal log reads",
     "refused: --train-fraction applies to a thermal log (a CSV with --target), not to a "
     "survey"),
    ("log_flag_with_a_bag", "check of a bag with --target, which only a thermal log reads",
     "refused: --target applies to a thermal log (a CSV with --target), not to a bag"),
    ("survey_flag_with_a_bag", "check of a bag with --columns, which only a survey reads",
     "refused: --columns applies to a survey (a CSV with a column map: --columns or --col), "
     "not to a bag"),
    ("negative_auto", "check of a bag with --auto -1",
     "refused: --auto must be an integer >= 0, got -1"),
    ("min_reduction_out_of_range", "fleet with --min-reduction 1.5",
     "refused: --min-reduction must be a fraction in [0, 1), got 1.5"),
    ("zero_workers", "fleet with --workers 0",
     "refused: --workers must be an integer >= 1, got 0"),
    ("play_rate_zero", "play with --rate 0", "refused: -r/--rate must be a speed factor > 0, "
     "got 0"),
    ("play_negative_start_offset", "play with --start-offset -5",
     "refused: --start-offset must be >= 0 [s], got -5"),
    ("malformed_remap", "play with --remap /a/b (no :=)",
     "refused: --remap must be OLD:=NEW, got '/a/b'"),
    ("csv_stride_zero", "simulate with --csv-stride 0",
     "refused: --csv-stride must be an integer >= 1, got 0"),
    ("negative_max_bag_size", "record with --max-bag-size -1",
     "refused: --max-bag-size must be an integer >= 0 [bytes; 0: no split], got -1"),
    ("non_finite_expansion", "iso230-2 with --expansion inf",
     "refused: --expansion must be a finite number in [-300, 300] [um/m/K], got inf"),
    ("expansion_in_per_kelvin", "iso230-2 with --expansion 11.5e-6 (1/K, not um/m/K)",
     "refused: that looks like 1/K (times 1e6: 11.5)"),
    ("rate_with_lockstep", "demo with --rate 2 and --lockstep (data time: no rate)",
     "refused: --rate applies to a demo in real time, not to --lockstep"),
    ("zeroed_runs_without_run", "check of a thermal log with --zeroed-runs but no --run",
     "refused: --zeroed-runs needs --run COLUMN (the instrument was zeroed at each run's "
     "start)"),
    ("live_flag_with_a_bag", "topic hz on a bag with --duration (a live-graph option)",
     "refused: --duration applies to the live graph, not to a bag"),
    ("json_with_an_empty_path", "check with --json \"\" (an empty path)",
     "refused: --json: an empty path; give a file or directory name"),
    ("json_is_a_directory", "check with --json naming an existing directory",
     "refused: is a directory; give a file name in it"),
    ("json_overwrites_the_input", "check with --json naming its own input CSV",
     "refused: it would be overwritten (give another path)"),
    ("report_under_a_file", "check with --report under a path that is a file, not a "
     "directory", "refused: is a file, not a directory"),
    ("json_and_report_on_one_path", "check with --json and --report naming the same file",
     "refused: is also --json's path; give each output its own"),
    ("recover_into_an_existing_path", "recover into an output that already exists",
     "refused: already exists; give a new directory (a bag is never overwritten)"),
    ("simulate_out_is_a_file", "simulate with --out naming an existing file",
     "refused: is a file, not a directory"),
]


def _thermal_log_rows() -> str:
    """A small thermal log: time [s], a temperature [degC], a displacement [um]."""
    return "time_s,t1_C,e_um\n" + "".join(f"{i * 60},{20 + 0.1 * i:.2f},{0.5 * i:.2f}\n"
                                          for i in range(40))


def _log(tmp_path: Path, encoding: str = "utf-8", mark: bytes = b"") -> Path:
    path = tmp_path / "log.csv"
    path.write_bytes(mark + _thermal_log_rows().encode(encoding))
    return path


def _damaged_bag(tmp_path: Path) -> Path:
    data = bytearray((DATA / "rosbag2_samples" / "talker" / "talker.mcap").read_bytes())
    data[3000:3400] = b"\xab" * 400
    path = tmp_path / "damaged.mcap"
    path.write_bytes(bytes(data))
    return path


def _png(path: Path) -> Path:
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(200))
    return path


def _truncated_bag(tmp_path: Path) -> Path:
    whole = (DATA / "rosbag2_samples" / "talker" / "talker.mcap").read_bytes()
    path = tmp_path / "killed.mcap"
    path.write_bytes(whole[:len(whole) * 2 // 3])
    return path


def _foreign_mcap(tmp_path: Path) -> Path:
    from mcap.writer import Writer

    path = tmp_path / "foreign.mcap"
    with open(path, "wb") as stream:
        writer = Writer(stream)
        writer.start(profile="", library="another tool")
        schema = writer.register_schema(name="Pose", encoding="jsonschema", data=b"{}")
        channel = writer.register_channel(topic="/reference/tcp_error", message_encoding="json",
                                          schema_id=schema)
        for i in range(5):
            writer.add_message(channel_id=channel, log_time=i, publish_time=i,
                               data=json.dumps({"x": i}).encode())
        writer.finish()
    return path


TALKER = str(DATA / "rosbag2_samples" / "talker")


def _build(name: str, tmp_path: Path) -> list[str]:
    """The command line of class ``name``, its input built in ``tmp_path`` (its outputs, if
    any, go there too: ``s.json``, ``r.html``)."""
    json_path, report = tmp_path / "s.json", tmp_path / "r.html"
    log = lambda: str(_log(tmp_path))  # noqa: E731 - built only by the classes that use it
    a_file = tmp_path / "plain.txt"
    builders = {
        "utf16_csv": lambda: ["check", str(_log(tmp_path, "utf-16")), "--target", "e_um",
                              "--json", str(json_path)],
        "utf16_big_endian_csv": lambda: ["check", str(_log(tmp_path, "utf-16-be", b"\xfe\xff")),
                                         "--target", "e_um", "--json", str(json_path)],
        "mcap_damaged_inside": lambda: ["topic", "list", "--bag", str(_damaged_bag(tmp_path))],
        "ballbar_simulation_option_on_a_measured_file": lambda: [
            "ballbar", log(), "--backlash", "--json", str(json_path)],
        "export_option_of_another_controller": lambda: [
            "export", "demo", "--out", str(tmp_path / "tables"), "--controller", "siemens",
            "--fanuc-step-limit", "7"],
        "utf16_csv_without_bom": lambda: ["check", str(_log(tmp_path, "utf-16-le")),
                                          "--target", "e_um", "--json", str(json_path)],
        "png_as_bag": lambda: ["check", str(_png(tmp_path / "photo.png")), "--json",
                               str(json_path)],
        "random_bytes_as_bag": lambda: (tmp_path / "blob.bin").write_bytes(
            bytes(range(256)) * 4) and ["check", str(tmp_path / "blob.bin")],
        "empty_bag_file": lambda: (tmp_path / "empty.mcap").touch() or
        ["info", str(tmp_path / "empty.mcap")],
        "truncated_mcap": lambda: ["check", str(_truncated_bag(tmp_path)), "--json",
                                   str(json_path)],
        "foreign_mcap": lambda: ["check", str(_foreign_mcap(tmp_path)), "--report",
                                 str(report)],
        "csv_given_to_info": lambda: ["info", log()],
        "png_named_csv": lambda: ["check", str(_png(tmp_path / "log.csv")), "--target", "e_um",
                                  "--json", str(json_path)],
        "sqlite_bag_to_play": lambda: (tmp_path / "bag").mkdir() or (
            tmp_path / "bag" / "bag_0.db3").write_bytes(b"SQLite format 3\x00" + bytes(100))
        and ["play", str(tmp_path / "bag")],
        "train_fraction_out_of_range": lambda: ["check", log(), "--target", "e_um",
                                                "--train-fraction", "2", "--json",
                                                str(json_path)],
        "uncertainty_flag_in_nanometres": lambda: ["check", log(), "--target", "e_um",
                                                   "--uncertainty-um", "5000", "--json",
                                                   str(json_path)],
        "log_flag_with_a_survey": lambda: ["check", log(), "--col", "pos.X=time_s:mm",
                                           "--col", "err.x=e_um:um", "--train-fraction",
                                           "0.6", "--json", str(json_path)],
        "log_flag_with_a_bag": lambda: ["check", TALKER, "--target", "e_um"],
        "survey_flag_with_a_bag": lambda: ["check", TALKER, "--columns", "map.yaml"],
        "negative_auto": lambda: ["check", TALKER, "--auto", "-1"],
        "min_reduction_out_of_range": lambda: ["fleet", str(tmp_path), "--min-reduction",
                                               "1.5", "--json", str(json_path)],
        "zero_workers": lambda: ["fleet", str(tmp_path), "--workers", "0"],
        "play_rate_zero": lambda: ["play", TALKER, "--rate", "0"],
        "play_negative_start_offset": lambda: ["play", TALKER, "--start-offset", "-5"],
        "malformed_remap": lambda: ["play", TALKER, "--remap", "/a/b"],
        "csv_stride_zero": lambda: ["simulate", "demo", "--out", str(tmp_path / "sim"),
                                    "--csv-stride", "0"],
        "negative_max_bag_size": lambda: ["record", "-o", str(tmp_path / "rec"),
                                          "--max-bag-size", "-1"],
        "non_finite_expansion": lambda: ["iso230-2", log(), "--expansion", "inf",
                                         "--json", str(json_path)],
        "expansion_in_per_kelvin": lambda: ["iso230-2", log(), "--expansion", "11.5e-6"],
        "rate_with_lockstep": lambda: ["demo", "--out", str(tmp_path / "demo"), "--rate", "2",
                                       "--lockstep"],
        "zeroed_runs_without_run": lambda: ["check", log(), "--target", "e_um",
                                            "--zeroed-runs"],
        "live_flag_with_a_bag": lambda: ["topic", "hz", "/topic", "--bag", TALKER,
                                         "--duration", "3"],
        "json_with_an_empty_path": lambda: ["check", log(), "--target", "e_um", "--json", ""],
        "json_is_a_directory": lambda: ["check", log(), "--target", "e_um", "--json",
                                        str(tmp_path)],
        "json_overwrites_the_input": lambda: ["check", log(), "--target", "e_um", "--json",
                                              str(tmp_path / "log.csv")],
        "report_under_a_file": lambda: a_file.write_text("x") and [
            "check", log(), "--target", "e_um", "--report", str(a_file / "r.html")],
        "json_and_report_on_one_path": lambda: ["check", log(), "--target", "e_um", "--json",
                                                str(json_path), "--report", str(json_path)],
        "recover_into_an_existing_path": lambda: (tmp_path / "salvaged").mkdir() or [
            "recover", str(_truncated_bag(tmp_path)), str(tmp_path / "salvaged")],
        "simulate_out_is_a_file": lambda: a_file.write_text("x") and [
            "simulate", "demo", "--out", str(a_file)],
    }
    return builders[name]()


def _files(root: Path) -> dict[str, bytes]:
    """Every file under ``root`` with its content (directories by name)."""
    return {str(p.relative_to(root)): (p.read_bytes() if p.is_file() else b"<dir>")
            for p in sorted(root.rglob("*"))}


def test_the_corpus_has_its_classes_and_every_class_a_builder(tmp_path):
    assert len(CLASSES) >= 16 and len({name for name, _, _ in CLASSES}) == len(CLASSES)
    for name, description, outcome in CLASSES:
        assert description and outcome.split(":")[0] in ("refused", "announced"), name


@pytest.mark.parametrize("name,description,outcome", CLASSES, ids=[c[0] for c in CLASSES])
def test_bad_input(name, description, outcome, tmp_path, capsys):
    argv = _build(name, tmp_path)
    verdict, _, words = outcome.partition(": ")
    before = _files(tmp_path)
    code = main(argv)
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err
    if verdict == "refused":
        assert code == 2, captured
        lines = captured.err.strip().splitlines()
        assert len(lines) == 1, captured.err
        assert words in lines[0], lines[0]
        assert lines[0].startswith(f"mt-accuracy {argv[0]}: ")
        # Nothing written: no output, no directory made, no file of the tree changed.
        assert _files(tmp_path) == before
        return
    assert code == 0, captured.err
    assert words in captured.out
    summary = json.loads((tmp_path / "s.json").read_text())
    assert words in json.dumps(summary, ensure_ascii=False)


def test_a_utf8_csv_with_a_byte_order_mark_is_read_without_a_note(tmp_path, capsys):
    """UTF-8 with its mark is plain UTF-8: read, and nothing to say about it."""
    path = tmp_path / "log.csv"
    path.write_bytes(_thermal_log_rows().encode("utf-8-sig"))
    assert main(["check", str(path), "--target", "e_um"]) == 0
    out = capsys.readouterr().out
    assert "log.csv: 40 of 40 rows used\n" in out or "log.csv: 40 of 40 rows used;" in out


def test_a_truncated_bag_is_still_recovered(tmp_path, capsys):
    """recover is offered for a truncated bag: it works on one."""
    source = _truncated_bag(tmp_path)
    assert main(["recover", str(source), str(tmp_path / "salvaged")]) == 0
    assert "recovered" in capsys.readouterr().out
    assert main(["info", str(tmp_path / "salvaged")]) == 0
    shutil.rmtree(tmp_path / "salvaged")


def test_a_model_saved_as_utf16_by_a_windows_editor_is_read(tmp_path):
    """A description's byte-order mark declares its encoding: read by it, same text."""
    from mt_accuracy_ros.core.errors import ParameterError
    from mt_accuracy_ros.core.inputs.safe_files import read_description

    text = "machine: kidani_hmc\neffects: {}\n"
    path = tmp_path / "model.yaml"
    path.write_bytes(text.encode("utf-16"))
    assert read_description(path, "model", ParameterError) == text
    _png(path)
    with pytest.raises(ParameterError, match="model is a PNG image, not a YAML text file"):
        read_description(path, "model", ParameterError)
    path.write_bytes(text.encode("utf-16-le"))
    with pytest.raises(ParameterError, match="UTF-16 without a byte-order mark"):
        read_description(path, "model", ParameterError)


def test_record_without_a_name_checks_its_default_bag_before_starting(tmp_path, monkeypatch,
                                                                      capsys):
    """No -o: the bag's default name in the working directory is chosen and checked by the
    command, before any node starts (here it is taken), and said when it is used."""
    import mt_accuracy_ros.io.bag_writer as bag_writer

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(bag_writer, "default_bag_name", lambda: "rosbag2_taken")
    (tmp_path / "rosbag2_taken").mkdir()
    assert main(["record"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == ("mt-accuracy record: -o/--output rosbag2_taken already exists; give a new "
                   "directory (a bag is never overwritten)")
    monkeypatch.undo()          # the real name: ros2 bag record's rosbag2_<date>-<time>
    assert re.fullmatch(r"rosbag2_\d{4}_\d\d_\d\d-\d\d_\d\d_\d\d",
                        bag_writer.default_bag_name())
