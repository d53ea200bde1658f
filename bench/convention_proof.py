"""The workbench on surveys whose conventions are drawn at random, made without the package.

``studies.convention_surveys`` (written from the physics alone: it imports nothing of
``mt_accuracy_ros``) draws per trial a topology (trunnion A/C and B/C, swivel head B/C,
mixed table/head, three-axis VMC and HMC), an instrument (R-test, laser tracker,
probing of one or several spheres, machining-point survey), the set-up pose, the
tables' signs, tilt pivots, units and column names, and one or two hidden effects
(rotary location errors, table tilts with or without a constant part, squareness) or
none. Each trial is checked exactly as a user would: ``mt-accuracy check survey.csv
--columns map.yaml --auto 3 --json``.

Scoring, per trial (every identifiable effect of the truth):

* a rotary location error (EX0C, EY0A, EA0C ...) is right when a ``rotary_location``
  effect of its axis is named and carries it with the truth's sign, within 30 % or
  3 U of its value;
* a table tilt is right when the tilt itself is named (an angular error of that axis,
  with or without its arm), and - for a tilt with a constant part - the constant part
  may be named as the squareness of its plane (ISO 230-1; its two forms together are
  one rotation of the body) or carried by the tilt; a pivot away from the carriage's
  origin may add a straightness of the same axis, a slope along it, or - where the
  pivot's offset turns along the axis' own travel - its positioning error (ISO 230-1);
* a tilt of a carriage the survey never moved is one constant turn eps(q0): named as the
  squareness of the plane it turns, where the carriage carries exactly one axis of that
  plane (ISO 230-1), it is right within 30 % or 3 U of eps(q0), with the sign of the
  squareness-as-one-rotation rule below (the same relation read the other way);
* a zero-angle error the poses can see (an outer axis' zero: a located sphere sees it as
  the tilt of the axis it carries) is right as that tilt, named on that axis'
  ``rotary_location``; where the output folds it into the carried line ("EB0B=EX0C*-0.118&
  EB0C*1", ISO 230-7: the line turned about the outer one) it is scored as a fold, below;
* a squareness is right when a squareness of its plane is named, or one rotation: the
  constant part P0 of the tilt of a carriage that carries exactly one axis of that plane
  (it turns that axis' travel against the other's, which ISO 230-1 books as the plane's
  squareness), within 30 % or 3 U with its sign;
* what the poses cannot part is said, and scored as said: a rotary location error the
  named effect folds into another (``setting.inseparable``, "EB0C=EX0C*-0.417": EX0C
  stands for EX0C - 0.417 m/rad x EB0C) is right when every parameter it folds into
  carries the truth's sum within 30 % or 3 U, and a truth kept as a parameter into
  which another truth is folded is judged against that sum too (a line error of an
  outer axis that stood still, folded into the line it carries, alike); an effect the output
  states the readings cannot part from a named one (``inseparable``: the other's name
  and its own fit of the same contribution) is right when that statement would be right
  as a named effect - the truth among the stated pair, with its value;
* a table tilt's constant part - its mean over the stroke, which the catalogue's
  zero-mean shapes leave out - turns one body against the other: named as the lines of
  rotary axes tilted about the same direction, it is right when the lines the tilted
  carriage carries together carry it, within 30 % or 3 U, and the other body's lines stay
  at zero; where the carriage carries no rotary axis, when the other body's lines
  together carry it with the sign turned;
* a carriage's constant turn about a direction turns the rotary lines it carries about
  it too (ISO 230-7), and no pose parts it from their own tilts: a line's tilt truth is
  judged against its sum with the mean turns of the carriages that carry it, unless a
  named tilt of that carriage holds its constant part (P0); a named tilt's P0 that holds
  that sum accounts for the line's tilt (the output says P0 is the outer axis' zero, which
  turns the lines it carries);
* a ``setup_location`` (the machine's error where the work or tool was located, turning
  with it) is right beside a truth that has such an error there: a linear-axis error
  (tilt, squareness) on that side - on the tool side only when the head carries rotary
  axes, else located into the work; a rotary location error whose named value holds
  such an error too (the output stating the set-up location inseparable from it) is
  right without its value being judged - the survey cannot give the split;
* anything else named is an extra; a null trial is right when nothing is named.

A trial is **right** when every identifiable effect is right and nothing extra is named.
Run: ``python -m bench.convention_proof --trials 60 --seed 2026 --json out.json``.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from studies.convention_surveys import generate

ROTATION_AXIS = {"A": "X", "B": "Y", "C": "Z"}


def linear_strokes(path: Path) -> dict[str, tuple[float, float]]:
    """The linear axes' strokes [m] a trial's machine file gives (bare lists, SI)."""
    import yaml

    axes = (yaml.safe_load(path.read_text()) or {}).get("axes", {}) if path.exists() else {}
    return {name: tuple(map(float, spec["stroke"])) for name, spec in axes.items()
            if name in "XYZ" and isinstance(spec.get("stroke"), list)}


#: A length unit's size [m], as the generator writes the survey's position columns.
LENGTH_UNITS_M = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "in": 0.0254}


def still_axes(path: Path, truth: dict) -> dict[str, float]:
    """The linear axes whose command never changed in the survey, with that command [m]."""
    import csv

    conventions = truth["conventions"]
    scale = LENGTH_UNITS_M[conventions["units"]["length"]]
    with path.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    out = {}
    for axis, column in conventions["columns"]["pos"].items():
        if axis not in "XYZ" or not rows:
            continue
        values = np.array([float(r[column]) for r in rows]) * scale
        if np.ptp(values) < 1e-9:
            out[axis] = float(values[0])
    return out


#: An identifiable effect whose largest located signature is under this many standard
#: deviations of one reading's noise is reported as faint (still judged).
FAINT_SIGMAS = 3.0


def at_noise(truth: dict) -> list[str]:
    """The identifiable effects whose largest signature is under FAINT_SIGMAS x one
    reading's noise, in position and (where the instrument reads it) tool direction:
    faint - a fit over many readings may still find them, so they stay judged, but a
    miss there says less than a miss of a large effect."""
    conventions = truth["conventions"]
    sigma_um = 1e6 * float(conventions.get("noise_sigma_m") or 0.0)
    sigma_urad = 1e6 * float(conventions.get("noise_sigma_dir_rad") or 0.0)

    def faint(effect):
        position = (effect.get("signature_max_um") or 0.0) < FAINT_SIGMAS * sigma_um
        direction = effect.get("signature_max_dir_urad")
        turned = direction is None or not sigma_urad or direction < FAINT_SIGMAS * sigma_urad
        return sigma_um > 0 and position and turned

    return [e["iso_name"] for e in truth["effects"] if e["identifiable"] and faint(e)]


def run_check(folder: Path) -> tuple[dict | None, str, float]:
    """The CLI on one trial: (its JSON or None, what it printed, seconds)."""
    from mt_accuracy_ros.cli import main

    out = folder / "check.json"
    printed = io.StringIO()
    start = time.perf_counter()
    with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(printed):
        try:
            code = main(["check", str(folder / "survey.csv"), "--columns",
                         str(folder / "map.yaml"), "--auto", "3", "--json", str(out)])
        except SystemExit as exc:          # argparse refusals
            code = exc.code
    seconds = time.perf_counter() - start
    result = json.loads(out.read_text()) if code == 0 and out.exists() else None
    return result, printed.getvalue(), seconds


def plane_of(variant: str) -> frozenset[str]:
    """The two linear axes a squareness or constant tilt lies in: ``EB0Z`` (X, Z),
    ``EZX`` (X, Z), an angular error ``EBX`` (X, Z)."""
    if len(variant) == 4:                       # E R 0 K: turned about R's axis
        return frozenset("XYZ") - {ROTATION_AXIS[variant[1]]}
    if variant[1] in "ABC":                     # an angular error E R K
        return frozenset("XYZ") - {ROTATION_AXIS[variant[1]]}
    return frozenset({variant[1], variant[2]})  # E C K: C's error growing with K


def carried_rotary(chain: str, axis: str) -> str:
    """The rotary axis ``axis`` carries on its side of the chain ("" if none):
    ``[w C A X Y b Z t]``: A carries C; ``[w X Y b Z C B t]``: C carries B."""
    letters = chain.strip("[]").split()
    bed = letters.index("b")
    work, tool = letters[1:bed][::-1], letters[bed + 1:-1]
    side = work if axis in work else tool
    after = side[side.index(axis) + 1:]
    return next((a for a in after if a in "ABC"), "")


def folds_of(named: dict) -> dict[str, dict[str, float]]:
    """A rotary_location's folds, {folded: {kept: ratio}} (see the module docstring)."""
    out = {}
    text = (named.get("setting") or {}).get("inseparable", "")
    for part in filter(None, str(text).split(";")):
        name, _, terms = part.partition("=")
        out[name] = {k: float(r) for k, r in (t.split("*") for t in filter(None, terms.split("&")))}
    return out


