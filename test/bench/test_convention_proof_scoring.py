"""The convention proof scores what the output says it cannot part as said.

A stated inseparable pair is right only when the truth is among it, with its value; a
fold is right when the parameter it folds into carries the sum it stands for; a table
tilt's constant part named as a rotary line's tilt only within 30 % of it.
"""
from __future__ import annotations

from bench.convention_proof import score

CHAIN = "[w X Y b Z C B t]"


def _truth(*effects, head=True):
    return {"chain": CHAIN, "conventions": {"tool_located": head}, "effects": list(effects),
            "strokes_m": {"X": (-0.3, 0.3), "Y": (-0.11, 0.31), "Z": (0.37, 0.91)}}


def _location(name, value, axis):
    return {"iso_name": name, "kind": "location_offset" if name[1] in "XYZ" else
            "location_tilt", "axis": axis, "side": "tool", "value_si": value,
            "identifiable": True}


def _named(name, parameters, setting=None, inseparable=None):
    family, _, variant = name.partition(":")
    out = {"name": name, "effect": family, "variant": variant, "parameters": parameters,
           "parameter_uncertainties": {k: 0.0 for k in parameters}, "setting": setting or {}}
    if inseparable is not None:
        out["inseparable"] = inseparable
    return out


def test_a_stated_pair_is_right_only_with_the_truth_among_it_and_its_value():
    truth = _truth(_location("EZ0B", 33e-6, "B"))
    said = [{"name": "rotary_location:CB", "parameters": {"EZ0B": 33.3e-6, "EX0C": 0.0},
             "reason": "..."}]
    named = _named("setup_location:tool", {"v_x": 0.0, "v_y": 0.0, "v_z": 33.3e-6},
                   inseparable=said)
    assert score(truth, {"named": [named]})["right"]
    # The same statement with another value: the pair holds the truth, its value does not.
    said[0]["parameters"]["EZ0B"] = 10e-6
    assert not score(truth, {"named": [named]})["right"]
    # Said inseparable from something that is not the truth: not named.
    other = _named("setup_location:tool", {"v_x": 0.0, "v_y": 0.0, "v_z": 33.3e-6},
                   inseparable=[{"name": "squareness:EB0Z", "parameters": {"angle_rad": 1e-5},
                                 "reason": "..."}])
    verdict = score(truth, {"named": [other]})
    assert not verdict["right"] and "EZ0B not named" in verdict["why"]


def test_a_fold_is_right_when_its_parameter_carries_the_sum_it_stands_for():
    truth = _truth(_location("EB0C", -51.3e-6, "C"), _location("EY0C", 24.0e-6, "C"))
    setting = {"inseparable": "EA0C=EY0C*4.17e-01;EB0C=EX0C*-4.17e-01"}
    # EX0C stands for EX0C - 0.417 m/rad x EB0C = +21.4 um; EY0C for EY0C + 0.417 EA0C.
    right = _named("rotary_location:C", {"EX0C": 21.4e-6, "EY0C": 24.0e-6}, setting)
    assert score(truth, {"named": [right]})["right"]
    wrong = _named("rotary_location:C", {"EX0C": 5e-6, "EY0C": 24.0e-6}, setting)
    verdict = score(truth, {"named": [wrong]})
    assert not verdict["right"] and "EB0C wrong value" in verdict["why"]


def test_a_tilts_constant_part_as_a_rotary_lines_tilt_within_thirty_percent():
    # The Y table's pitch about y, 1.52e-4 rad/m x Y over [-0.11, 0.31] m: 15.2 urad on
    # average, which turns the work against the head's C line (the other side: -15.2).
    tilt = {"iso_name": "EBY", "kind": "table_tilt", "axis": "Y", "side": "work",
            "value_si": [0.0, 1.52e-4, 0.0], "constant_part_si": 0.0,
            "pivot_m": [0.0, 0.0, 0.0], "identifiable": True}
    angular = _named("angular:EBY", {"P1": 32e-6})
    for value, right in ((-15.9e-6, True), (-9e-6, False), (15.9e-6, False)):
        line = _named("rotary_location:C", {"EX0C": -7e-6, "EY0C": 0.0, "EA0C": 0.0,
                                            "EB0C": value})
        assert score(_truth(tilt), {"named": [angular, line]})["right"] is right, value


