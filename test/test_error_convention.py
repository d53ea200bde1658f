"""A survey's error columns in another convention (the column map's ``error_convention``):
the work relative to the tool, a correction instead of a deviation, components along a
frame that turns with the table. The same readings written in each convention give the
same answer as in the package's own; the check says which convention it took."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import InputDataError, ParameterError
from mt_accuracy_ros.io.column_map import ErrorConvention, column_map_from_dict

# A C table on the bed, the three linear axes on the tool side: the workpiece frame is
# the C table's, turned by +C about z from the bed's.
MACHINE_YAML = """\
name: c_table
chain: '[w C b X Y Z t]'
tool: [0.0, 0.0, -0.1]
workpiece: [0.0, 0.0, 0.0]
axes:
  C: {stroke: {value: [-360, 360], unit: deg}, sign: 1, offset: [0, 0, 0]}
  X: {stroke: [-0.3, 0.3], offset: [0, 0, 0]}
  Y: {stroke: [-0.3, 0.3], offset: [0, 0, 0]}
  Z: {stroke: [-0.3, 0.3], offset: [0, 0, 0]}
"""
SPHERE_MM = (60.0, 0.0, 20.0)
OFFSET_M = (20e-6, -8e-6, 0.0)          # the C line's offset (EX0C, EY0C)


def _turn_z(angle):
    """(N, 3, 3) rotations by ``angle`` (N,) [rad] about z."""
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros((angle.size, 3, 3))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = c, -s, s, c
    out[:, 2, 2] = 1.0
    return out


def _survey(n=240, seed=4):
    """Poses and the tool-relative-to-work error of a sphere on a C table whose line is
    offset by d: the sphere, located at C = 0, turns about the real line, so it sits
    (I - R_C) d away from where the nominal turn puts it (ISO 230-7) - and the tool,
    relative to it, by the opposite."""
    rng = np.random.default_rng(seed)
    c_turn = np.radians(rng.choice(np.arange(0, 360, 15), n))
    xyz = rng.uniform(-0.1, 0.1, (n, 3))
    turn = _turn_z(c_turn)
    moved = np.asarray(OFFSET_M) - np.einsum("nij,j->ni", turn, OFFSET_M)
    tool_rel_work = -moved + rng.normal(0.0, 0.2e-6, (n, 3))
    return c_turn, xyz, tool_rel_work, turn


def _write(folder, name, c_turn, xyz, errors, convention):
    folder.mkdir(exist_ok=True)
    (folder / "machine.yaml").write_text(MACHINE_YAML)
    rows = ["t_s,X_mm,Y_mm,Z_mm,C_deg,ex_um,ey_um,ez_um"]
    for i in range(c_turn.size):
        rows.append(",".join(f"{v:.12g}" for v in (
            i, *(xyz[i] * 1e3), np.degrees(c_turn[i]), *(errors[i] * 1e6))))
    (folder / f"{name}.csv").write_text("\n".join(rows) + "\n")
    lines = ["machine: machine.yaml", "time: {column: t_s, unit: s}", "positions:"]
    lines += [f"  {a}: {{column: {a}_mm, unit: mm}}" for a in "XYZ"]
    lines += ["  C: {column: C_deg, unit: deg}", "errors:"]
    lines += [f"  {c}: {{column: e{c}_um, unit: um}}" for c in "xyz"]
    lines += [f"target_point: {{value: {list(SPHERE_MM)}, unit: mm}}",
              "uncertainty: {value: 0.5, unit: um}"]
    if convention:
        lines.append(f"error_convention: {convention}")
    (folder / f"{name}.yaml").write_text("\n".join(lines) + "\n")
    return folder / f"{name}.csv", folder / f"{name}.yaml"


def _check(csv, mapping):
    import yaml

    from mt_accuracy_ros.commands.check import check_mapped_csv

    column_map = column_map_from_dict(yaml.safe_load(mapping.read_text()), str(mapping))
    return check_mapped_csv(csv, column_map, None, [], 3, 0.05)


def _named(result):
    return {e["name"]: dict(e["parameters"]) for e in result.named}


@pytest.mark.parametrize("convention, written", [
    ("{of: work}", lambda e, turn: -e),
    ("{as: correction}", lambda e, turn: -e),
    ("{of: work, as: correction}", lambda e, turn: e),
    # Components along the table's axes: e_table = R_C^T e_bed.
    ("{frame: work}", lambda e, turn: np.einsum("nji,nj->ni", turn, e)),
    ("{of: work, frame: work}", lambda e, turn: -np.einsum("nji,nj->ni", turn, e)),
])
def test_the_same_readings_in_another_convention_give_the_same_answer(tmp_path, convention,
                                                                        written):
    c_turn, xyz, errors, turn = _survey()
    own = _check(*_write(tmp_path, "own", c_turn, xyz, errors, None))
    other = _check(*_write(tmp_path, "other", c_turn, xyz, written(errors, turn), convention))
    assert "rotary_location:C" in _named(own), _named(own)
    location = _named(own)["rotary_location:C"]
    assert abs(abs(location["EX0C"]) - 20e-6) < 1.5e-6
    assert abs(abs(location["EY0C"]) - 8e-6) < 1.5e-6
    assert _named(other).keys() == _named(own).keys()
    for name, parameters in _named(own).items():
        for key, value in parameters.items():
            assert _named(other)[name][key] == pytest.approx(value, rel=1e-6, abs=1e-12)
    assert "the column map's error_convention" in other.source.machine_note
    assert "errors read as the tool relative to the work, actual minus nominal, along the " \
           "machine's axes (the default" in own.source.machine_note


def test_a_wrong_sign_is_not_the_same_answer(tmp_path):
    """The convention matters: the readings negated and read as the package's own give
    the offset with the other sign (what a survey in another convention would have given
    without error_convention)."""
    c_turn, xyz, errors, _ = _survey()
    own = _named(_check(*_write(tmp_path, "own", c_turn, xyz, errors, None)))
    flipped = _named(_check(*_write(tmp_path, "flip", c_turn, xyz, -errors, None)))
    assert np.sign(flipped["rotary_location:C"]["EX0C"]) == \
        -np.sign(own["rotary_location:C"]["EX0C"])


def test_a_turning_frame_needs_every_component(tmp_path):
    c_turn, xyz, errors, _ = _survey(n=60)
    csv, mapping = _write(tmp_path, "s", c_turn, xyz, errors, "{frame: work}")
    text = mapping.read_text().replace("  z: {column: ez_um, unit: um}\n", "")
    mapping.write_text(text)
    with pytest.raises(InputDataError, match="frame: work needs all three error components"):
        _check(csv, mapping)


@pytest.mark.parametrize("spec, match", [
    ({"of": "sphere"}, "of: 'sphere' is not one of tool, work"),
    ({"frame": "table"}, "frame: 'table' is not one of machine, work, tool"),
    ({"sign": -1}, "unknown key"),
    ("correction", "expected"),
])
def test_an_unknown_convention_is_refused(spec, match):
    with pytest.raises(ParameterError, match=match):
        column_map_from_dict({"error_convention": spec})


def test_the_convention_signs():
    assert ErrorConvention().sign == 1.0
    assert ErrorConvention(of="work").sign == -1.0
    assert ErrorConvention(sense="correction").sign == -1.0
    assert ErrorConvention(of="work", sense="correction").sign == 1.0


HEAD_YAML = """\
name: b_head
chain: '[w X Y b Z B t]'
tool: [0.0, 0.0, -0.1]
workpiece: [0.0, 0.0, 0.0]
axes:
  X: {stroke: [-0.3, 0.3], offset: [0, 0, 0]}
  Y: {stroke: [-0.3, 0.3], offset: [0, 0, 0]}
  Z: {stroke: [-0.3, 0.3], offset: [0, 0, 0]}
  B: {stroke: {value: [-90, 90], unit: deg}, sign: 1, offset: [0, 0, 0]}
