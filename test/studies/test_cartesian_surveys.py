"""Issue 28's independent generator, and a few of its trials through ``mt-accuracy check``.

:mod:`studies.cartesian_surveys` shares no code with the package (its own 4x4 chain,
three machines of its own, spline and sinusoid errors). The figures over every trial
are in docs/results.md (``python -m bench.independent_proof``); here the generator is
checked against closed forms, and one trial per machine runs the user's way: a
logger's CSV and column map, no machine, no model.
"""
from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

from studies.cartesian_surveys import (LAYOUTS, Errors, accepted, single_effect_trial,
                                       tcp_error)


def test_the_generators_chain_against_closed_forms():
    layout = LAYOUTS["gantry_2000"]       # every axis on the tool side, tip at z - 0.2 m
    q = {"X": np.array([0.3, 1.2]), "Y": np.array([0.1, 0.9]), "Z": np.array([0.2, 0.7])}
    tilt = 10e-6     # exact rotations: first order plus tilt^2 x lever ~ 1e-10 m
    # A pitch of X about y turns Y, Z and the tool: e = tilt y x (0, y, z - 0.2).
    error = tcp_error(layout, q, Errors(angular={("X", 1): lambda x: tilt + 0 * x}))
    np.testing.assert_allclose(error[:, 0], tilt * (q["Z"] - 0.2), atol=1e-9)
    np.testing.assert_allclose(error[:, 2], 0.0, atol=1e-9)
    # A table axis (the VMC's X, carried by Y): its yaw about z turns the workpiece under
    # a standing tool - the tip moves by -tilt z x (tip - X's origin) in the table frame.
    # The tables move against the command (a CNC's coordinates: the tool relative to the
    # work), so the table's origin sits at (-x, -y) and the arm is (x, y, z + tool).
    layout = LAYOUTS["vmc_500"]
    q = {"X": np.array([0.1, 0.4]), "Y": np.array([0.05, 0.3]), "Z": np.array([-0.1, -0.2])}
    error = tcp_error(layout, q, Errors(angular={("X", 2): lambda x: tilt + 0 * x}))
    lever = np.column_stack([q["X"], q["Y"], q["Z"] - 0.12])
    expected = -np.cross(np.array([0, 0, tilt]), lever)
    np.testing.assert_allclose(error, expected, atol=1e-9)
    # A linear error of the head's Z (tool side) is itself at the tip.
    error = tcp_error(layout, q, Errors(linear={("Z", 0): lambda z: 2e-6 + 0 * z}))
    np.testing.assert_allclose(error, np.tile([2e-6, 0, 0], (2, 1)), atol=1e-15)


@pytest.mark.parametrize("machine, kind, seed", [("vmc_500", "bow", 21),
                                                 ("gantry_2000", "angular", 22),
                                                 ("hmc_600", "square", 37)])
def test_a_survey_of_a_machine_never_seen_names_its_effect_and_nothing_else(
        tmp_path, machine, kind, seed):
    from mt_accuracy_ros.cli import main

    csv, column_map, fair = single_effect_trial(machine, kind, seed, tmp_path)
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["check", str(csv), "--columns", str(column_map), "--auto", "3",
                     "--json", str(tmp_path / "s.json")]) == 0
    summary = json.loads((tmp_path / "s.json").read_text())
    assert summary["machine"] == "generic_cartesian" and not summary["travel_warning"]
    named = [entry["name"] for entry in summary["named"]]
    assert named and all(accepted(name, fair) for name in named), (named, fair)


def _check(tmp_path, csv, column_map, *extra):
    from mt_accuracy_ros.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["check", str(csv), "--columns", str(column_map), "--auto", "3",
                     "--json", str(tmp_path / "s.json"), *extra])
    return code, out.getvalue(), err.getvalue()


@pytest.mark.parametrize("machine, kind, seed", [("vmc_500", "angular_table", 90_001),
                                                 ("hmc_600", "angular_table", 90_102),
                                                 ("vmc_500", "angular_tables", 90_003)])
def test_a_tilt_of_an_axis_that_carries_the_workpiece_is_named_alone(tmp_path, machine, kind,
                                                                    seed):
    """Issue 38: the generator reads the error at the workpiece point under the tool; the
    workbench, taking every error at the machining point too, names the table's tilt -
    both tables' when both tilt - and nothing else (before: 3-4 substitute terms)."""
    from studies.cartesian_surveys import judged

    csv, column_map, fair = single_effect_trial(machine, kind, seed, tmp_path, readings=700,
                                                noise_m=0.4e-6)
    assert all(name.startswith("angular:E") and name[-1] in LAYOUTS[machine].work
               for name in fair)
    code, _, _ = _check(tmp_path, csv, column_map)
    assert code == 0
    named = [entry["name"] for entry in json.loads((tmp_path / "s.json").read_text())["named"]]
    right, spurious = judged(kind, named, fair)
    assert right and not spurious, (named, fair)


