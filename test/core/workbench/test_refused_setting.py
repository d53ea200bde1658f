"""A setting whose fit physics refuses is not the one a fold chooses while another stands.

The survey is seed 97's trial 18 of ``studies.convention_surveys`` (rigid bodies written
from the physics alone): a trunnion B/C read by an R-test, its Y carriage rolled linearly
about its origin (EAY, 160 urad/m) and Y's travel out of square toward X (EC0Y,
-34.5 urad). The roll's setting with a lever and its slope fits best by BIC, but its
constant part is nil (0.01 urad) while the lever takes 1.4 um of the squareness: a pivot
100 m away, refused. Chosen per fold by BIC alone, the candidate stood for that refused
setting only, and nothing was named. A fold now takes the best setting physics does not
refuse (the located roll), and both effects are named with their values.
"""
from __future__ import annotations

from bench.convention_proof import score
from convention_trials import checked, write_trial


def test_a_refused_lever_setting_does_not_hide_the_tilt(tmp_path):
    truth = write_trial(tmp_path, 97, 18)
    result = checked(tmp_path)
    named = {n["name"]: n for n in result["named"]}
    assert set(named) == {"angular:EAY", "squareness:EXY"}, sorted(named)
    assert not named["angular:EAY"]["setting"].get("lever"), named["angular:EAY"]["setting"]
    square = next(e for e in truth["effects"] if e["iso_name"] == "EC0Y")["value_si"]
    fitted = named["squareness:EXY"]["parameters"]["angle_rad"]
    spread = named["squareness:EXY"]["parameter_uncertainties"]["angle_rad"]
    assert abs(fitted - square) < 3 * spread, (fitted, square, spread)
    assert score(truth, result)["right"], score(truth, result)
