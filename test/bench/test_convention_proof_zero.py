"""The convention proof scores an outer rotary axis' zero error as the output says it.

A located sphere sees an outer axis' zero as the carried line turned about the outer one
(ISO 230-7): right as the carried axis' tilt named on that axis, and, where the output
folds it into the carried line's tilt and offset, as the sums it says those stand for.
"""
from __future__ import annotations

from bench.convention_proof import score

from test_convention_proof_scoring import _location, _named, _truth


TRUNNION = "[w C B X Y b Z t]"


def _zero(axis, value):
    return {"iso_name": f"E{axis}0{axis}", "kind": "zero", "axis": axis, "side": "work",
            "value_si": value, "identifiable": True}


def test_an_outer_zero_is_right_as_the_tilt_of_the_line_it_carries():
    truth = dict(_truth(_zero("B", 48e-6), head=False), chain=TRUNNION)
    named = _named("rotary_location:C", {"EX0C": 0.0, "EB0C": 47e-6})
    assert score(truth, {"named": [named]})["right"]
    named["parameters"]["EB0C"] = -47e-6
    assert not score(truth, {"named": [named]})["right"]


def test_an_outer_zero_said_folded_is_scored_as_the_sums_it_makes():
    """EB0B folded into C's line: EX0C stands for EX0C - 0.118 EB0B, EB0C for EB0C + EB0B."""
    truth = dict(_truth(_zero("B", 48e-6), _location("EB0C", -51e-6, "C"), head=False),
                 chain=TRUNNION)
    setting = {"inseparable": "EB0B=EX0C*-1.18e-01&EB0C*1.0e+00"}
    right = _named("rotary_location:C", {"EX0C": -5.7e-6, "EB0C": -3.1e-6}, setting)
    assert score(truth, {"named": [right]})["right"]
    # EB0C at its own truth alone is not the sum the output says it stands for.
    alone = _named("rotary_location:C", {"EX0C": -5.7e-6, "EB0C": -51e-6}, setting)
    verdict = score(truth, {"named": [alone]})
    assert not verdict["right"] and "EB0B wrong value" in verdict["why"]
    assert "EB0C wrong value" in verdict["why"]


def test_a_still_outer_lines_offset_said_folded_is_scored_as_the_sum_it_makes():
    """A's line offset EY0A 40 um while A stood at -60 deg, beside C's EY0C -37.7 um: the
    output names C's line alone, EY0C standing for EY0C + (cos 60 deg - 1) EY0A = -57.7 um."""
    truth = dict(_truth(_location("EY0A", 40e-6, "A"), _location("EY0C", -37.7e-6, "C"),
                        head=False), chain="[w C A X Y b Z t]")
    setting = {"inseparable": "EY0A=EY0C*-5.0e-01"}
    right = _named("rotary_location:C", {"EX0C": 0.0, "EY0C": -57.0e-6}, setting)
    assert score(truth, {"named": [right]})["right"]
    # C's own truth alone is not the sum the output says EY0C stands for.
    alone = _named("rotary_location:C", {"EX0C": 0.0, "EY0C": -37.7e-6}, setting)
    assert not score(truth, {"named": [alone]})["right"]
    # Not said folded, A's offset is missed on C's line.
    unsaid = _named("rotary_location:C", {"EX0C": 0.0, "EY0C": -57.0e-6})
    assert not score(truth, {"named": [unsaid]})["right"]
