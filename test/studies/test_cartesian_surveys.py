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
    layout = LAYOUTS["vmc_500"]
    q = {"X": np.array([0.1, 0.4]), "Y": np.array([0.05, 0.3]), "Z": np.array([-0.1, -0.2])}
    error = tcp_error(layout, q, Errors(angular={("X", 2): lambda x: tilt + 0 * x}))
    lever = np.column_stack([-q["X"], -q["Y"], q["Z"] - 0.12])
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
