"""A table's tilt about a pivot off its origin, on a machine without rotary axes.

The surveys are trials of ``studies.convention_surveys`` (rigid bodies written from the
physics alone, imported by nothing of the package), whose tables tilt by
eps(q) = c0 + c1 q + c2 q^2 about a pivot p of their own frame. About p the table turns
the work by eps e_k x (r - p): beside the tilt about the origin, the move -eps(q) e_k x p,
whose slope -P1 L1(u) (e_k x p) is a positioning and a straightness slope of the table's
own axis (ISO 230-1). The workbench names the tilt with that slope as one rotation
(``lever_slope``), and says what ISO 230-1 books it as at the origin.
"""
from __future__ import annotations

import numpy as np
import pytest

from bench.convention_proof import score
from convention_trials import checked, write_trial
from mt_accuracy_ros.core.effects import geometric
from mt_accuracy_ros.core.effects.geometric import lever_slope_move

PLAIN_PIVOT = {"order": 1, "constant": True, "lever_slope": True}


def _named(result, name):
    (found,) = [n for n in result["named"] if n["name"] == name]
    return found


@pytest.mark.parametrize("seed, index", [(47, 14), (43, 14), (47, 29)])
def test_the_pivots_slope_is_the_tilts_slope_across_the_pivot(tmp_path, seed, index):
    """Closed form: the fitted lever slope is -P1 (e_k x p), p the generator's pivot (its
    frame parallel to the bed's), to 3 standard uncertainties or 0.2 um."""
    truth = write_trial(tmp_path, seed, index)
    (tilt,) = truth["effects"]
    assert tilt["kind"] == "table_tilt" and np.any(tilt["pivot_m"]), tilt
    result = checked(tmp_path)
    named = _named(result, f"angular:{tilt['iso_name']}")
    assert named["setting"] == PLAIN_PIVOT, named["setting"]
    fitted, spread = named["parameters"], named["parameter_uncertainties"]
    about = np.eye(3)["ABC".index(tilt["iso_name"][1])]
    expected = -fitted["P1"] * np.cross(about, tilt["pivot_m"])    # -P1 (e_k x p)
    for component in geometric.lever_components(tilt["iso_name"]):
        name = f"lever_slope_{component}"
        want = expected["xyz".index(component)]
        assert abs(fitted[name] - want) <= max(3 * spread[name], 0.2e-6), \
            (name, fitted[name], want)
    assert score(truth, result)["right"], score(truth, result)


def test_a_squareness_beside_a_tilt_about_the_origin_is_said_as_the_pivots_slope(tmp_path):
    """A squareness EB0Z of 45.4 urad with a yaw ECZ of the Z table about its origin: the
    yaw is named about a pivot, whose slope along x is the squareness - said so, with the
    squareness' value (either form of the X-Z pair) to 10 %, and |angle| times half the
    stroke equal to the slope (u = 2 (q - mid) / stroke)."""
    truth = write_trial(tmp_path, 41, 18)
    square = next(e for e in truth["effects"] if e["kind"] == "squareness")
    assert square["iso_name"] == "EB0Z"
    result = checked(tmp_path)
    named = _named(result, "angular:ECZ")
    assert named["setting"] == PLAIN_PIVOT, named["setting"]
    said = [a for a in named["inseparable"] if a["name"].startswith("squareness:")]
    assert len(said) == 1 and "pivot slope lever_slope_x" in said[0]["reason"], \
        named["inseparable"]
    angle = said[0]["parameters"]["angle_rad"]
    assert abs(abs(angle) - square["value_si"]) < 0.1 * square["value_si"], angle
    low, high = truth["strokes_m"]["Z"]
    slope = named["parameters"]["lever_slope_x"]
    assert abs(abs(angle) * (high - low) / 2 - abs(slope)) < 1e-3 * abs(slope)
    assert "squareness and positioning slope" in named["explanation"]
    assert score(truth, result)["right"], score(truth, result)


def test_two_tilts_of_one_table_say_their_shared_slope_once(tmp_path):
    """A pitch and a yaw of the X table about one pivot both move it along x: the readings
    hold their sum alone, which the first named says once, as X's positioning slope."""
    truth = write_trial(tmp_path, 37, 35)
    assert {e["iso_name"] for e in truth["effects"]} == {"EAX", "ECX"}
    result = checked(tmp_path)
    tilts = [n for n in result["named"] if n["name"] in ("angular:EAX", "angular:ECX")]
    assert [t["setting"] for t in tilts] == [PLAIN_PIVOT] * 2, tilts
    first, second = tilts
    slopes = [a for t in tilts for a in t["inseparable"] if "lever_slope_y" in a["reason"]]
    assert len(slopes) == 1 and slopes[0] in first["inseparable"], slopes
    total = first["parameters"]["lever_slope_y"] + second["parameters"]["lever_slope_y"]
    assert f"{total * 1e6:.3g} µm" in slopes[0]["reason"], (total, slopes[0]["reason"])
    assert score(truth, result)["right"], score(truth, result)


class _Context:
    """The two things :func:`lever_slope_move` reads of a context."""

    def __init__(self, n):
        self.n = n


def test_the_pivots_move_is_minus_the_normalised_travel_across_the_tilts_axis():
    """Unit: EBX (about y) moves the table along x and z by -L1(u) per metre of slope."""
    u = np.linspace(-1.0, 1.0, 7)
    moved = lever_slope_move(_Context(u.size), "EBX", u)
    assert moved.shape == (7, 3, 2)
    np.testing.assert_array_equal(moved[:, 0, 0], -u)
    np.testing.assert_array_equal(moved[:, 2, 1], -u)
    assert not np.any(moved[:, 1, :]) and not np.any(moved[:, 0, 1]) and \
        not np.any(moved[:, 2, 0])