"""


def _turn_y(angle):
    """(N, 3, 3) rotations by ``angle`` (N,) [rad] about y."""
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros((angle.size, 3, 3))
    out[:, 0, 0], out[:, 0, 2], out[:, 2, 0], out[:, 2, 2] = c, s, -s, c
    out[:, 1, 1] = 1.0
    return out


def _machine(tmp_path, text, setup=None):
    from mt_accuracy_ros.core.kinematics.machine import load_machine, with_setup_pose

    path = tmp_path / "machine.yaml"
    path.write_text(text)
    machine = load_machine(path)
    return with_setup_pose(machine, setup, "the test's set-up") if setup else machine


def _convert(machine, positions, errors, directions, **words):
    from mt_accuracy_ros.commands.check import in_package_convention

    mask = np.ones(errors.shape, dtype=bool)
    convention = ErrorConvention(**words, stated=True)
    return in_package_convention(errors, mask, directions, convention, machine, positions)


@pytest.mark.parametrize("words, expected_sign", [({"of": "work"}, -1.0),
                                                  ({"of": "work", "sense": "correction"}, 1.0)])
def test_errors_and_directions_along_a_turning_table_are_turned_to_the_machine(
        tmp_path, words, expected_sign):
    """frame: work on a C table: machine axes = s Rz(C) @ the table's, for the errors and
    the tool direction's change alike (closed form)."""
    rng = np.random.default_rng(2)
    n = 50
    c_turn = rng.uniform(-np.pi, np.pi, n)
    positions = {"C": c_turn, **{a: rng.uniform(-0.1, 0.1, n) for a in "XYZ"}}
    errors, change = rng.normal(0, 1e-5, (n, 3)), rng.normal(0, 1e-5, (n, 3))
    change[:, 2] = 0.0
    directions = {c: change[:, k] for k, c in enumerate("xyz")}
    machine = _machine(tmp_path, MACHINE_YAML)
    out, turned, note = _convert(machine, positions, errors, directions, frame="work",
                                 **words)
    turn = _turn_z(c_turn)
    np.testing.assert_allclose(out, expected_sign * np.einsum("nij,nj->ni", turn, errors),
                               rtol=0, atol=1e-18)
    expected = expected_sign * np.einsum("nij,nj->ni", turn, change)
    np.testing.assert_allclose(np.column_stack([turned[c] for c in "xyz"]), expected,
                               rtol=0, atol=1e-18)
    assert "workpiece frame's axes (the machine's at every rotary axis at 0" in note