def test_a_pivots_part_along_the_axis_is_its_positioning_error_only_where_it_turns_there():
    """A yaw of Y about a pivot 0.124 m off in x moves the work along y by -0.124 eps(y):
    Y's positioning error (ISO 230-1), no extra; a pivot off in z turns nothing along y."""
    def yaw(pivot):
        return {"iso_name": "ECY", "kind": "table_tilt", "axis": "Y", "side": "work",
                "value_si": [0.0, 1.0e-4, 0.0], "constant_part_si": 0.0, "pivot_m": pivot,
                "identifiable": True}
    named = [_named("angular:ECY", {"P1": 20e-6}), _named("positioning:EYY", {"P1": 2e-6})]
    assert score(_truth(yaw([0.124, -0.34, 0.079])), {"named": named})["right"]
    verdict = score(_truth(yaw([0.0, 0.0, 0.2])), {"named": named})
    assert not verdict["right"] and "extra: positioning:EYY" in verdict["why"]


def test_a_squareness_named_as_one_rotation_is_right_with_its_value_and_sign():
    """A constant turn of a carriage that carries one axis of the plane (Y carries X, so
    EBY turns X's travel against Z's) is that plane's squareness (ISO 230-1): EB0Z tilts
    Z's travel, so P0 = -EB0Z. Another size, the wrong sign, another plane, a carriage
    that carries no axis of the plane (X, outermost: a turn of the work only) or a
    tool-side one (Z carries only the tool) are not."""
    truth = {"chain": "[w X Y b Z t]", "conventions": {"tool_located": False},
             "strokes_m": {}, "effects": [{"iso_name": "EB0Z", "kind": "squareness",
                                           "axis": "Z", "side": "tool",
                                           "value_si": -34.5e-6, "identifiable": True}]}

    def right(name, p0):
        return score(truth, {"named": [_named(name, {"P1": 0.4e-6, "P0": p0})]})["right"]

    assert right("angular:EBY", 34.47e-6)
    assert not right("angular:EBY", 12e-6)
    assert not right("angular:EBY", -34.47e-6)
    assert not right("angular:ECY", 34.47e-6)
    assert not right("angular:EBX", 34.47e-6)
    assert not right("angular_arm:EBZ", 34.47e-6)
    assert not score(truth, {"named": [_named("angular:EBY", {"P1": 34.47e-6})]})["right"]
    # Tilting the carried axis instead: EB0X turns X's travel as EBY's P0 does.
    truth["effects"][0].update(iso_name="EB0X", axis="X", side="work", value_si=20e-6)
    assert right("angular:EBY", 20e-6) and not right("angular:EBY", -20e-6)


def test_a_still_carriages_tilt_as_its_planes_squareness_with_its_value_and_sign():
    """Y never moved (at 0.1357 m): its pitch EBY is one turn eps(q0) that turns the X
    travel it carries against Z's - the X-Z squareness (ISO 230-1). With X's table moving
    against its command (sign -1, as in seed 7's trial 012) the slope tilting X's travel
    (EZX) carries +eps(q0), the rotation of Z's (EB0Z) -eps(q0); another size, the wrong
    sign, another plane, or a Y that moved are not."""
    c0, c1, c2 = -51.28e-6, 70.91e-6, 512.4e-6
    q0 = 0.1357
    turn = c0 + c1 * q0 + c2 * q0 ** 2                         # -32.3 urad
    truth = {"chain": "[w X Y b Z C B t]",
             "conventions": {"tool_located": False, "signs": {"X": -1, "Y": -1, "Z": 1}},
             "strokes_m": {"Y": (0.08, 0.19)}, "still_m": {"Y": q0},
             "effects": [{"iso_name": "EBY", "kind": "table_tilt", "axis": "Y",
                          "side": "work", "value_si": [c0, c1, c2],
                          "constant_part_si": c0, "pivot_m": [0.0, 0.0, 0.0],
                          "identifiable": True}]}

    def right(name, angle):
        return score(truth, {"named": [_named(name, {"angle_rad": angle})]})["right"]

    assert right("squareness:EZX", 0.98 * turn) and right("squareness:EB0Z", -0.98 * turn)
    assert not right("squareness:EZX", -turn) and not right("squareness:EB0Z", turn)
    assert not right("squareness:EZX", 0.5 * turn)
    assert not right("squareness:EC0Y", turn) and not right("squareness:EYX", turn)
    # A slope is the error per unit of K's command: with X's table moving with its command
    # (sign +1) the same turn gives the slope EZX the other sign; the rotation EB0Z keeps it.
    truth["conventions"]["signs"]["X"] = 1
    assert right("squareness:EZX", -turn) and not right("squareness:EZX", turn)
    assert right("squareness:EB0Z", -turn)
    truth["still_m"] = {}
    assert not right("squareness:EZX", -turn)


