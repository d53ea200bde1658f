"""A tilt's lever that stands for a line offset: refused by the machine's reach.

The survey is seed 11's trial 3 of ``studies.convention_surveys`` (rigid bodies written
from the physics alone): a trunnion A/C read by an R-test, its Y carriage pitched (EBY,
linear, about its origin) and A's line offset in z by EZ0A = -32.8 um. A tilt's lever is
-P0 (e_k x p): the move of all the carriage carries by its constant turn about a pivot p.
Without a bound the lever took A's whole offset, lever_z -32.8 um over P0 = 7.5 urad - a
pivot 4.35 m from the carriage's origin, beyond the machine - and the offset was named as
the tilt's. The pivot it implies is now held to :func:`machine_reach`, as the lever's slope
already was, and the offset is named as what it is.
"""
from __future__ import annotations

from bench.convention_proof import score
from convention_trials import checked, write_trial


def test_a_line_offset_is_named_as_itself_not_as_a_far_pivots_lever(tmp_path):
    truth = write_trial(tmp_path, 11, 3)
    offset = next(e for e in truth["effects"] if e["iso_name"] == "EZ0A")
    result = checked(tmp_path)
    named = {n["name"]: n for n in result["named"]}
    assert set(named) == {"rotary_location:A", "angular:EBY"}, sorted(named)
    assert not named["angular:EBY"]["setting"].get("lever"), named["angular:EBY"]["setting"]
    fitted = named["rotary_location:A"]["parameters"]["EZ0A"]
    spread = named["rotary_location:A"]["parameter_uncertainties"]["EZ0A"]
    assert abs(fitted - offset["value_si"]) < max(0.03 * abs(offset["value_si"]), 3 * spread), \
        (fitted, offset["value_si"])
    assert score(truth, result)["right"], score(truth, result)
