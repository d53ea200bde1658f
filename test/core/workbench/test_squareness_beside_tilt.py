"""A squareness named beside a table tilt whose motion cancels part of it.

Seed 83's trial 37 of ``studies.convention_surveys`` (imported by nothing of the package):
a trunnion B/C machine ``[w C B X Y b Z t]``, an R-test sphere located at B = 0, C = 45 deg,
Z's travel tilted toward X by 29.5 urad (EB0Z) and the X table's pitch EBX with a constant
part, about a pivot off the carriage. The squareness' located move turns with C into y,
where the pitch moves the readings the other way: alone the squareness moves y by more
than the residual there allows, beside the pitch it does not. Before, it was refused as
a stand-in and Z's straightness of order 5 took its place.
"""
from __future__ import annotations

from bench.convention_proof import score
from convention_trials import checked, write_trial


def test_the_squareness_is_named_beside_the_pitch_that_cancels_it_in_y(tmp_path):
    """X's pitch and a squareness of the X-Z plane are named, the squareness within 3 U
    of the truth (its slope form EXZ reads -EB0Z); the scorer calls the trial right."""
    truth = write_trial(tmp_path, 83, 37)
    assert sorted(e["iso_name"] for e in truth["effects"]) == ["EB0Z", "EBX"]
    square = next(e for e in truth["effects"] if e["iso_name"] == "EB0Z")
    result = checked(tmp_path)
    names = [n["name"] for n in result["named"]]
    assert "angular:EBX" in names and "straightness:EXZ" not in names, names
    (named,) = [n for n in result["named"] if n["name"] in ("squareness:EXZ",
                                                            "squareness:EB0Z")]
    sign = -1.0 if named["name"] == "squareness:EXZ" else 1.0
    angle = sign * named["parameters"]["angle_rad"]
    assert abs(angle - square["value_si"]) <= 3 * 2 * named["parameter_uncertainties"][
        "angle_rad"], (angle, square["value_si"])
    assert score(truth, result)["right"], score(truth, result)
