"""Finding a fleet's data: directories, globs and manifests, and the day of each file."""
from __future__ import annotations

import datetime as dt
from pathlib import Path

import pytest

from mt_accuracy_ros.core.errors import InputDataError
from mt_accuracy_ros.io.fleet_inputs import day_of, discover, plan_days


def _bag(folder: Path, start: dt.datetime) -> Path:
    """A real bag (two temperature messages) whose first message is at ``start``."""
    from rclpy.serialization import serialize_message

    from mt_accuracy_msgs.msg import TemperatureArray
    from mt_accuracy_ros.io.bag_writer import BagWriter

    t0 = int(start.timestamp() * 1e9)
    with BagWriter(folder) as bag:
        bag.add_topic("/temperatures", "mt_accuracy_msgs/msg/TemperatureArray")
        for k in range(2):
            bag.write("/temperatures", serialize_message(TemperatureArray()), t0 + k * 10**9)
    return folder


UTC = dt.timezone.utc


@pytest.fixture
def plant(tmp_path):
    """plant/m1 (a model of its own, two days), plant/m2 (one bag, one dated survey)."""
    root = tmp_path / "plant"
    _bag(root / "m1" / "monday", dt.datetime(2026, 11, 23, 23, 59, 0, tzinfo=UTC))
    _bag(root / "m1" / "tuesday", dt.datetime(2026, 11, 24, 0, 1, 0, tzinfo=UTC))
    (root / "m1" / "model.yaml").write_text("machine: kidani_hmc\neffects: {geometric: {}}\n")
    _bag(root / "m2" / "run", dt.datetime(2026, 11, 24, 8, 0, 0, tzinfo=UTC))
    (root / "m2" / "survey_20261125.csv").write_text("x\n1\n")
    (root / "m2" / "notes.txt").write_text("not data")
    return root


def test_a_directory_has_a_machine_per_folder_with_its_own_model(plant):
    found = discover([str(plant)], model="demo")
    assert [(d.machine, Path(d.path).name, d.kind) for d in found] == [
        ("m1", "monday", "bag"), ("m1", "tuesday", "bag"), ("m2", "run", "bag"),
        ("m2", "survey_20261125.csv", "survey_csv")]
    assert found[0].model == str((plant / "m1" / "model.yaml").resolve())
    assert found[2].model == "demo"     # no model.yaml of its own: the default


def test_days_come_from_the_first_message_in_utc_and_from_a_survey_s_name(plant):
    days = plan_days(discover([str(plant)]))
    assert [(d.machine, d.day) for d in days] == [
        ("m1", "2026-11-23"), ("m1", "2026-11-24"), ("m2", "2026-11-24"), ("m2", "2026-11-25")]
    assert days[1].day_number - days[0].day_number == 1.0
    task = days[0].as_task(3, 0.05)
    assert task["datasets"][0]["path"].endswith("monday") and task["auto"] == 3


def test_a_damaged_bag_takes_its_day_from_metadata_and_an_unknown_one_is_its_own_day(plant):
    bag = plant / "m1" / "monday"
    mcap = next(bag.glob("*.mcap"))
    mcap.write_bytes(mcap.read_bytes()[:300])
    (dataset,) = [d for d in discover([str(plant)]) if d.path.endswith("monday")]
    assert day_of(dataset) == ("2026-11-23", float(dt.date(2026, 11, 23).toordinal()))
    (bag / "metadata.yaml").unlink()
    assert day_of(dataset) == ("undated: monday", None)


def test_a_glob_names_each_machine_by_its_folder(plant):
    found = discover([str(plant / "*" / "*day")])
    assert {(d.machine, Path(d.path).name) for d in found} == {("m1", "monday"),
                                                               ("m1", "tuesday")}
    # a file of a bag directory stands for its bag
    (only,) = discover([str(plant / "m2" / "run" / "*.mcap")])
    assert only.machine == "m2" and Path(only.path).name == "run"


def test_a_manifest_names_machines_and_resolves_paths_from_its_folder(plant, tmp_path):
    (tmp_path / "maps").mkdir()
    (tmp_path / "maps" / "m.yaml").write_text("positions: {X: x}\n")
    manifest = tmp_path / "fleet.yaml"
    manifest.write_text("machines:\n"
                        "  left: {model: plant/m1/model.yaml, data: [plant/m1/*day]}\n"
                        "  right: {machine: vmc, columns: maps/m.yaml, data: plant/m2/*.csv}\n")
    found = discover([str(manifest)])
    assert [(d.machine, Path(d.path).name) for d in found] == [
        ("left", "monday"), ("left", "tuesday"), ("right", "survey_20261125.csv")]
    assert found[0].model == str((plant / "m1" / "model.yaml").resolve())
    assert found[2].machine_file == "vmc"            # a bundled name, as given
    assert found[2].columns == str((tmp_path / "maps" / "m.yaml").resolve())


@pytest.mark.parametrize("text, message", [
    ("machines: {a: {data: [nothing/*]}}", "match no bag"),
    ("machines: {a: {data: [x], colour: red}}", "unknown key 'colour'"),
    ("machines: {a: {model: demo}}", "has no data"),
    ("machines: [a, b]", "expected 'machines:'"),
    ("machines: {a: [1]}", "expected a mapping"),
])
def test_a_bad_manifest_is_one_line_naming_the_machine(tmp_path, text, message):
    manifest = tmp_path / "fleet.yaml"
    manifest.write_text(text)
    with pytest.raises(InputDataError, match=message):
        discover([str(manifest)])


def test_inputs_that_hold_nothing_are_refused(tmp_path):
    with pytest.raises(InputDataError, match="matches no bag"):
        discover([str(tmp_path / "none" / "*")])
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputDataError, match="no bag or survey found"):
        discover([str(tmp_path / "empty")])
    (tmp_path / "x.txt").write_text("")
    with pytest.raises(InputDataError, match="not a bag"):
        discover([str(tmp_path / "x.txt")])
    with pytest.raises(InputDataError, match="give a directory"):
        discover([])