def folded_share(kept: str, named: dict, truths: dict[str, float]) -> float:
    """What a named rotary_location parameter stands for beyond its own truth: each
    error the output folds into it (``setting.inseparable``) times its ratio."""
    return sum(ratio * truths.get(name, 0.0) for name, onto in folds_of(named).items()
               for k, ratio in onto.items() if k == kept)


def folded_value(effect: dict, named: dict, truths: dict[str, float]) -> str:
    """"value"/"wrong value" for a truth location error the named effect folded, "" if not."""
    into = folds_of(named).get(effect["iso_name"])
    if not into:
        return ""
    for kept in into:
        # What the kept parameter stands for: its own truth plus each folded one's share.
        expected = truths.get(kept, 0.0) + folded_share(kept, named, truths)
        value = named["parameters"].get(kept)
        spread = 3.0 * named.get("parameter_uncertainties", {}).get(kept, 0.0)
        if value is None or value * expected <= 0 or \
                abs(value - expected) > max(0.3 * abs(expected), spread):
            return "wrong value"
    return "value"


def located_companion(effect: dict, named: dict, truth: dict) -> str:
    """Why a named setup_location accounts for part of the truth ("" when it does not)."""
    if named["effect"] != "setup_location" or effect["kind"] not in ("table_tilt",
                                                                     "squareness"):
        return ""
    head = truth["conventions"].get("tool_located", False)
    side = effect["side"] if (effect["side"] == "work" or head) else "work"
    return "located at the set-up" if named["variant"] == side else ""


