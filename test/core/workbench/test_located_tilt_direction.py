"""A located tilt's turn of the tool direction, as the fit reads it and as the model predicts it.

The survey is seed 59's trial 28 of ``studies.convention_surveys`` (rigid bodies written
from the physics alone, imported by nothing of the package): a trunnion A/C whose Y
saddle carries X, A and C, read by a two-sphere R-test set up at A = 0, C = -90 deg, with
the tool's direction. The saddle's tilt EBY, eps(q) = c1 q about y, turns the work; the
instrument located both spheres at the set-up, so the direction it reads is zero there
and the set-up's change turns with the work (ISO 10791-6):

    du(q) = -(eps(q) - R_W(q) R_W(q_s)^T eps(q_s)) x u

The fit's design read it so; the model's prediction must too, or the residual the next
look sees holds the tilt at the set-up (11 um-rad here) and stand-ins are named for it.
"""
from __future__ import annotations

import math

import numpy as np

from convention_trials import checked, drawn_trial, write_trial
from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.kinematics.chain import KinematicModel
from mt_accuracy_ros.core.kinematics.machine import load_machine, with_setup_pose

SEED, INDEX = 59, 28
LOCATED = {"order": 1, "constant": True, "located": True}


def _true_tilt(truth) -> dict:
    """The truth's EBY in the package's numbers: eps = c1 q = c1 (mid + half L1(u)), so
    P1 = c1 half and P0 = c1 mid."""
    (tilt,) = truth["effects"]
    c0, c1, c2 = tilt["value_si"]
    assert tilt["iso_name"] == "EBY" and c0 == 0.0 and c2 == 0.0, tilt
    low, high = truth["strokes_m"]["Y"]
    return {"P1": c1 * (high - low) / 2, "P0": c1 * (high + low) / 2}


def test_the_models_direction_is_the_located_instruments(tmp_path):
    """The model's tool direction at the survey's poses, with the truth's coefficients,
    equals the generator's located reading to 0.05 urad (second order in the tilt);
    read unlocated it differs by the tilt at the set-up, over 5 urad."""
    truth = write_trial(tmp_path, SEED, INDEX, only={"EBY"}, noise_m=0.0)
    trial, _ = drawn_trial(SEED, INDEX, only={"EBY"}, noise_m=0.0)
    pose = {a: math.radians(v) for a, v in truth["conventions"]["setup_pose_deg"].items()}
    machine = with_setup_pose(load_machine(tmp_path / "machine.yaml"), pose)
    entry = {"family": "angular", "variant": "EBY", "setting": dict(LOCATED),
             "coefficients": _true_tilt(truth)}
    model = ErrorModel(machine).with_effect("angular:EBY", entry)
    q = {a: np.array([row[a] for row in trial["rows"]["q"]]) for a in machine.axis_order}
    axis = KinematicModel(machine).tool_axis(q)
    expected = trial["located_direction"]
    expected = expected - axis * np.einsum("nc,nc->n", expected, axis)[:, None]

    def direction(located: bool):
        turn = model.tcp_error(q, work_point=trial["rows"]["target"], located_readings=True,
                               direction_measured=located)[1]
        return np.cross(turn, axis)             # du = theta x u

    assert np.abs(expected).max() > 40e-6
    assert np.abs(direction(True) - expected).max() < 0.05e-6
    assert np.abs(direction(False) - expected).max() > 5e-6


def test_a_located_tilt_with_the_direction_is_named_alone_with_its_value(tmp_path):
    """Checked as a user runs it (0.05 um noise): EBY alone, its slope and its value at
    the strokes' middle to 3 U; before, the direction's residual at the set-up was named
    as Z's pitch and a periodic pitch beside it."""
    truth = write_trial(tmp_path, SEED, INDEX, only={"EBY"}, noise_m=0.05e-6)
    result = checked(tmp_path)
    assert result["added"] == ["angular:EBY"], result["added"]
    (named,) = [n for n in result["named"] if n["name"] == "angular:EBY"]
    assert named["setting"] == {**LOCATED, "order": named["setting"]["order"]}
    for name, want in _true_tilt(truth).items():
        got, spread = named["parameters"][name], named["parameter_uncertainties"][name]
        assert abs(got - want) <= max(3 * spread, 0.2e-6), (name, got, want)
