"""A table tilt with a constant part: one rotation of the carriage (ISO 230-1).

A yaw eps(y) = eps0 + eps1 u(y) of the Y carriage turns everything it carries about the
carriage's pivot; its constant part eps0 is the squareness of the XY plane. The angular
family offers the constant part (Legendre P0) on a carriage that carries no rotary axis,
so the yaw is named once, not as an angular error plus a pair of squareness slopes.
"""
from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from mt_accuracy_ros.cli import main
from mt_accuracy_ros.core.effects import Context, family_named
from mt_accuracy_ros.core.effects.geometric import carries_rotary
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.kinematics.chain import KinematicModel
from mt_accuracy_ros.core.kinematics.machine import load_machine, machine_from_dict
from studies import convention_surveys as cs

#: A VMC whose tables move against the command; the tool tip off the Y pivot's line in
#: x and y (an in-plane arm) [m].
VMC = {"name": "vmc_yaw", "chain": "[w X Y b Z t]", "tool": [0.0, 0.0, -0.1],
       "workpiece": [0.0, 0.0, 0.0],
       "axes": {"X": {"stroke": [-0.3, 0.3], "sign": -1, "offset": [0.0, 0.0, 0.0]},
                "Y": {"stroke": [-0.2, 0.2], "sign": -1, "offset": [0.0, 0.0, 0.0]},
                "Z": {"stroke": [-0.5, -0.3], "offset": [0.07, 0.03, 0.6]}}}


def test_a_table_yaw_with_a_constant_part_moves_the_machining_point_as_a_turn_about_its_pivot():
    """e = -eps(y) z x (tip - pivot): the material at the tool tip turns with the Y carriage
    about the carriage's origin (at y_bed = -y: the table moves against the command); the
    error is the tool relative to the work. Hand formula: e_x = eps (y_tip + y),
    e_y = -eps x_tip, e_z = 0."""
    machine = machine_from_dict(VMC)
    rng = np.random.default_rng(50)
    n = 30
    q = {a: rng.uniform(*machine.axes[a].stroke, n) for a in machine.axis_order}
    ctx = Context(machine, Variables(q), KinematicModel(machine))
    family = family_named("angular")
    setting = {"order": 1, "constant": True}
    assert setting in family.settings(ctx, "ECY")
    assert family.parameter_names("ECY", setting) == ["P1", "P0"]
    eps0, eps1 = 40e-6, 25e-6                          # rad: P0 and P1
    predicted = family.design(ctx, "ECY", setting) @ np.array([eps1, eps0])
    u = q["Y"] / 0.2                                   # Legendre's domain over the stroke
    eps = eps0 + eps1 * u                              # rad
    x_tip, y_tip = 0.07, 0.03                          # m: Z's in-plane offset
    hand = np.column_stack([eps * (y_tip + q["Y"]), -eps * x_tip, np.zeros(n)])
    np.testing.assert_allclose(predicted, hand, rtol=0, atol=1e-12)
    # The error motion a CNC table holds is the yaw itself, constant part included.
    np.testing.assert_allclose(family.motion_error(machine, "ECY", setting, [eps1, eps0], q["Y"]),
                               eps, rtol=1e-12)


def test_the_constant_part_is_offered_only_on_a_table_that_carries_no_rotary_axis():
    """On a trunnion the constant turn of a carriage is the tilt of the rotary lines it
    carries (rotary_location) and its carried axes' squareness: not a second name. On
    the tool side the squareness family holds a constant turn."""
    trunnion = load_machine("khan_chen_rpppr")
    vmc = machine_from_dict(VMC)
    assert not carries_rotary(vmc, "Y") and not carries_rotary(vmc, "Z")
    q = {a: np.linspace(*vmc.axes[a].stroke, 8) for a in vmc.axis_order}
    settings = family_named("angular").settings(Context(vmc, Variables(q), KinematicModel(vmc)),
                                                "EAZ")
    assert not any(s.get("constant") for s in settings)          # Z carries the tool
    carrying = [a for a in trunnion.axis_order
                if not trunnion.axes[a].is_rotary and carries_rotary(trunnion, a)]
    assert carrying
    q = {a: np.linspace(*trunnion.axes[a].stroke, 8) for a in trunnion.axis_order}
    ctx = Context(trunnion, Variables(q), KinematicModel(trunnion))
    family = family_named("angular")
    for axis in carrying:      # (read by a located target, see test_located_tilt)
        assert not any(s.get("constant") and not s.get("located")
                       for s in family.settings(ctx, f"EC{axis}"))


def _yaw_trial(folder: Path, instrument: str) -> dict:
    """A VMC survey from the independent generator with one hidden yaw of the Y saddle,
    40 urad constant plus 50 urad over the half stroke; its map gives ``work_axes``
    and a tool offset, and a second map gives the generator's machine YAML instead."""
    for seed in range(200):
        rng = np.random.default_rng(seed)
        trial = cs.draw_trial(rng, "yaw", topology="vmc_3axis", instrument=instrument,
                              null=True)
        if not trial["machine_given"] and trial["tool_offset_given"]:
            break
    low, high = trial["machine"]["work"][0]["stroke"]
    yaw = {"iso_name": "ECY", "kind": "table_tilt", "axis": "Y", "side": "work",
           "value_si": [40e-6, 50e-6 / max(abs(low), abs(high)), 0.0],
           "pivot_m": [0.0, 0.0, 0.0], "constant_part_si": 40e-6, "identifiable": True}
    trial["effects"] = [yaw]
    position, _ = cs.located_errors(trial["machine"], cs.errs_from_effects([yaw]), trial["rows"])
    trial["errors_m"] = position + rng.normal(0.0, trial["sigma_m"], position.shape)
    cs.write_trial(trial, folder, rng)
    described = yaml.safe_load((folder / "map.yaml").read_text())
    described.pop("work_axes")
    described.pop("tool_offset", None)
    described["machine"] = "machine.yaml"
    (folder / "map_machine.yaml").write_text(yaml.safe_dump(described))
    return trial


def _named(folder: Path, column_map: str) -> list[dict]:
    out = folder / f"{column_map}.json"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(printed):
        code = main(["check", str(folder / "survey.csv"), "--columns", str(folder / column_map),
                     "--auto", "3", "--json", str(out)])
    assert code == 0, printed.getvalue()
    return json.loads(out.read_text())["named"]


@pytest.mark.parametrize("instrument", ["laser_tracker", "machining_point"])
def test_a_constant_yaw_is_one_rotation_through_work_axes_and_through_a_machine_yaml(
        tmp_path, instrument):
    """The same survey, through ``work_axes`` and through the machine YAML, names the yaw
    alone, its constant part the 40 urad the generator turned the saddle by (before, the
    map named the yaw plus a squareness slope, the YAML a 7th-order straightness)."""
    _yaw_trial(tmp_path, instrument)
    by_map, by_yaml = _named(tmp_path, "map.yaml"), _named(tmp_path, "map_machine.yaml")
    assert [n["name"] for n in by_map] == [n["name"] for n in by_yaml] == ["angular:ECY"], \
        (by_map, by_yaml)
    for named in (by_map[0], by_yaml[0]):
        assert named["parameters"]["P0"] == pytest.approx(40e-6, rel=0.1)