def mean_tilt(effect: dict, strokes: dict) -> float:
    """A tilt's mean over its axis' stroke [rad]: what the catalogue's zero-mean shapes
    leave out (eps = c0 + c1 q + c2 q^2, averaged over [a, b]); 0 without the stroke."""
    if effect["axis"] not in strokes:
        return 0.0
    a, b = strokes[effect["axis"]]
    c0, c1, c2 = effect["value_si"]
    return c0 + c1 * (a + b) / 2.0 + c2 * (a * a + a * b + b * b) / 3.0


def carriage_turns(truth: dict, named: list[dict], strokes: dict) -> dict[str, float]:
    """What each truth line tilt E{d}0{R} stands for beside the tilts of the carriages that
    carry R: a carriage's constant turn about d turns R's line about d with it (ISO 230-7),
    which no pose parts from the line's own tilt - the line then carries the sum, unless a
    named tilt of that carriage carries its constant part (P0). {line tilt: the carriages'
    mean turns to add} [rad]."""
    chain = truth.get("chain", "")
    if not chain or not strokes:
        return {}
    letters = chain.strip("[]").split()
    bed = letters.index("b")
    sides = (letters[1:bed][::-1], letters[bed + 1:-1])
    claimed = {n["variant"] for n in named if n["effect"].startswith("angular") and
               "P0" in n.get("parameters", {})}
    out: dict[str, float] = {}
    for line in truth["effects"]:
        if line["kind"] != "location_tilt":
            continue
        for tilt in truth["effects"]:
            if tilt["kind"] != "table_tilt" or tilt["iso_name"][1] != line["iso_name"][1] or \
                    tilt["iso_name"] in claimed:
                continue
            side = next((s for s in sides if tilt["axis"] in s and line["axis"] in s), None)
            if side and side.index(line["axis"]) > side.index(tilt["axis"]):
                out[line["iso_name"]] = out.get(line["iso_name"], 0.0) + \
                    mean_tilt(tilt, strokes)
    return out