def test_errors_along_a_turning_head_are_turned_with_the_spindle(tmp_path):
    """frame: tool on a B head: machine axes = Ry(B) @ the spindle frame's; frame: work
    there is the machine's own (no rotary axis carries the work)."""
    rng = np.random.default_rng(3)
    n = 40
    b_turn = rng.uniform(-1.2, 1.2, n)
    positions = {"B": b_turn, **{a: rng.uniform(-0.1, 0.1, n) for a in "XYZ"}}
    errors = rng.normal(0, 1e-5, (n, 3))
    machine = _machine(tmp_path, HEAD_YAML)
    out, _, note = _convert(machine, positions, errors, {}, frame="tool")
    np.testing.assert_allclose(out, np.einsum("nij,nj->ni", _turn_y(b_turn), errors),
                               rtol=0, atol=1e-18)
    assert "spindle frame's axes" in note
    same, _, _ = _convert(machine, positions, errors, {}, frame="work")
    np.testing.assert_allclose(same, errors, rtol=0, atol=1e-18)


def test_a_frame_aligned_at_the_set_up_pose_turns_from_there(tmp_path):
    """aligned_at: setup: the table's axes are the machine's at the set-up pose C = 45 deg,
    so machine axes = Rz(C - 45 deg) @ the table's."""
    rng = np.random.default_rng(4)
    n = 30
    c_turn = rng.uniform(-np.pi, np.pi, n)
    positions = {"C": c_turn, **{a: np.zeros(n) for a in "XYZ"}}
    errors = rng.normal(0, 1e-5, (n, 3))
    machine = _machine(tmp_path, MACHINE_YAML, {"C": np.radians(45.0)})
    out, _, note = _convert(machine, positions, errors, {}, frame="work", aligned_at="setup")
    expected = np.einsum("nij,nj->ni", _turn_z(c_turn - np.radians(45.0)), errors)
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-18)
    assert "the machine's at the set-up pose" in note


def test_a_turning_frame_needs_every_direction_component(tmp_path):
    n = 10
    positions = {"C": np.zeros(n), **{a: np.zeros(n) for a in "XYZ"}}
    machine = _machine(tmp_path, MACHINE_YAML)
    with pytest.raises(InputDataError, match="three direction_errors components .missing z"):
        _convert(machine, positions, np.zeros((n, 3)), {"x": np.zeros(n), "y": np.zeros(n)},
                 frame="work")


def test_the_check_and_the_fleet_say_the_convention_in_their_json(tmp_path):
    from mt_accuracy_ros.commands.fleet import _compact

    c_turn, xyz, errors, _ = _survey(n=80)
    result = _check(*_write(tmp_path, "s", c_turn, xyz, -errors, "{of: work}"))
    said = {"of": "work", "as": "deviation", "frame": "machine", "aligned_at": "zero",
            "stated": True}
    assert result.to_json()["error_convention"] == said
    assert _compact(result)["error_convention"] == said
    default = _check(*_write(tmp_path, "d", c_turn, xyz, errors, None))
    assert default.to_json()["error_convention"]["stated"] is False
