"""A squareness of the slide that carries a head which never turned, read by located spheres.

Seed 71's trial 11 of ``studies.convention_surveys`` (imported by nothing of the package):
a mixed table/head machine ``[w C X Y b Z B t]``, three spheres probed over a C sweep with
the B head standing at 0, and Z's travel tilted toward Y by -39.7 urad (EA0Z). The Z ram
stands at one height per sphere, so the squareness is a constant move per sphere, which
the located sphere reads as a circle as C turns. The head carries a rotary axis, but one
that stood still keeps the tool located in its own frame as one constant: before, the
squareness was offered only where the slide carried no rotary axis at all, and the tilt
was named as X's pitch and yaw.
"""
from __future__ import annotations

from bench.convention_proof import score
from convention_trials import checked, write_trial


def test_the_squareness_under_a_head_that_stood_still_is_named_with_its_value(tmp_path):
    """Only squarenesses of the Y-Z plane are named; their angles together are the truth's
    to 10 %; the proof's scorer calls the trial right."""
    truth = write_trial(tmp_path, 71, 11)
    (square,) = truth["effects"]
    assert square["iso_name"] == "EA0Z"
    result = checked(tmp_path)
    names = [n["name"] for n in result["named"]]
    assert names and all(n in ("squareness:EYZ", "squareness:EZY", "squareness:EA0Z")
                         for n in names), names
    total = sum(n["parameters"]["angle_rad"] for n in result["named"])
    assert abs(total - square["value_si"]) < 0.1 * abs(square["value_si"]), total
    assert score(truth, result)["right"], score(truth, result)