def line_in_carriage_turn(effect: dict, named: dict, truth: dict, strokes: dict) -> str:
    """A truth line tilt E{d}0{R} held by the constant part P0 of a named tilt about d of a
    carriage that carries R: the carriage's turn turns R's line with it, so P0 is the sum of
    the line's tilt and the carriage's own mean turn (the output says P0 is the outer
    axis' zero, which turns the lines it carries). Right within 30 % or 3 U of that sum;
    "" when it is not."""
    chain = truth.get("chain", "")
    if effect["kind"] != "location_tilt" or not named["effect"].startswith("angular") or \
            "P0" not in named.get("parameters", {}) or not chain or not strokes:
        return ""
    variant = named["variant"]
    if variant[1] != effect["iso_name"][1]:
        return ""
    letters = chain.strip("[]").split()
    bed = letters.index("b")
    side = next((s for s in (letters[1:bed][::-1], letters[bed + 1:-1])
                 if variant[2] in s and effect["axis"] in s), None)
    if side is None or side.index(effect["axis"]) < side.index(variant[2]):
        return ""
    turn = sum(mean_tilt(t, strokes) for t in truth["effects"]
               if t["kind"] == "table_tilt" and t["iso_name"] == variant)
    expected = effect["value_si"] + turn
    value = named["parameters"]["P0"]
    spread = 3.0 * named.get("parameter_uncertainties", {}).get("P0", 0.0)
    right = value * expected > 0 and abs(value - expected) <= max(0.3 * abs(expected), spread)
    return "line tilt in its carriage's constant turn" if right else ""


def turned_line(effect: dict, named: dict, chain: str, strokes: dict) -> str:
    """A tilt's constant part named as a rotary axis' line tilted about the same direction.
    Where the tilted carriage carries rotary axes, the turn is theirs: their lines together
    carry it (its sign kept) and the other body's lines stay at zero (within 30 % of the
    turn or 3 U). Where it carries none, it turns the work (or the tool) against the other
    body, booked on the other body's lines with the sign turned, together once. "" when it
    is not."""
    if named["effect"] != "rotary_location" or not chain or not strokes:
        return ""
    mean = mean_tilt(effect, strokes)
    letters = chain.strip("[]").split()
    bed = letters.index("b")
    work, tool = letters[1:bed][::-1], letters[bed + 1:-1]
    side = work if effect["axis"] in work else tool
    carried = set(side[side.index(effect["axis"]) + 1:]) if effect["axis"] in side else set()
    component = effect["iso_name"][1]
    uncertainty = named.get("parameter_uncertainties", {})
    lines = {axis: named["parameters"][f"E{component}0{axis}"] for axis in named["variant"]
             if component != axis and f"E{component}0{axis}" in named["parameters"]}
    if not lines or not mean:
        return ""
    own = [a for a in lines if a in carried and lines[a] is not None]
    if own:
        total = sum(lines[a] for a in own)
        spread = 3.0 * np.sqrt(sum(uncertainty.get(f"E{component}0{a}", 0.0) ** 2
                                   for a in own))
        still = all(abs(v) <= max(0.3 * abs(mean),
                                  3.0 * uncertainty.get(f"E{component}0{a}", 0.0))
                    for a, v in lines.items() if a not in own)
    else:
        # Turning only the work (or the tool): the other body's lines, the sign turned.
        others = [a for a in lines if a not in side]
        total = -sum(lines[a] for a in others)
        spread = 3.0 * np.sqrt(sum(uncertainty.get(f"E{component}0{a}", 0.0) ** 2
                                   for a in others))
        still = bool(others)
    right = still and total * mean > 0 and abs(total - mean) <= max(0.3 * abs(mean), spread)
    return "constant part as a line's tilt" if right else ""


def constant_turn(effect: dict, named: dict, chain: str) -> str:
    """A squareness named as one rotation: the constant part P0 of a carriage's tilt in
    the same plane. A constant turn of a carriage turns the travels of the axes it
    carries; when it carries exactly one axis U of the plane, U's travel is turned against
    the other's - the plane's squareness (ISO 230-1). (Carrying both, or neither, it turns
    them together, or only the work: no squareness.) Right when P0 is within 30 % or 3 U of
    the squareness with its sign: the squareness tilts axis K's travel, so P0 = +value when
    K is U and -value when K is the other axis of the pair (the same angle between them).
    "" when it is not."""
    variant = named["variant"]
    if named["effect"] not in ("angular", "angular_arm") or len(variant) != 3 or not chain or \
            plane_of(variant) != plane_of(effect["iso_name"]):
        return ""
    value = named["parameters"].get("P0")
    letters = chain.strip("[]").split()
    bed = letters.index("b")
    work, tool = letters[1:bed][::-1], letters[bed + 1:-1]
    carriage = variant[2]
    side = work if carriage in work else tool if carriage in tool else []
    if value is None or not side:
        return ""
    carried = set(side[side.index(carriage) + 1:]) & plane_of(variant)
    if len(carried) != 1:
        return ""
    tilted = effect["iso_name"][3]                  # E R 0 K: K's travel turned about R
    expected = effect["value_si"] if tilted in carried else -effect["value_si"]
    spread = 3.0 * named.get("parameter_uncertainties", {}).get("P0", 0.0)
    right = value * expected > 0 and abs(value - expected) <= max(0.3 * abs(expected), spread)
    return "as one rotation" if right else ""


