"""What the named effects together leave: a term carrying nothing goes, a squareness says
the tilt it may be.

The surveys are trials of ``studies.convention_surveys`` (rigid bodies written from the
physics alone, imported by nothing of the package), each drawn from its own stream exactly
as in a whole proof's set:

* seed 37's trial 9: a three-axis VMC surveyed at the machining point, the X table yawed
  (ECX, quadratic) and rolled (EAX, linear). The first step took a 7th-order straightness
  EYX, which the two tilts named after it left with every number inside its uncertainty.
* seed 41's trial 1: a trunnion B/C under an R-test, the X carriage yawed (ECX with a
  constant part, about a pivot 0.43 m off). A first guess of its roll EAX was left with
  nothing once the yaw, its pivot's slope and its positioning term were named (with the
  pivot's slope read as the tilt's own, the yaw leads and EAX is never taken).
* seed 41's trial 13: a three-axis HMC whose Z carriage (the work's) pitches linearly
  (EBZ, 47 urad/m) but moved only 11.5 mm of its 120 mm stroke: over that travel the pitch
  is one constant turn of about -20.4 urad, which ISO 230-1 books as the X-Z squareness.
"""
from __future__ import annotations



from bench.convention_proof import score
from convention_trials import checked, write_trial


def test_a_first_guess_the_later_tilts_leave_at_zero_is_dropped_and_said(tmp_path):
    truth = write_trial(tmp_path, 37, 9)
    assert sorted(e["iso_name"] for e in truth["effects"]) == ["EAX", "ECX"]
    result = checked(tmp_path)
    names = [n["name"] for n in result["named"]]
    assert sorted(names) == ["angular:EAX", "angular:ECX"], names
    said = [d for d in result["dropped"] if d["name"] == "straightness:EYX"]
    assert len(said) == 1, result["dropped"]
    assert "angular:ECX" in said[0]["by"] and "angular:EAX" in said[0]["by"]
    assert "nothing to carry" in said[0]["sentence"]
    assert score(truth, result)["right"], score(truth, result)


def test_a_roll_left_inside_its_uncertainty_by_the_yaw_and_its_pivot_is_dropped(tmp_path):
    truth = write_trial(tmp_path, 41, 1)
    (yaw,) = truth["effects"]
    assert yaw["iso_name"] == "ECX"
    result = checked(tmp_path)
    names = [n["name"] for n in result["named"]]
    assert "angular:EAX" not in names and "angular:ECX" in names, names
    # Taken first and dropped, or never taken (the yaw with its pivot's slope leads).
    assert {d["name"] for d in result["dropped"]} <= {"angular:EAX"}, result["dropped"]
    # The yaw's constant part is the truth's c0 (its pivot's move is named apart).
    named = next(n for n in result["named"] if n["name"] == "angular:ECX")
    assert abs(named["parameters"]["P0"] - yaw["value_si"][0]) < 0.1 * abs(yaw["value_si"][0])
    assert score(truth, result)["right"], score(truth, result)


def test_a_squareness_says_the_pitch_of_a_carriage_that_barely_moved(tmp_path):
    truth = write_trial(tmp_path, 41, 13)
    (pitch,) = truth["effects"]
    assert pitch["iso_name"] == "EBZ" and pitch["value_si"][0] == 0.0
    result = checked(tmp_path)
    (named,) = result["named"]
    assert named["name"] == "squareness:EB0Z", named["name"]
    tilt = [a for a in named["inseparable"] if a["name"] == "angular:EBZ"]
    assert len(tilt) == 1, named["inseparable"]
    assert "squareness" in tilt[0]["reason"] and "ISO 230-1" in tilt[0]["reason"]
    # The pitch's constant part over the stroke is its value at the stroke's middle
    # (Legendre P0), c1 q_mid, and the squareness one rotation of the same size.
    low, high = truth["strokes_m"]["Z"]
    expected = pitch["value_si"][1] * 0.5 * (low + high)
    assert abs(abs(tilt[0]["parameters"]["P0"]) - abs(expected)) < 0.3 * abs(expected), \
        (tilt[0]["parameters"], expected)
    assert abs(abs(named["parameters"]["angle_rad"]) - abs(expected)) < 0.3 * abs(expected)
    assert score(truth, result)["right"], score(truth, result)


def test_a_squareness_the_poses_part_from_every_tilt_says_none(tmp_path):
    """The statement is judged, not granted: on an HMC surveyed over its travel (seed 43's
    trial 11: the squarenesses EC0Y and EB0Z) each named squareness says no tilt of its
    plane, since a carriage's tilt would move the tool along its arms as no slope does."""
    truth = write_trial(tmp_path, 43, 11)
    assert sorted(e["iso_name"] for e in truth["effects"]) == ["EB0Z", "EC0Y"]
    result = checked(tmp_path)
    squares = [n for n in result["named"] if n["name"].startswith("squareness:")]
    assert len(squares) == 2, [n["name"] for n in result["named"]]
    for square in squares:
        assert not [a for a in square.get("inseparable", []) if a["name"].startswith("angular:")], \
            square["inseparable"]
    assert score(truth, result)["right"], score(truth, result)
