"""A named squareness that stands for a squareness and a rotary line's tilt together.

The surveys are trials of ``studies.convention_surveys`` (rigid bodies written from the
physics alone, imported by nothing of the package), each drawn from its own stream exactly
as in a whole proof's set:

* seed 41's trial 15: a trunnion A/C (A on X on Y) probed at four spheres, each located on
  its own; the truth is the X-Y squareness EC0Y (-14.1 urad, Y's travel tilted) and A's
  line tilted about z (EC0A, -12.5 urad). ISO 230-1's two forms of the X-Y squareness
  (EYX tilts X's travel, EXY Y's) differ by a turn of both travels against the work,
  which A's line turned about z makes too (the work turned before A is taken in by each
  sphere's location): EYX(t) = EXY(t) + EC0A(-t) on any such poses. The check names one
  squareness, EYX, at 12.9 urad, carrying both truths; no one alternative reproduces it.
* seed 43's trial 11: a three-axis HMC, no rotary axis: no line turns the work, so a named
  squareness says no such pair.
"""
from __future__ import annotations



from bench.convention_proof import score
from convention_trials import checked, write_trial


def test_a_squareness_says_the_line_tilt_it_carries_with_the_other_form(tmp_path):
    truth = write_trial(tmp_path, 41, 15)
    values = {e["iso_name"]: e["value_si"] for e in truth["effects"]}
    assert sorted(values) == ["EC0A", "EC0Y"]
    result = checked(tmp_path)
    (named,) = result["named"]
    assert named["name"] == "squareness:EYX", named["name"]
    angle = named["parameters"]["angle_rad"]
    (line,) = [a for a in named.get("inseparable", []) if a["name"] == "rotary_location:A"]
    # The identity EYX(t) = EXY(t) + EC0A(-t): the other form takes the whole angle and
    # the line's tilt about z its opposite, the other lines nothing.
    assert line["with"].keys() == {"squareness:EXY"}, line
    assert abs(line["with"]["squareness:EXY"]["angle_rad"] - angle) < 1e-3 * abs(angle)
    assert abs(line["parameters"]["EC0A"] + angle) < 1e-3 * abs(angle), line["parameters"]
    assert all(abs(v) < 1e-3 * abs(angle) for k, v in line["parameters"].items() if k != "EC0A")
    # Its number is the truth's line tilt within 30 %, with its sign.
    assert abs(line["parameters"]["EC0A"] - values["EC0A"]) < 0.3 * abs(values["EC0A"])
    assert "ISO 230-1" in line["reason"] and "sum" in line["reason"]
    assert "squareness:EXY" in named["explanation"]
    assert score(truth, result)["right"], score(truth, result)


def test_a_squareness_without_rotary_axes_says_no_line_with_another_form(tmp_path):
    truth = write_trial(tmp_path, 43, 11)
    assert sorted(e["iso_name"] for e in truth["effects"]) == ["EB0Z", "EC0Y"]
    result = checked(tmp_path)
    squares = [n for n in result["named"] if n["name"].startswith("squareness:")]
    assert squares, [n["name"] for n in result["named"]]
    for square in squares:
        assert not [a for a in square.get("inseparable", []) if "with" in a], \
            square["inseparable"]
    assert score(truth, result)["right"], score(truth, result)
