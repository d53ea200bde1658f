"""The tool's direction as a measured quantity of the workbench (issue 30, item 4).

The data come from ``studies/five_axis_rtest.py``: Khan & Chen's RPPPR machine
written out with its own exact rotations, sharing no code with the package, read
by a two-sphere R-test zeroed at the work offset.
"""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.compensation.five_axis import tool_direction
from mt_accuracy_ros.core.kinematics.machine import load_machine
from mt_accuracy_ros.core.workbench.diagnosis import Observations, add_effects, diagnose
from studies.five_axis_rtest import FiveAxisErrors, reading_fields, survey

DATUM = {"X": 0.3, "Y": 0.2, "Z": 0.2, "A": 0.0, "B": 0.0}
#: The five-axis main job's machine: both rotary axes tilted, A's zero off, an eccentric
#: A bearing with a once-per-revolution positioning error.
OUT_OF_PLACE = FiveAxisErrors(a_tilt=(25e-6, 40e-6, -30e-6), b_tilt=(30e-6, 0.0, -20e-6),
                              a_radial_m=6e-6, a_phase_rad=0.4, a_positioning_rad=15e-6)


def _observations(data, with_direction: bool = True) -> Observations:
    return Observations(**reading_fields(data, with_direction))


def _model() -> ErrorModel:
    return ErrorModel(load_machine("khan_chen_rpppr"), datum=dict(DATUM))


def _held_out(model: ErrorModel, seed: int):
    """(position RMS [m], direction RMS [rad]) per component of what ``model`` leaves on
    new readings of the same machine: the compensated machine, as the R-test sees it."""
    data = survey(OUT_OF_PLACE, readings=200, seed=seed, datum=DATUM)
    position, orientation = model.tcp_error(data.positions, work_point=data.work_point_m)
    axis = tool_direction(model.kinematics, data.positions)
    orientation = orientation - axis * np.einsum("ni,ni->n", orientation, axis)[:, None]
    return (np.sqrt(np.mean((data.position_error_m - position) ** 2, axis=0)),
            np.sqrt(np.mean((data.direction_error_rad - orientation) ** 2, axis=0)))


@pytest.mark.parametrize("seed", [1, 2])
def test_rotary_tilts_are_named_from_the_tools_direction(seed):
    data = survey(OUT_OF_PLACE, readings=240, seed=seed, datum=DATUM)
    obs = _observations(data)
    diagnosis = diagnose(_model(), obs, max_effects=5)
    names = [c.name for c in diagnosis.selected]
    # Both axes' centre lines first (the direction sees their tilts' sum, the tip parts
    # them), then the A bearing's once-per-revolution positioning error.
    assert names[0] == "rotary_location:AB", diagnosis.text()
    assert "rotary_error:EAA" in names, diagnosis.text()
    location = diagnosis.selected[0].parameters
    for name, truth in (("EB0A", 40e-6), ("EC0A", -30e-6), ("EA0B", 30e-6), ("EC0B", -20e-6)):
        assert abs(location[name] - truth) < 3e-6, (name, location[name])
    # A's zero error (25 urad) is taken out by the set-up at A = 0: no parameter carries it.
    assert "EA0A" not in location and "EB0B" not in location
    eaa = next(c for c in diagnosis.selected if c.name == "rotary_error:EAA").parameters
    assert abs(np.hypot(eaa["cos1"], eaa["sin1"]) - 15e-6) < 2e-6
    # Tilts of 20-40 urad turn the tool by tens of urad before anything is added.
    assert diagnosis.direction_rmse_rad > 15e-6
    # Added, they leave the instrument's noise on new readings: the tip (0.5 um per
    # component) and the direction (1 urad per component, seen across the tool axis).
    position, direction = _held_out(add_effects(_model(), diagnosis.selected, obs), seed + 100)
    assert np.all(position < 0.7e-6), position
    assert np.all(direction < 1.3e-6), direction


def test_without_the_direction_the_tip_is_fitted_but_the_tool_stays_tilted():
    """The contrast that makes the direction worth measuring: from the tip alone the
    same candidates fit the tip as well, and leave the tool tilted by tens of urad."""
    data = survey(OUT_OF_PLACE, readings=240, seed=1, datum=DATUM)
    obs = _observations(data, with_direction=False)
    diagnosis = diagnose(_model(), obs, max_effects=5)
    position, direction = _held_out(add_effects(_model(), diagnosis.selected, obs), 101)
    assert np.all(position < 0.7e-6)
    assert np.max(direction) > 5e-6, direction


@pytest.mark.parametrize("errors, expected", [
    (FiveAxisErrors(b_tilt=(30e-6, 0.0, -20e-6)), ["rotary_location:B"]),
    (FiveAxisErrors(a_tilt=(0.0, 40e-6, -30e-6)), ["rotary_location:A"]),
    (FiveAxisErrors(), []),
])
def test_one_axis_out_of_place_is_named_alone_and_nothing_is_named_when_nothing_is(
        errors, expected):
    data = survey(errors, readings=240, seed=3, datum=DATUM)
    diagnosis = diagnose(_model(), _observations(data), max_effects=5)
    assert [c.name for c in diagnosis.selected] == expected, diagnosis.text()
    if not expected:
        assert "nothing missing" in diagnosis.text()


def test_a_reading_without_the_direction_is_judged_on_its_tip_only():
    data = survey(OUT_OF_PLACE, readings=240, seed=4, datum=DATUM)
    obs = _observations(data)
    obs.orientation_measured[::2] = False      # every other reading: a probe, no R-test
    obs.measured_orientation_rad[::2] = np.nan  # what it did not measure is never read
    diagnosis = diagnose(_model(), obs, max_effects=5)
    assert diagnosis.selected and diagnosis.selected[0].name == "rotary_location:AB"


@pytest.mark.parametrize("uncertainty", [0.0, float("nan"), 5.0])
def test_a_direction_uncertainty_that_is_no_uncertainty_is_one_clear_error(uncertainty):
    from mt_accuracy_ros.core.errors import ParameterError

    obs = _observations(survey(OUT_OF_PLACE, readings=40, seed=5, datum=DATUM))
    obs.orientation_uncertainty_rad = uncertainty
    with pytest.raises(ParameterError, match="tool-direction uncertainty"):
        diagnose(_model(), obs)


def test_directions_are_taken_from_the_readings_that_measured_them():
    data = survey(OUT_OF_PLACE, readings=4, seed=6, datum=DATUM)
    obs = Observations(**reading_fields(data, with_direction=False))
    obs.set_directions([None, None, None, None], [0.0] * 4)
    assert not obs.measures_direction
    errors = [data.direction_error_rad[0], None, data.direction_error_rad[2], None]
    obs.set_directions(errors, [3e-6, 99.0, 5e-6, 99.0])   # unmeasured: ignored
    assert obs.orientation_measured.tolist() == [True, False, True, False]
    assert obs.orientation_uncertainty_rad == pytest.approx(4e-6)
    np.testing.assert_array_equal(obs.measured_orientation_rad[1], 0.0)
    np.testing.assert_array_equal(obs.measured_orientation_rad[2], data.direction_error_rad[2])
