"""Surveys in the user's conventions: the map says what a metrologist knows.

The data come from generators that share no code with the package
(``studies/cartesian_surveys.py``, ``studies/convention_surveys.py``): tables that move
against the command, rotary axes turning about their real lines, the work set up at a
rotary pose, units and column names drawn at random.
"""
from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import pytest
import yaml

from mt_accuracy_ros.cli import main
from studies.cartesian_surveys import LAYOUTS, single_effect_trial


def _check(csv: Path, column_map: Path, *extra: str) -> tuple[int, dict | None, str]:
    out = csv.parent / f"check{len(extra)}.json"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(printed):
        code = main(["check", str(csv), "--columns", str(column_map), "--auto", "3",
                     "--json", str(out), *extra])
    return code, json.loads(out.read_text()) if code == 0 else None, printed.getvalue()


def _machine_yaml(layout, path: Path) -> Path:
    """The VMC the survey was taken on, described by its user: the tables move against
    the command (sign -1), the tool at the layout's height, no offsets known."""
    axes = {a: {"stroke": [float(v) for v in layout.travel[a]], "offset": [0.0, 0.0, 0.0],
                "sign": -1 if a in layout.work else 1} for a in "XYZ"}
    chain = "[" + " ".join(["w", *reversed(layout.work), "b", *layout.tool, "t"]) + "]"
    path.write_text(yaml.safe_dump({"name": "vmc_500", "chain": chain,
                                    "tool": [0.0, 0.0, layout.tool_z_m],
                                    "workpiece": [0.0, 0.0, 0.0], "axes": axes}))
    return path


def test_one_survey_through_work_axes_and_through_a_machine_yaml_names_the_same(tmp_path):
    csv, column_map, fair = single_effect_trial("vmc_500", "angular_table", 31, tmp_path)
    code, by_map, printed = _check(csv, column_map)
    assert code == 0, printed
    machine = _machine_yaml(LAYOUTS["vmc_500"], tmp_path / "vmc_500.yaml")
    described = yaml.safe_load(column_map.read_text())
    described.pop("work_axes")
    described.pop("tool_offset")
    described["machine"] = machine.name          # beside the map: resolved there
    with_machine = tmp_path / "map_machine.yaml"
    with_machine.write_text(yaml.safe_dump(described))
    code, by_yaml, printed = _check(csv, with_machine)
    assert code == 0, printed
    named = lambda result: [n["name"].replace("angular_arm:", "angular:")  # noqa: E731
                            for n in result["named"]]
    assert named(by_map) == named(by_yaml) and named(by_map)[0] in fair, (named(by_map),
                                                                          named(by_yaml), fair)
    assert by_yaml["machine"] == "vmc_500"
    # --machine naming another machine than the map's is a contradiction, said in one line.
    code, _, printed = _check(csv, with_machine, "--machine", "vmc")
    assert code == 2 and "contradicts the column map's machine" in printed