def still_turn(effect: dict, named: dict, chain: str, still: dict) -> str:
    """A tilt of a carriage that never moved, named as the squareness of the plane it turns:
    standing still, the tilt is one constant turn eps(q0) of the carriage, which turns the
    travel of the axis U it carries in that plane by eps(q0) against the other's - the
    plane's squareness (ISO 230-1), the other direction of :func:`constant_turn`. The named
    form tilts axis K's travel by theta_K = +eps(q0) when K is U, -eps(q0) when it is the
    other axis. A location form (``EB0Z``) is that rotation; a slope form (``EZX``: the C
    error growing with K's command) is theta_K turned into the error along C by the command's
    sign: s_K ((e_R x e_K) . e_C) theta_K, R the tilt's rotation axis. Right within 30 % or
    3 U with that sign. ``still``: ``{"at": {axis: q0 [m]}, "signs": {axis: +-1}}``. ""
    when it is not."""
    axis, variant = effect["axis"], named["variant"]
    if axis not in still.get("at", {}) or named["effect"] != "squareness" or not chain or \
            plane_of(variant) != plane_of(effect["iso_name"]):
        return ""
    letters = chain.strip("[]").split()
    bed = letters.index("b")
    work, tool = letters[1:bed][::-1], letters[bed + 1:-1]
    side = work if axis in work else tool if axis in tool else []
    carried = set(side[side.index(axis) + 1:]) & plane_of(variant) if side else set()
    value = named["parameters"].get("angle_rad")
    if len(carried) != 1 or value is None:
        return ""
    q0 = still["at"][axis]
    c0, c1, c2 = effect["value_si"]
    turn = c0 + c1 * q0 + c2 * q0 * q0             # the generator's eps(q), q the command
    tilted = variant[-1]                           # K: the axis whose travel the form tilts
    expected = turn if tilted in carried else -turn
    if len(variant) == 3:                          # a slope: error along C per K's command
        unit = {a: np.eye(3)["XYZ".index(a)] for a in "XYZ"}
        rotation = np.eye(3)["ABC".index(effect["iso_name"][1])]
        expected *= still.get("signs", {}).get(tilted, 1) * float(
            np.cross(rotation, unit[tilted]) @ unit[variant[1]])
    spread = 3.0 * named.get("parameter_uncertainties", {}).get("angle_rad", 0.0)
    right = value * expected > 0 and abs(value - expected) <= max(0.3 * abs(expected), spread)
    return "a still carriage's turn as its plane's squareness" if right else ""


