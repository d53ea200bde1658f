"""A squareness of a slide that carries the head and stood still, said beside the line
offset it cannot be parted from.

Seed 89's trial 21 of ``studies.convention_surveys`` (imported by nothing of the package):
a swivel-head machine ``[w X Y b Z C B t]``, an R-test sphere under the C axis, the tool
located at the head's set-up, C swept through a turn while X, Y, Z and B stood still. Z's
travel is tilted toward X by 41.1 urad (EB0Z): at Z's one position it moves the head once,
and the located tool turns that move with C along the circle an offset of C's line draws.
The readings cannot part the two; before, the output named C's offset and said neither
the squareness nor why.
"""
from __future__ import annotations

import numpy as np

from bench.convention_proof import score
from convention_trials import checked, write_trial


def test_the_still_slides_squareness_is_said_with_its_value_beside_the_line_offset(tmp_path):
    """C's line is named; its offset EX0C is said to stand for the squareness EXZ, whose
    angle is -EB0Z (the slope form) to 3 %, and the angle times Z's position is EX0C's
    move to 3 %; the scorer calls the trial right."""
    truth = write_trial(tmp_path, 89, 21)
    square = next(e for e in truth["effects"] if e["iso_name"] == "EB0Z")
    result = checked(tmp_path)
    (line,) = [n for n in result["named"] if n["name"] == "rotary_location:C"]
    (said,) = [a for a in line["inseparable"] if a["name"] == "squareness:EXZ"]
    assert said["reason"].startswith("Z stood at one position") and \
        said["reason"].endswith("as EX0C does"), said["reason"]
    angle = said["parameters"]["angle_rad"]
    assert abs(-angle - square["value_si"]) < 0.03 * abs(square["value_si"]), angle
    survey = np.genfromtxt(tmp_path / "survey.csv", delimiter=",", names=True)
    stance_m = np.unique(survey["POS_Z_mm"]) * 1e-3
    assert stance_m.size == 1
    offset = line["parameters"]["EX0C"]
    assert abs(abs(angle * stance_m[0]) - abs(offset)) < 0.03 * abs(offset), (angle, offset)
    assert score(truth, result)["right"], score(truth, result)
