"""A rotary axis' location error that the readings cannot see is said, never fitted.

Seed 71's trial 8 of ``studies.convention_surveys`` (imported by nothing of the package):
a mixed table/head machine ``[w C X Y b Z B t]`` surveyed by an R-test over a sweep of
the B head alone, C standing at its set-up angle throughout. A tilt of C's line moves
nothing then but rounding (1e-17 m per rad): it was fitted as 1.1e10 rad.
"""
from __future__ import annotations

from convention_trials import checked, write_trial
from mt_accuracy_ros.core.effects.geometric import parse_inseparable


def test_a_still_axis_line_tilts_are_said_unseen_and_every_fitted_number_is_physical(
        tmp_path):
    """Every rotary_location number named is a machine's (under a mm or a mrad), C's line
    tilts none of them, and they are said as moving nothing."""
    write_trial(tmp_path, 71, 8)
    result = checked(tmp_path)
    located = [n for n in result["named"] if n["name"].startswith("rotary_location:")]
    assert located, result["named"]
    for named in located:
        for name, value in named["parameters"].items():
            # Offsets [m] and tilts [rad] of a machine: none reaches a millimetre or mrad.
            assert abs(value) < 1e-3, (named["name"], name, value)
            assert name not in ("EA0C", "EB0C", "EX0C", "EY0C"), (named["name"], name)
    # Every candidate holding C's line (named or ranked) says its tilts move nothing.
    holding_c = [c for c in result["ranking"] + result["named"]
                 if c["name"].startswith("rotary_location:") and "C" in c["name"]]
    assert holding_c, [c["name"] for c in result["ranking"]]
    for candidate in holding_c:
        said = parse_inseparable(candidate["setting"].get("inseparable", ""))
        assert {"EA0C", "EB0C"} <= {k for k, v in said.items() if not v}, (candidate["name"],
                                                                             said)