def test_without_the_tool_offset_a_table_tilt_is_named_once_with_the_arm_the_data_give(
        tmp_path):
    """No tool_offset in the map: the tilt is named as angular_arm (the tilt with its arm
    along the tool fitted), not as a tilt plus a substitute straightness, and the arm it
    reports is the generator's tool (-120 mm) within its stated uncertainty."""
    import re

    csv, column_map, fair = single_effect_trial("vmc_500", "angular_table", 80_001, tmp_path,
                                                readings=700, noise_m=0.4e-6,
                                                give_tool_offset=False)
    code, out, _ = _check(tmp_path, csv, column_map)
    assert code == 0
    named = [entry["name"] for entry in json.loads((tmp_path / "s.json").read_text())["named"]]
    assert named == sorted(fair) and named[0].startswith("angular_arm:"), (named, fair)
    line = next(t for t in out.splitlines() if t.startswith(named[0] + ": the tilt acts"))
    arm, half_width = (float(v) for v in re.search(r"([-+][\d.]+) ± ([\d.]+) mm", line).groups())
    assert abs(arm - (-120.0)) <= max(half_width, 5.0), line


def _wrong_tool_offset(tmp_path, kind, seed):
    import yaml

    csv, column_map, _ = single_effect_trial("vmc_500", kind, seed, tmp_path,
                                             readings=700, noise_m=0.4e-6)
    data = yaml.safe_load(column_map.read_text())
    data["tool_offset"]["value"] = -300.0          # the truth is -120 mm
    column_map.write_text(yaml.safe_dump(data))
    return _check(tmp_path, csv, column_map)


def test_one_tilt_whose_arm_misses_the_tool_offset_says_where_its_pivot_or_the_tool_is(
        tmp_path):
    """One tilt's arm reaches from its pivot to the tool tip: 180 mm more than the map's
    tool offset says the pivot lies 180 mm away or the offset is wrong - the readings
    cannot tell, so the check goes on with the map's offset and says both, with the
    tool tip the arm supports (the generator's -120 mm)."""
    import re

    code, out, err = _wrong_tool_offset(tmp_path, "angular_table", 80_001)
    assert code == 0, err
    line = next(t for t in out.splitlines() if "from the map's tool_offset -300.0 mm" in t)
    supported = float(re.search(r"tool tip at ([-\d.]+) ±", line).group(1))
    assert abs(supported - (-120.0)) < 15.0, line
    assert "its pivot lies that far" in line and "the map's tool_offset is kept" in line


def test_a_tool_offset_two_tilts_contradict_is_refused_naming_the_value_they_support(
        tmp_path):
    """Both tables tilt: two arms whose pivots are unrelated agree on one tool tip (the
    generator's -120 mm), not the map's -300 mm - refused in one line naming it."""
    import re

    code, out, err = _wrong_tool_offset(tmp_path, "angular_tables", 90_012)
    assert code == 2 and len(err.strip().splitlines()) == 1, (err, out[-2000:])
    assert "tool_offset -300.0 mm contradicts the data: the tilts" in err
    supported = float(re.search(r"tool tip at ([-\d.]+) ±", err).group(1))
    assert abs(supported - (-120.0)) < 15.0, err


def test_the_tool_offset_is_refused_only_when_the_missing_arms_agree():
    """Closed form: two arms 1 mm apart (sigma 1 mm) agree on their weighted mean; two
    20 mm apart do not (each may be its own pivot); one alone never refuses."""
    from mt_accuracy_ros.commands.check import contradicted_tool_offset

    agree = contradicted_tool_offset([("EBX", -0.120, 1e-3), ("EAY", -0.121, 1e-3)], -0.3)
    assert "tool tip at -120.5 ± 1.4 mm" in agree and "the tilts EBX, EAY" in agree
    assert contradicted_tool_offset([("EBX", -0.120, 1e-3), ("EAY", -0.140, 1e-3)], -0.3) == ""
    assert contradicted_tool_offset([("EBX", -0.120, 1e-3)], -0.3) == ""


def test_work_axes_that_contradict_the_given_machine_are_refused_in_one_line(tmp_path):
    import yaml

    csv, column_map, _ = single_effect_trial("vmc_500", "scale", 3, tmp_path)
    data = yaml.safe_load(column_map.read_text())
    data.pop("tool_offset")
    column_map.write_text(yaml.safe_dump(data))       # work_axes [Y, X]
    code, _, err = _check(tmp_path, csv, column_map, "--machine", "kidani_hmc")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "work_axes [Y, X] contradict kidani_hmc" in err and "[Z]" in err