def matches(effect: dict, named: dict, chain: str = "", truths: dict | None = None,
            strokes: dict | None = None, still: dict | None = None) -> str:
    """Why ``named`` accounts for the truth ``effect`` ("" when it does not)."""
    family, variant = named["effect"], named["variant"]
    iso, kind = effect["iso_name"], effect["kind"]
    if kind == "zero":
        # A located sphere sees an outer axis' zero error as the tilt of the axis it
        # carries about the same direction (EA0A as EA0C): the same turn of that line.
        carried = carried_rotary(chain, effect["axis"]) if chain else ""
        if not carried or family != "rotary_location" or carried not in variant:
            return ""
        if effect["iso_name"] in folds_of(named):
            # Said as what it folds into (its tilt and its arm's offset): scored as said.
            return folded_value(effect, named, truths or {})
        effect = dict(effect, iso_name=f"E{effect['axis']}0{carried}", axis=carried,
                      kind="location_tilt", as_carried_tilt=True)
        iso, kind = effect["iso_name"], effect["kind"]
    if kind in ("location_offset", "location_tilt"):
        if family != "rotary_location":
            return ""
        if effect["axis"] not in variant:
            # A still outer axis' line error said as what it folds into on a carried
            # line that turned: scored as said.
            return folded_value(effect, named, truths or {}) \
                if iso in folds_of(named) else ""
        value = named["parameters"].get(iso)
        if value is None:
            return folded_value(effect, named, truths or {}) if family == "rotary_location" \
                else ""
        # A parameter the output says stands for a sum is judged against that sum.
        truth = effect["value_si"] + (0.0 if effect.get("as_carried_tilt") else
                                      folded_share(iso, named, truths or {}))
        spread = 3.0 * named.get("parameter_uncertainties", {}).get(iso, 0.0)
        if value * truth > 0 and abs(value - truth) <= max(0.3 * abs(truth), spread):
            return "value"
        return "wrong value"
    if kind == "squareness":
        if family == "squareness" and plane_of(variant) == plane_of(iso):
            return "plane"
        return constant_turn(effect, named, chain)
    if kind == "table_tilt":
        axis = effect["axis"]
        if family in ("angular", "angular_periodic", "angular_arm") and variant == iso:
            return "tilt"
        constant = effect.get("constant_part_si") or 0.0
        if constant and family == "squareness" and axis in plane_of(variant) and \
                plane_of(variant) == plane_of(iso):
            return "constant part"
        turned = turned_line(effect, named, chain, strokes) or \
            still_turn(effect, named, chain, still or {})
        if turned:
            return turned
        # A pivot away from the carriage's origin adds p x eps(q): a straightness of the
        # axis, or - for the tilt's linear part - a slope (a squareness along the axis).
        pivoted = effect.get("pivot_m") and any(effect["pivot_m"])
        if pivoted and family.startswith("straightness") and variant[2] == axis:
            return "pivot"
        # Its part along the axis' own travel is that axis' positioning error (ISO 230-1):
        # a yaw of Y about a pivot off in x moves the work along y by p_x eps(y).
        if pivoted and family.startswith("positioning") and variant == f"E{axis}{axis}" and \
                abs(np.cross(np.eye(3)["ABC".index(iso[1])], effect["pivot_m"])[
                    "XYZ".index(axis)]) > 1e-3:
            return "pivot"
        if pivoted and family == "squareness" and len(variant) == 3 and variant[2] == axis:
            return "pivot"
    return ""