def test_rotary_columns_without_a_rotary_machine_are_refused_in_one_line(tmp_path):
    csv, column_map, _ = single_effect_trial("vmc_500", None, 32, tmp_path)
    text = csv.read_text().splitlines()
    csv.write_text("\n".join([text[0] + ",A_deg"] + [row + f",{(k * 7) % 90}"
                                                     for k, row in enumerate(text[1:])]) + "\n")
    mapping = yaml.safe_load(column_map.read_text())
    mapping["positions"]["A"] = {"column": "A_deg", "unit": "deg"}
    column_map.write_text(yaml.safe_dump(mapping))
    code, _, printed = _check(csv, column_map)
    lines = [line for line in printed.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1, printed
    assert "rotary position columns (A)" in printed and "describe the machine" in printed


@pytest.mark.parametrize("key, value, words", [
    ("setup_pose", {"C": 30}, "give the angle with its unit"),
    ("setup_pose", {"Q": {"value": 1, "unit": "deg"}}, "names rotary axes"),
    ("target_point", {"value": [1, 2], "unit": "mm"}, "three numbers"),
    ("target_point", {"value": [1, 2, 3]}, "expected {value: [x, y, z], unit: mm}"),
    ("target_point", {"columns": {"x": "a", "y": "b"}, "unit": "mm"}, "name the x, y and z"),
    ("machine", 3, "machine YAML's path or a bundled name"),
])
def test_what_the_map_says_of_the_set_up_is_read_with_its_unit_or_refused(
        tmp_path, key, value, words):
    csv, column_map, _ = single_effect_trial("vmc_500", None, 33, tmp_path)
    mapping = yaml.safe_load(column_map.read_text())
    mapping[key] = value
    column_map.write_text(yaml.safe_dump(mapping))
    code, _, printed = _check(csv, column_map)
    assert code == 2 and words in printed, printed


def test_a_trunnion_survey_set_up_at_a_rotary_pose_names_the_c_centre(tmp_path):
    """The issue's first case: an R-test survey of a trunnion VMC described in a machine
    YAML, the sphere set up at A = C = 0 and again at C = 45 deg: a 20 um offset of the C
    line (EX0C) is named, with its value, and the set-up pose is said."""
    from studies.convention_surveys import generate

    with contextlib.redirect_stdout(io.StringIO()):
        generate(str(tmp_path / "panel"), 4, 50, topology="trunnion_AC", instrument="r_test")
    index = json.loads((tmp_path / "panel" / "index.json").read_text())
    found = 0
    for entry in index["trials"]:
        folder = tmp_path / "panel" / entry["folder"]
        truth = json.loads((folder / "truth.json").read_text())
        code, result, printed = _check(folder / "survey.csv", folder / "map.yaml")
        assert code == 0, printed
        assert "set-up pose A = " in result["machine_note"]
        for effect in truth["effects"]:
            if effect["kind"] != "location_offset" or not effect["identifiable"]:
                continue
            carried = [n["parameters"].get(effect["iso_name"]) for n in result["named"]
                       if n["effect"] == "rotary_location"]
            value = next((v for v in carried if v is not None), None)
            assert value is not None, (effect, printed)
            assert abs(value - effect["value_si"]) <= 0.3 * abs(effect["value_si"]), \
                (effect["iso_name"], value, effect["value_si"])
            found += 1
    assert found >= 1      # not vacuous: the panel held a line offset


def test_the_tilts_of_one_stack_are_judged_with_one_tool():
    from mt_accuracy_ros.commands.check import one_tool_for_the_stack

    agree = one_tool_for_the_stack([("EAX", 0.101, 0.002), ("EBY", 0.098, 0.003)])
    # weighted by 1/sigma^2
    assert len(agree) == 1 and "agree on one tool" in agree[0] and "at 100.1 mm" in agree[0]
    differ = one_tool_for_the_stack([("EAX", 0.101, 0.002), ("EBY", -0.396, 0.003)])
    assert len(differ) == 1 and differ[0].startswith("warning: the tilts of one stack")
    assert one_tool_for_the_stack([("EAX", 0.1, 0.002)]) == []


def test_a_machine_files_impossible_set_up_the_map_replaces_is_said_not_refused(tmp_path):
    """The machine file says A was set up at 90 deg, outside A's stroke; the survey's map
    says where its sphere was located (A = C = 0). The check reads the survey at the map's
    set-up and says why the file's is not used, instead of refusing the survey."""
    from studies.convention_surveys import generate

    with contextlib.redirect_stdout(io.StringIO()):
        generate(str(tmp_path / "panel"), 1, 50, topology="trunnion_AC", instrument="r_test")
    folder = tmp_path / "panel" / json.loads(
        (tmp_path / "panel" / "index.json").read_text())["trials"][0]["folder"]
    described = yaml.safe_load((folder / "machine.yaml").read_text())
    low, high = described["axes"]["A"]["stroke"]["value"] if isinstance(
        described["axes"]["A"]["stroke"], dict) else [v * 57.29577951308232 for v in
                                                       described["axes"]["A"]["stroke"]]
    outside = high + 60.0
    described["setup_pose"] = {"A": {"value": outside, "unit": "deg"},
                               "C": {"value": 0.0, "unit": "deg"}}
    (folder / "machine.yaml").write_text(yaml.safe_dump(described))
    column_map = yaml.safe_load((folder / "map.yaml").read_text())
    assert "setup_pose" in column_map and "A" in column_map["setup_pose"]
    code, result, printed = _check(folder / "survey.csv", folder / "map.yaml")
    assert code == 0, printed
    assert f"{outside:g} deg is outside the stroke" in result["machine_note"]
    assert "not used - the column map's setup_pose gives A's set-up" in result["machine_note"]
    # Without the map's set-up the file's impossible one is refused, in one line.
    del column_map["setup_pose"]
    (folder / "bare.yaml").write_text(yaml.safe_dump(column_map))
    code, _, printed = _check(folder / "survey.csv", folder / "bare.yaml")
    assert code == 2 and "outside the stroke" in printed
