"""A squareness of a slide that stood still while each sphere was probed, seen through the
work's turn under the located sphere.

The survey is seed 47's trial 24 of ``studies.convention_surveys`` (rigid bodies written
from the physics alone, imported by nothing of the package): a trunnion B/C probed on four
spheres, each located at C = 0 and probed over a C sweep, the Z ram (the tool's) tilted
toward Y by EA0Z = 42.6 urad and standing at one height per sphere. Z never moved while a
sphere was probed, so its squareness moves the tool by a constant e_s = eps z_s e_y at each
sphere; the sphere, located at the set-up, turns with C, and the readings are
(I - R_C R_C(q_s)^T) e_s (ISO 10791-6) - a circle whose radius follows the sphere's height,
which parts it from a line offset of C (one circle for every sphere).
"""
from __future__ import annotations

from bench.convention_proof import score
from convention_trials import checked, write_trial


def test_a_still_slides_squareness_is_named_from_the_located_turn(tmp_path):
    truth = write_trial(tmp_path, 47, 24)
    (square,) = truth["effects"]
    assert square["iso_name"] == "EA0Z" and square["kind"] == "squareness"
    result = checked(tmp_path)
    (named,) = result["named"]
    # The plane's squareness in either form (EA0Z, or Z's travel slope EYZ: one rotation
    # of the same pair, ISO 230-1), its size the truth's.
    assert named["name"] in ("squareness:EA0Z", "squareness:EYZ"), named["name"]
    angle, spread = named["parameters"]["angle_rad"], \
        named["parameter_uncertainties"]["angle_rad"]
    assert abs(abs(angle) - square["value_si"]) < max(0.05 * square["value_si"], 6 * spread), \
        (angle, square["value_si"])
    assert score(truth, result)["right"], score(truth, result)