def score(truth: dict, result: dict | None) -> dict:
    """One trial's verdict (see the module docstring)."""
    if result is None:
        return {"right": False, "why": "refused", "named": []}
    named = result.get("named", [])
    names = [n["name"] for n in named]
    wanted = [e for e in truth["effects"] if e["identifiable"]]
    truths = {e["iso_name"]: e["value_si"] for e in truth["effects"]
              if e["kind"] in ("location_offset", "location_tilt", "zero")}
    used, problems = set(), []

    strokes = truth.get("strokes_m", {})
    # A line tilt carries its carriage's constant turn about the same direction too.
    turns = carriage_turns(truth, named, strokes)
    truths.update({iso: truths[iso] + extra for iso, extra in turns.items()})
    wanted = [dict(e, value_si=truths[e["iso_name"]]) if e["iso_name"] in turns else e
              for e in wanted]
    still = {"at": truth.get("still_m", {}),
             "signs": truth.get("conventions", {}).get("signs", {})}

    def accounts(effect, entry):
        why = matches(effect, entry, truth.get("chain", ""), truths, strokes, still) or \
            line_in_carriage_turn(effect, entry, truth, strokes)
        if why and why != "wrong value":
            return why
        # What the output says the readings cannot part from it, scored as if named.
        stated = [matches(effect, {"effect": alt["name"].split(":")[0],
                                   "variant": alt["name"].partition(":")[2],
                                   "parameters": alt["parameters"]},
                          truth.get("chain", ""), truths, strokes, still)
                  for alt in entry.get("inseparable", [])]
        said = next((f"stated inseparable ({w})" for w in stated if w and w != "wrong value"),
                    why)
        if said == "wrong value" and any(
                located_companion(other, {"effect": alt["name"].split(":")[0],
                                          "variant": alt["name"].partition(":")[2]}, truth)
                for alt in entry.get("inseparable", []) for other in wanted):
            # Its value holds the set-up's located error too, which the output says these
            # poses cannot part from it and the truth put there: no value to judge.
            return "stated inseparable from the located set-up"
        return said

    for effect in wanted:
        how = [(i, accounts(effect, n)) for i, n in enumerate(named)]
        good = [i for i, why in how if why and why != "wrong value"]
        if not good:
            wrong = [named[i]["name"] for i, why in how if why == "wrong value"]
            problems.append(f"{effect['iso_name']} " + (f"wrong value in {wrong[0]}" if wrong
                                                        else "not named"))
        used.update(good)
    # A located set-up error beside a truth that put an error there is no extra, nor is
    # an effect the output says it cannot part from one.
    def as_named(alt):
        return {"effect": alt["name"].split(":")[0], "variant": alt["name"].partition(":")[2]}

    used.update(i for i, n in enumerate(named) if i not in used and
                any(located_companion(e, entry, truth) for e in wanted
                    for entry in [n] + [as_named(a) for a in n.get("inseparable", [])]))
    extras = [names[i] for i in range(len(named)) if i not in used]
    if extras:
        problems.append("extra: " + ", ".join(extras))
    return {"right": not problems, "why": "; ".join(problems), "named": names}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--trials", type=int, default=60)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--topology")
    parser.add_argument("--instrument")
    parser.add_argument("--json", help="write every trial's outcome here")
    parser.add_argument("--only", nargs="+", default=None, metavar="TRIAL",
                        help="check only these trials of the drawn set (e.g. 008 030); the "
                             "draw is the whole set's, so a trial is the same as in a full run")
    parser.add_argument("--keep", type=Path, default=None, metavar="DIR",
                        help="write the surveys here and keep them (default: a temporary folder)")
    parser.add_argument("--no-error-conventions", action="store_true",
                        help="write every survey's error columns in the default convention "
                             "(the generator's other draws are the same either way)")
    args = parser.parse_args(argv)
    rows = []
    with (contextlib.nullcontext(str(args.keep)) if args.keep
          else tempfile.TemporaryDirectory()) as tmp:
        root = Path(tmp)
        root.mkdir(parents=True, exist_ok=True)
        with contextlib.redirect_stdout(io.StringIO()):
            generate(str(root), args.trials, args.seed, topology=args.topology,
                     instrument=args.instrument,
                     error_conventions=not args.no_error_conventions)
        index = json.loads((root / "index.json").read_text())
        for i, entry in enumerate(index["trials"]):
            if args.only and not any(entry["name"].endswith(t) for t in args.only):
                continue
            folder = root / entry["folder"]
            truth = json.loads((folder / "truth.json").read_text())
            truth["strokes_m"] = linear_strokes(folder / "machine.yaml")
            truth["still_m"] = still_axes(folder / "survey.csv", truth)
            result, printed, seconds = run_check(folder)
            verdict = score(truth, result)
            truth_names = [e["iso_name"] + ("" if e["identifiable"] else " (unidentifiable)")
                           for e in truth["effects"]] or ["null"]
            row = {"trial": entry["name"], "topology": truth["topology"],
                   "instrument": truth["instrument"], "truth": truth_names,
                   "at_noise": at_noise(truth),
                   "setup_pose_deg": truth["conventions"].get("setup_pose_deg"),
                   "error_convention": truth["conventions"].get("error_convention"),
                   "seconds": round(seconds, 2), **verdict}
            if result is None:
                row["printed"] = printed.strip().splitlines()[-1:] if printed else []
            rows.append(row)
            print(f"[{i + 1}/{len(index['trials'])}] {row['trial']} {row['topology']:<17} "
                  f"{row['instrument']:<15} truth {', '.join(truth_names):<34} "
                  f"{'RIGHT' if row['right'] else 'WRONG'} {row['why']}", flush=True)
    right = sum(r["right"] for r in rows)
    print(f"right: {right} of {len(rows)}")
    faint = [r["trial"] for r in rows if not r["right"] and r["at_noise"]]
    if faint:
        print(f"  of the wrong, with a faint identifiable effect (its largest signature under "
              f"{FAINT_SIGMAS:g} sigma of one reading's noise): {', '.join(faint)} (still "
              "counted wrong)")
    by = {}
    for r in rows:
        key = r["topology"]
        by.setdefault(key, [0, 0])
        by[key][0] += r["right"]
        by[key][1] += 1
    for key, (good, total) in sorted(by.items()):
        print(f"  {key:<17} {good} of {total}")
    if args.json:
        Path(args.json).write_text(json.dumps({"seed": args.seed, "trials": rows,
                                               "right": right}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
