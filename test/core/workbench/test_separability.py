"""What the surveyed poses cannot part is said, with the other explanation's own values.

The readings come from ``studies.convention_surveys`` (rigid bodies written from the
physics alone: each rotary body turns about its actual line, the sphere and a head's tool
located at the set-up by a translation), on machines described here to both codes.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects import family_named
from mt_accuracy_ros.core.effects.base import Context, target_groups
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.kinematics.machine import machine_from_dict, with_setup_pose
from mt_accuracy_ros.core.workbench.diagnosis import Observations, diagnose
from studies import convention_surveys as cs

SPHERE = np.array([0.06, -0.04, 0.05])      # the R-test's sphere, workpiece frame [m]
NOISE = 0.3e-6                              # the instrument's noise, k = 1 [m]


def _machines(work, tool, tool_vec, setup_deg, strokes_deg):
    """(the generator's machine, the package's description) of one geometry."""
    axes = {}
    for ax in work + tool:
        if ax["rotary"]:
            low, high = strokes_deg[ax["name"]]
            ax["stroke"] = (math.radians(low), math.radians(high))
            axes[ax["name"]] = {"stroke": {"value": [low, high], "unit": "deg"}}
        else:
            axes[ax["name"]] = {"stroke": [-0.6, 0.9]}
        axes[ax["name"]].update(offset=ax["offset"].tolist(), sign=ax["sign"])
    setup = {n: math.radians(v) for n, v in setup_deg.items()}
    generator = {"topology": "given", "work": work, "tool": tool,
                 "tool_vec": np.asarray(tool_vec, float), "work_vec": np.zeros(3),
                 "setup": setup}
    chain = "[w " + " ".join([a["name"] for a in work][::-1] + ["b"] +
                             [a["name"] for a in tool]) + " t]"
    described = machine_from_dict({"name": "given", "chain": chain, "tool": list(tool_vec),
                                   "workpiece": [0, 0, 0], "axes": axes})
    return generator, with_setup_pose(described, setup)


def _survey(generator, described, poses, effects, seed=0):
    """Observations of one sphere followed with RTCP over ``poses`` (rotary commands), the
    first at the set-up pose, where the sphere was located."""
    poses = [dict(generator["setup"])] + list(poses)
    rows = {"q": [cs.solve_linear(generator, p, SPHERE) for p in poses],
            "target": np.tile(SPHERE, (len(poses), 1)), "group": [0] * len(poses),
            "setup": {0: 0}, "tool_setup": 0}
    errors, _ = cs.located_errors(generator, cs.errs_from_effects(effects), rows)
    n = len(poses)
    positions = {a: np.array([q[a] for q in rows["q"]]) for a in described.axis_order}
    measured = errors + np.random.default_rng(seed).normal(0.0, NOISE, (n, 3))
    return Observations(positions, measured, np.ones((n, 3), bool), np.arange(n, dtype=float),
                        {}, {}, 2 * NOISE, work_point=SPHERE)


def _effect(name, axis, value, kind="location_offset"):
    return {"iso_name": name, "kind": kind, "axis": axis, "value_si": value}


def _trunnion_bc(setup_deg):
    work = [cs._ax("Y", 1, [0, 0, 0.1]), cs._ax("X", -1, [0, 0, 0.25]),
            cs._ax("B", 1, [0.01, 0, -0.08]), cs._ax("C", 1, [0, 0, 0])]
    return _machines(work, [cs._ax("Z", 1, [0, 0, 0.6])], [0, 0, -0.14], setup_deg,
                     {"B": (-120, 120), "C": (-180, 180)})


def test_a_line_offset_on_a_sweep_of_its_axis_is_said_inseparable_from_the_set_up():
    """A sphere located at B = -90 deg, B swept alone: B's line offset and an error the
    set-up located into the sphere turn with B alike - named once, the other said."""
    generator, described = _trunnion_bc({"B": -90, "C": 45})
    poses = [{"B": math.radians(b), "C": math.radians(45)} for b in np.arange(-90, 91, 5)]
    poses = poses * 6
    obs = _survey(generator, described, poses, [_effect("EX0B", "B", 15e-6)])
    diagnosis = diagnose(ErrorModel(described), obs)
    named = diagnosis.selected[0]
    assert named.name == "rotary_location:B", diagnosis.text()
    assert abs(named.parameters["EX0B"] - 15e-6) < 1e-6
    alike = {a["name"]: a for a in named.inseparable}
    assert "setup_location:work" in alike, named.inseparable
    # Its own values: a vector located at the set-up that turns with the work.
    located = alike["setup_location:work"]["parameters"]
    assert math.hypot(located["v_x"], located["v_z"]) == pytest.approx(15e-6, rel=0.05)
    assert "cannot part rotary_location:B from setup_location:work" in named.explanation
    assert "turns with the rotary axes as their lines' offsets do" in named.explanation


def test_on_a_grid_a_c_centre_is_not_said_inseparable_from_the_set_up():
    """With B and C both turning, a C centre offset turns with C alone, a located error
    with both: the readings part them and nothing is said."""
    generator, described = _trunnion_bc({"B": 0, "C": 0})
    poses = [{"B": math.radians(b), "C": math.radians(c)}
             for b in np.arange(-90, 91, 15) for c in np.arange(-180, 180, 30)]
    obs = _survey(generator, described, poses, [_effect("EX0C", "C", -12e-6)])
    diagnosis = diagnose(ErrorModel(described), obs)
    named = diagnosis.selected[0]
    assert named.name == "rotary_location:C", diagnosis.text()
    assert abs(named.parameters["EX0C"] + 12e-6) < 1e-6
    assert named.inseparable == []


def test_a_tool_side_c_with_its_tip_on_the_axis_folds_the_tilt_into_the_offset():
    """A swivel head's C swept alone, the tool tip on C's line: a tilt of the line moves
    the tip as an offset 0.42 m times the tilt would - the fit keeps the offset and says
    what it stands for."""
    work = [cs._ax("Y", -1, [0, 0, 0.1]), cs._ax("X", 1, [0, 0, 0.05])]
    tool = [cs._ax("Z", 1, [0, 0, 0.6]), cs._ax("C", 1, [0, 0, -0.2]),
            cs._ax("B", 1, [0, 0, -0.127])]
    generator, described = _machines(work, tool, [0, 0, -0.093], {"C": 0, "B": 0},
                                     {"C": (-180, 180), "B": (-110, 110)})
    poses = [{"C": math.radians(c), "B": 0.0} for c in np.arange(-180, 180, 10)] * 8
    obs = _survey(generator, described, poses, [_effect("EB0C", "C", -50e-6,
                                                         "location_tilt")])
    ctx = Context(described, Variables(obs.positions), work_point=SPHERE)
    family = family_named("rotary_location")
    setting = family.settings(ctx, "C")[0]
    assert family.parameter_names("C", setting) == ["EX0C", "EY0C"]
    lever = 0.2 + 0.127 + 0.093                       # the tilt's arm down to the tip [m]
    folds = dict(part.split("=") for part in setting["inseparable"].split(";"))
    assert folds["EB0C"].split("*")[0] == "EX0C"
    assert abs(abs(float(folds["EB0C"].split("*")[1])) - lever) < 1e-9
    assert "cannot part" in family.explanation("C", setting)
    diagnosis = diagnose(ErrorModel(described), obs)
    named = diagnosis.selected[0]
    assert named.name == "rotary_location:C", diagnosis.text()
    ratio = float(folds["EB0C"].split("*")[1])
    # EX0C stands for EX0C + ratio x EB0C: here the tilt's share alone.
    assert named.parameters["EX0C"] == pytest.approx(ratio * -50e-6, rel=0.03)
    assert "EB0C" not in named.parameters


def test_a_head_lines_tilt_and_a_squareness_are_said_alike_on_one_sphere():
    """A swivel head's B line tilted about x moves a single sphere's readings in y by the
    tilt times the tool's height under B, which the RTCP turns into Z travel: the Y-Z pair
    out of square reads the same. Either is named, the other said, with its own value."""
    work = [cs._ax("Y", -1, [0, 0, 0.054]), cs._ax("X", 1, [0, 0, 0.133]),
            cs._ax("C", -1, [0, 0, 0])]
    tool = [cs._ax("Z", -1, [0, 0, 0.752]), cs._ax("B", -1, [0, 0, -0.165])]
    generator, described = _machines(work, tool, [0, 0, -0.121], {"C": 0, "B": 0},
                                     {"C": (-360, 360), "B": (-110, 30)})
    poses = [{"C": math.radians(c), "B": math.radians(b)}
             for b in np.arange(-110, 31, 10) for c in np.arange(0, 360, 30)]
    obs = _survey(generator, described, poses, [_effect("EA0B", "B", 11e-6,
                                                         "location_tilt")])
    diagnosis = diagnose(ErrorModel(described), obs)
    named = diagnosis.selected[0]
    said = {a["name"]: a["parameters"] for a in named.inseparable}
    if named.name == "squareness:EYZ":
        assert abs(said["rotary_location:B"]["EA0B"] - 11e-6) < 1e-6, said
    else:
        assert named.name.startswith("rotary_location") and "squareness:EYZ" in said, \
            diagnosis.text()
        assert abs(named.parameters["EA0B"] - 11e-6) < 1e-6
    assert "move the target along the same circle" in named.explanation


def _mixed_table_head():
    """A C table under a swivel head's B on the Z ram: the tip 0.286 m under B's line."""
    work = [cs._ax("Y", -1, [0, 0, 0.054]), cs._ax("X", 1, [0, 0, 0.133]),
            cs._ax("C", -1, [0, 0, 0])]
    tool = [cs._ax("Z", -1, [0, 0, 0.752]), cs._ax("B", -1, [0, 0, -0.165])]
    return _machines(work, tool, [0, 0, -0.121], {"C": 0, "B": 0},
                     {"C": (-360, 360), "B": (-110, 30)})


def test_a_head_lines_tilt_beside_its_offset_is_said_as_the_y_z_squareness():
    """The Y-Z pair out of square (the generator's EA0Z: Z's slide tilted toward Y) beside
    an offset of the head's B line. Keeping the tip on the sphere, the RTCP moves Z by
    L (1 - cos b) (L the tip's depth under B), so the squareness a moves the sphere's
    reading along y by a L (1 - cos b): what B's line tilted about x by -a does (ISO 230-7).
    One line explains both; with its offset beside the tilt no squareness reproduces the
    whole line, so its tilt alone is judged, and the output says the squareness it may be,
    with its own value."""
    generator, described = _mixed_table_head()
    poses = [{"C": math.radians(c), "B": math.radians(b)}
             for b in np.arange(-110, 31, 10) for c in np.arange(0, 360, 30)]
    square, offset = -40e-6, 9e-6
    rows = {"q": [cs.solve_linear(generator, p, SPHERE)
                  for p in [dict(generator["setup"])] + poses],
            "target": np.tile(SPHERE, (len(poses) + 1, 1)), "group": [0] * (len(poses) + 1),
            "setup": {0: 0}, "tool_setup": 0}
    read = {name: cs.located_errors(generator, cs.errs_from_effects([effect]), rows)[0]
            for name, effect in [("EA0Z", _effect("EA0Z", "Z", square, "squareness")),
                                 ("EA0B", _effect("EA0B", "B", -square, "location_tilt"))]}
    z, b = (np.array([q[a] for q in rows["q"]]) for a in "ZB")
    depth = 0.165 + 0.121
    assert np.allclose(z - z[0], depth * (1 - np.cos(b)), rtol=0, atol=1e-12)
    assert np.allclose(read["EA0Z"][:, 1], square * depth * (1 - np.cos(b)), rtol=0, atol=1e-13)
    assert np.abs(read["EA0Z"] - read["EA0B"]).max() < 2e-9      # second order in the angle
    obs = _survey(generator, described, poses,
                  [_effect("EA0Z", "Z", square, "squareness"), _effect("EX0B", "B", offset)])
    diagnosis = diagnose(ErrorModel(described), obs)
    names = [c.name for c in diagnosis.selected]
    assert names == ["rotary_location:B"], diagnosis.text()
    named = diagnosis.selected[0]
    assert named.parameters["EX0B"] == pytest.approx(offset, abs=0.3e-6)
    said = {a["name"]: a for a in named.inseparable}
    assert "squareness:EYZ" in said, named.inseparable
    assert said["squareness:EYZ"]["parameters"]["angle_rad"] == pytest.approx(square, rel=0.05)
    assert "along the circle EA0B draws" in said["squareness:EYZ"]["reason"]
    assert "cannot part rotary_location:B from" in named.explanation


def test_several_spheres_located_one_by_one_each_keep_their_own_zero():
    """Three spheres probed on a trunnion, each found at the set-up on its own: where each
    sphere really sits is known only to that finding (here 20 um apart from the nominal),
    so each reads from a zero of its own. A C-line offset moves each by (I - R_C) d from
    that zero; judged with one zero for all, the steps between the spheres would be left
    over and named as something else."""
    generator, described = _trunnion_bc({"B": 0, "C": 0})
    spheres = np.array([[0.06, -0.04, 0.05], [-0.08, 0.03, 0.02], [0.02, 0.09, 0.07]])
    found_off = np.array([[20e-6, -15e-6, 8e-6], [-12e-6, 18e-6, -20e-6], [5e-6, 9e-6, 16e-6]])
    q, target, group = [], [], []
    for index, sphere in enumerate(spheres):
        poses = [{"B": 0.0, "C": 0.0}] + [{"B": math.radians(b), "C": math.radians(c)}
                                          for b in (-60, -30, 0, 30) for c in range(0, 360, 45)]
        q += [cs.solve_linear(generator, p, sphere) for p in poses]
        target += [sphere] * len(poses)
        group += [index] * len(poses)
    setup_rows = {g: group.index(g) for g in range(len(spheres))}
    rows = {"q": q, "target": np.array(target), "group": group, "setup": setup_rows,
            "tool_setup": 0}
    errors, _ = cs.located_errors(generator, cs.errs_from_effects(
        [_effect("EX0C", "C", 14e-6)]), rows)
    n = len(q)
    positions = {a: np.array([row[a] for row in q]) for a in described.axis_order}
    measured = errors + found_off[group] + np.random.default_rng(3).normal(0.0, NOISE, (n, 3))
    obs = Observations(positions, measured, np.ones((n, 3), bool), np.arange(n, dtype=float),
                       {}, {}, 2 * NOISE, work_point=np.array(target))
    found = target_groups(obs.work_point, n)
    assert len(set(zip(found.tolist(), group))) == len(spheres)     # the same partition
    diagnosis = diagnose(ErrorModel(described), obs)
    assert [s.name for s in diagnosis.selected] == ["rotary_location:C"], diagnosis.text()
    assert diagnosis.selected[0].parameters["EX0C"] == pytest.approx(14e-6, abs=1e-6)
    assert diagnosis.final_cv_rmse < 3 * NOISE


def test_a_table_yaw_and_a_straightness_of_its_axis_are_said_alike_where_the_tool_stays():
    """An R-test on a trunnion: the tables bring the sphere under a tool that stays, so the
    Y table's yaw E_CY(y) = c1 y turns the sphere about an arm that is Y's own travel, and
    moves it in x by about c1 y^2 - a straightness EXY of Y. Whichever is named, the other
    is said, with its own fit; a yaw of 300 urad/m is c1 itself. Read as the located
    sphere reads it (the yaw turns the rotary axes Y carries, and its value at the set-up
    turns with them), the yaw is named with its closed-form coefficients instead."""
    work = [cs._ax("Y", -1, [0, 0, 0.092]), cs._ax("X", -1, [0, 0, 0.324]),
            cs._ax("A", -1, [0, 0, -0.049]), cs._ax("C", -1, [0, 0, 0])]
    generator, described = _machines(work, [cs._ax("Z", -1, [0, 0, 0.632])], [0, 0, -0.199],
                                     {"A": 0, "C": 0}, {"A": (-30, 110), "C": (-360, 360)})
    poses = [{"A": math.radians(a), "C": math.radians(c)}
             for a in np.arange(-30, 111, 10) for c in np.arange(0, 360, 15)]
    yaw = {"iso_name": "ECY", "kind": "table_tilt", "axis": "Y", "value_si": [0.0, 300e-6, 0.0],
           "pivot_m": [0.0, 0.0, 0.0]}
    obs = _survey(generator, described, poses, [yaw])
    diagnosis = diagnose(ErrorModel(described), obs)
    named = diagnosis.selected[0]
    said = {a["name"]: a for a in named.inseparable}
    # The yaw's Legendre P1 over the stroke -0.6..0.9 m: c1 x the half stroke, 225 urad
    # (its fit of the straightness' contribution, noise and all: within 35 %).
    if named.name == "angular:ECY" and named.setting.get("located"):
        # Read as the located sphere reads it, with its constant part c1 x 0.15 m = 45 urad
        # (the stroke's middle): that part turns A's and C's lines, which no straightness
        # of Y does, so the two are no longer alike.
        assert named.parameters["P1"] == pytest.approx(225e-6, rel=0.1), diagnosis.text()
        assert named.parameters["P0"] == pytest.approx(45e-6, abs=10e-6), diagnosis.text()
        return
    if named.name == "angular:ECY":
        assert "straightness:EXY" in said, diagnosis.text()
        p1 = named.parameters["P1"]
    else:
        assert named.name == "straightness:EXY" and "angular:ECY" in said, diagnosis.text()
        p1 = said["angular:ECY"]["parameters"]["P1"]
    assert abs(p1 - 225e-6) < 0.35 * 225e-6, (p1, said)
    assert "the tilt's arm is the axis' own travel" in named.explanation
