"""A table's pitch whose only trace is its Abbe error, said beside the positioning error
it cannot be parted from.

Seed 41's trial 24 of ``studies.convention_surveys`` (imported by nothing of the package):
a swivel head ``[w X Y b Z C B t]``, one R-test sphere on the X table, the head turning;
X pitches (EBX, a constant part and a slope, about the carriage's origin) and C's line is
tilted (EA0C). The table moves only to keep the tool on the sphere, which stands at one
height above the carriage: the pitch's slope moves it along X by the tilt times that arm
(ISO 230-1's Abbe error), as X's positioning error does. The output named the
positioning error and said nothing of the pitch.
"""
from __future__ import annotations

from bench.convention_proof import score
from convention_trials import checked, write_trial


def test_the_positioning_error_says_the_pitch_it_stands_for(tmp_path):
    truth = write_trial(tmp_path, 41, 24)
    assert sorted(e["iso_name"] for e in truth["effects"]) == ["EA0C", "EBX"]
    result = checked(tmp_path)
    (positioning,) = [n for n in result["named"] if n["effect"] == "positioning"]
    axis = positioning["variant"][-1]
    stated = {a["name"]: a for a in positioning["inseparable"]}
    pitches = [name for name in stated if name.startswith("angular:") and name[-1] == axis]
    assert pitches, stated
    assert all("the Abbe error, ISO 230-1" in stated[name]["reason"] for name in pitches)
    assert score(truth, result)["right"], score(truth, result)