def test_a_tilts_constant_part_is_on_the_lines_its_carriage_carries_once():
    """X carries C on the work side, B turns the head: a constant roll of X turns C's line
    (EA0C = the mean turn) and leaves B's (EA0B = 0). Booked on B's line, the other body's,
    it is a different turn (the head's), and booked on both it is counted twice."""
    tilt = {"iso_name": "EAX", "kind": "table_tilt", "axis": "X", "side": "work",
            "value_si": [-44.5e-6, 0.0, 0.0], "constant_part_si": -44.5e-6,
            "pivot_m": [0.0, 0.0, 0.0], "identifiable": True}
    truth = {"chain": "[w C X Y b Z B t]", "conventions": {"tool_located": True},
             "strokes_m": {"X": (-0.31, 0.23)}, "effects": [tilt]}

    def right(ea0c, ea0b):
        line = _named("rotary_location:CB", {"EA0C": ea0c, "EA0B": ea0b, "EX0C": 0.0})
        return score(truth, {"named": [line]})["right"]

    assert right(-44e-6, 0.0)               # on C's line, the one X carries
    assert right(-44e-6, 1e-6)              # B's at zero within 30 % of the turn
    assert not right(0.0, 44e-6)            # on the head's B line instead
    assert not right(-22e-6, 22e-6)         # split
    assert not right(-44e-6, 44e-6)         # twice
    assert not right(-10e-6, 0.0)           # too small


def _trunnion(*effects):
    """A trunnion B/C ([w C B X Y b Z t]: X carries B, which carries C)."""
    return {"chain": "[w C B X Y b Z t]", "conventions": {"tool_located": False},
            "effects": list(effects), "strokes_m": {"X": (-0.2, 0.2), "Y": (-0.2, 0.2),
                                                    "Z": (0.2, 0.5)}}


def _pitch(constant):
    # The X table's pitch about y: c0 + 2.2e-4 rad/m x X over [-0.2, 0.2] m (mean c0).
    return {"iso_name": "EBX", "kind": "table_tilt", "axis": "X", "side": "work",
            "value_si": [constant, -2.2e-4, 0.0], "constant_part_si": constant,
            "pivot_m": [0.29, 0.12, 0.39], "identifiable": True}


def _c_tilt(value):
    return {"iso_name": "EB0C", "kind": "location_tilt", "axis": "C", "side": "work",
            "value_si": value, "identifiable": True}


def test_a_carried_lines_tilt_holds_its_carriages_constant_turn_unless_a_tilt_holds_it():
    # X's constant turn about y (26 urad) turns C's line about y with it: with the pitch
    # named without a constant part, C's line carries 39 + 26 urad, not 39 alone.
    truth = _trunnion(_pitch(26e-6), _c_tilt(39e-6))
    pitch = _named("angular:EBX", {"P1": -44e-6})
    for value, right in ((65e-6, True), (39e-6, False), (-65e-6, False)):
        line = _named("rotary_location:C", {"EX0C": 0.0, "EY0C": 0.0, "EA0C": 0.0,
                                            "EB0C": value})
        assert score(truth, {"named": [line, pitch]})["right"] is right, value
    # Where the named pitch holds its constant part, the line holds its own tilt alone.
    held = _named("angular:EBX", {"P1": -44e-6, "P0": 26e-6})
    line = _named("rotary_location:C", {"EX0C": 0.0, "EY0C": 0.0, "EA0C": 0.0,
                                        "EB0C": 39e-6})
    assert score(truth, {"named": [line, held]})["right"]


def test_a_carried_lines_tilt_is_right_in_its_carriages_constant_turn_with_the_sum():
    # The C line tilted -32 urad about y, X turned 56 urad about y: one named pitch whose
    # P0 holds both (24 urad) accounts for the line's tilt; another P0 does not.
    truth = _trunnion(_pitch(56e-6), _c_tilt(-32e-6))
    for value, right in ((24e-6, True), (56e-6, False), (-24e-6, False)):
        pitch = _named("angular:EBX", {"P1": -44e-6, "P0": value})
        assert score(truth, {"named": [pitch]})["right"] is right, value
    # A tilt of the carriage about another direction holds none of it.
    roll = {"iso_name": "EAX", "kind": "table_tilt", "axis": "X", "side": "work",
            "value_si": [24e-6, 0.0, 0.0], "constant_part_si": 24e-6, "pivot_m": None,
            "identifiable": True}
    verdict = score(_trunnion(roll, _c_tilt(-32e-6)),
                    {"named": [_named("angular:EAX", {"P0": 24e-6})]})
    assert not verdict["right"] and "EB0C not named" in verdict["why"]
