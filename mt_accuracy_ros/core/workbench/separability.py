"""What the surveyed poses cannot part: a named effect and another that moves them alike.

A rotary axis' line offset, the machine's error where the sphere was located at the
set-up (:mod:`..effects.setup_location`), a tilt of a line and a squareness can move an
instrument's target along the same circles on the poses a survey took: a single sweep
of one rotary axis, one sphere, a tool whose tip sits on the turning axis. The selection
then names one of them (the simplest, Occam), and the readings would be fitted as well by
the other. This module says so: for each named effect of these families, every other
candidate of them that reproduces its fitted contribution - with the other named effects
and the offsets free - to within what the readings can tell,

    || (I - P) X_k b_k ||^2  <=  chi2_0.95(p_k) sigma^2    (the fits' sums of squares
                                                          differ by less)

P the projection on the offsets, the other named effects and the alternative's columns,
X_k b_k the named effect's fitted contribution at the readings, sigma the instrument's
noise (k = 1), and the bound the 95 % quantile of chi-square with as many degrees of
freedom as the named effect has parameters (its fit took that much of the noise, which no
alternative need reproduce). Only a contribution the other named effects do not already
reproduce is judged (what is left of it beyond that bound). The alternative's own
coefficients are given (its least-squares fit of that contribution), so a reader - or a
proof - can read the other explanation's values.

A named squareness is also judged against a candidate together with the same plane's
squareness in another form (:func:`with_other_form`): the two forms differ by a turn of
the plane's travels against the work, which a rotary line tilted about the plane's normal
makes too, so one named form can stand for a squareness and that line's tilt at once.

A named rotary line or set-up location is also judged parameter by parameter against the
constant turns of the tool-side carriages that carry the head (:func:`head_turns`): where
the carriages stand still while the head turns, such a turn moves the located tool along
the circles a line's offset draws, and the output says which parameter it stands for. A
named rotary line's parameter is judged so against the squarenesses too
(:func:`line_squareness`): a slide that travels only to keep the tool on the target as a
rotary axis turns moves it, out of square, along the circle a tilt of that line draws;
and against the squareness of a slide that carries the head and stood still
(:func:`still_slide_squareness`), whose one move the located tool turns with the head.
A named positioning error is judged against the tilts of its axis as a straightness is
(:data:`AXIS_PAIRS`): a target at one arm from the carriage reads a tilt's Abbe error as
positioning.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..effects import family_named
from ..effects.geometric import (HEAD, STILL_TURN, carries_head, head_setup_row,
                                 lever_components, lever_line_offsets, lever_names,
                                 lever_slope_names, turns_about_carried_rotary)
from .distributions import chi2_sf
from .selection import Selector, Term

#: The families whose effects move a located target along the rotary axes' circles.
FAMILIES = ("rotary_location", "setup_location", "squareness")
#: The families of one linear axis' error motions that a survey can leave alike: where the
#: tool stays at a target the tables bring under it, a tilt's arm is the axis' own travel,
#: and the tilt moves the target as a straightness of that axis does; where the target
#: stands at one arm from the carriage across its travel, the tilt moves it along the
#: travel by the tilt times that arm (the Abbe error, ISO 230-1), as the axis'
#: positioning error does.
AXIS_FAMILIES = ("straightness", "angular", "positioning")
#: The pairs of :data:`AXIS_FAMILIES` judged against each other (of one axis).
AXIS_PAIRS = (frozenset({"straightness", "angular"}), frozenset({"positioning", "angular"}))
#: The probability below which a difference of the fits' sums of squares would be
#: chance: above the bound it is not (chi-square, 95 %).
LEVEL = 0.95

_WHY = {
    frozenset({"rotary_location", "setup_location"}):
        "a target (or tool) located at the set-up with the machine's error there turns "
        "with the rotary axes as their lines' offsets do",
    frozenset({"rotary_location", "squareness"}):
        "on these poses a tilt or offset of a rotary line and an axis pair out of square "
        "move the target along the same circle",
    frozenset({"setup_location", "squareness"}):
        "on these poses the set-up's located error and an axis pair out of square move "
        "the target alike",
    frozenset({"rotary_location"}):
        "on these poses the lines of different rotary axes move the target alike",
    frozenset({"straightness", "angular"}):
        "on these poses the tool stays where the tables bring the target, so the tilt's "
        "arm is the axis' own travel and the tilt moves the target as a straightness of "
        "that axis does",
    frozenset({"positioning", "angular"}):
        "on these poses the target stands at one arm from the carriage across its travel, "
        "so the tilt moves it along the travel by the tilt times that arm (the Abbe error, "
        "ISO 230-1), as the axis' positioning error does",
    frozenset({"rotary_location", "angular"}):
        "a carriage that stood still under the rotary axes turns them once: the carried "
        "axis' zero and its line's offset by the turn's lever (ISO 230-7), which move the "
        "target as these lines do",
    frozenset({"squareness", "angular"}):
        "a carriage's constant turn about the plane's normal turns the work once, which "
        "ISO 230-1 books as the plane's squareness; over the travel made here the tilt "
        "changes too little to be told from that turn (the tilt's numbers its own fit of "
        "the readings)",
    frozenset({"squareness"}):
        "the same pair out of square with the other axis as the reference (ISO 230-1), "
        "the rest of the difference a turn the other named effects hold",
}


def _refit(x: NDArray[np.float64], contribution: NDArray[np.float64]
           ) -> tuple[NDArray[np.float64], float]:
    """The least-squares fit of ``contribution`` (R,) by the columns ``x`` (R, q) and the
    sum of squares it leaves [m^2]: what every judgement here compares with its bound."""
    solution, *_ = np.linalg.lstsq(x, contribution, rcond=None)
    rest = contribution - x @ solution
    return solution, float(rest @ rest)


def chi2_quantile(level: float, dof: int) -> float:
    """x with P(chi-square(dof) <= x) = ``level``, by bisection on the survival function
    (to 1e-9 relative; scipy.stats is not imported for one number).

    Parameters
    ----------
    level : float
        The probability, in (0, 1) (:data:`LEVEL` for the bound), dimensionless.
    dof : int
        Degrees of freedom, >= 1.

    Returns
    -------
    float
        The quantile x, dimensionless (a chi-square statistic).
    """
    low, high = 0.0, float(dof) + 10.0 * np.sqrt(2.0 * dof) + 10.0
    while high - low > 1e-9 * high:
        middle = 0.5 * (low + high)
        low, high = (middle, high) if chi2_sf(middle, dof) > 1.0 - level else (low, middle)
    return 0.5 * (low + high)


def _comparable(named: Term, other: Term) -> bool:
    """Whether ``other`` is judged as another explanation of ``named``: both move a located
    target along the rotary axes' circles, or they are a straightness and a tilt of one
    linear axis (the axis is the variant's last letter: EXY, ECY)."""
    if other.name == named.name:
        return False
    if _still_turn_pair(named, other):
        return True
    if named.family.name in FAMILIES and other.family.name in FAMILIES:
        return not _same_lines(named, other)
    return frozenset({named.family.name, other.family.name}) in AXIS_PAIRS and \
        named.variant[-1:] == other.variant[-1:]


def _still_turn_pair(named: Term, other: Term) -> bool:
    """A rotary axis' lines and the one constant turn of a carriage that stood still under
    them (:data:`STILL_TURN`, offered only there): the turn is the carried axis' zero and
    its line's offset by the turn's lever (ISO 230-7), so on readings whose tool direction
    the set-up did not locate the two move the target alike."""
    pair = {named.family.name: named, other.family.name: other}
    turn = pair.get("angular")
    return set(pair) == {"rotary_location", "angular"} and turn is not None and \
        any(setting == STILL_TURN for setting in turn.settings)


def _same_lines(named: Term, other: Term) -> bool:
    """``other`` holds ``named``'s parameters (rotary_location:C in rotary_location:BC)."""
    return named.family.name == other.family.name == "rotary_location" and \
        (set(named.variant) <= set(other.variant) or set(other.variant) <= set(named.variant))


def alternatives(selector: Selector, selected: list[tuple[Term, dict]],
                 coefficients: list[NDArray[np.float64]], terms: list[Term]
                 ) -> list[list[dict]]:
    """For each selected term, the candidates the readings cannot part from it.

    Parameters
    ----------
    selector : Selector
        The selection that named ``selected`` (its rows, offsets and noise; the noise
        sigma in the readings' unit, [m] or [rad]).
    selected : list of tuple of (Term, dict)
        (term, setting) of each named effect, in order.
    coefficients : list of ndarray, shape (p_k,)
        Each named effect's joint-fit coefficients, in SI (each in its parameter's own
        unit, as the family names them), in the order of ``selected``.
    terms : list of Term
        The candidates the selection considered.

    Returns
    -------
    list of list of dict
        Per selected term, a list of ``{"name", "parameters" (SI, the alternative's fit of
        the named contribution), "reason"}`` (and ``"with"``, the other squareness form's
        share, where the alternative holds only together with it: :func:`with_other_form`);
        empty for terms outside :data:`FAMILIES`.
    """
    blocks = [selector.design_rows(t, s) for t, s in selected]
    slopes = shared_pivot_slopes(selected, coefficients)
    out: list[list[dict]] = []
    for k, ((term, setting), block) in enumerate(zip(selected, blocks)):
        found: list[dict] = []
        limit = chi2_quantile(LEVEL, max(1, block.shape[1])) * selector.noise_sigma ** 2
        contribution = block @ np.asarray(coefficients[k], dtype=np.float64)
        others = [selector.offsets] + [b for i, b in enumerate(blocks) if i != k]
        base = np.column_stack(others)
        own, *_ = np.linalg.lstsq(base, contribution, rcond=None)
        unique = contribution - base @ own
        if term.family.name in FAMILIES + AXIS_FAMILIES and float(unique @ unique) > limit:
            for other in terms:
                if _comparable(term, other):
                    found += _reproduces(selector, base, contribution, term, other, limit)
            found += with_other_form(selector, base, contribution, term, terms, limit, found)
            found += head_turns(selector, base, block, contribution, (term, setting), terms,
                                limit)
            found += line_squareness(selector, base, block, contribution, (term, setting),
                                     terms, limit, {f["name"] for f in found})
            found += still_slide_squareness(selector, base, block, contribution,
                                            (term, setting), limit, {f["name"] for f in found})
        if setting.get("lever"):
            found += _lever_statement(selector, term, setting, coefficients[k])
        elif setting.get("lever_slope") and not setting.get("located"):
            found += pivot_slope_statement(selector, (term, setting), block, slopes[k],
                                           terms, limit)
        found += _carried_zero(selector.ctx.machine, term, setting, coefficients[k])
        found += head_constant(selector, base, block, contribution, (term, setting), terms,
                               limit)
        found += plane_squareness(selector, base, block, contribution, (term, setting), terms,
                                  limit)
        found += plane_tilts(selector, base, block, term, terms, limit)
        out.append(found)
    return out


def with_other_form(selector: Selector, base: NDArray[np.float64],
                    contribution: NDArray[np.float64], term: Term, terms: list[Term],
                    limit: float, found: list[dict]) -> list[dict]:
    """The candidates that reproduce a named squareness together with the same plane's
    squareness in another form: the named effect may stand for the sum of two.

    ISO 230-1 books one squareness per plane, with either axis as the reference (EC0Y and
    EXY tilt Y's travel, EYX tilts X's); two forms differ by a turn of both travels of the
    plane against the work. A survey aligned to the machine keeps that turn, and where the
    work turns on rotary axes a rotary line tilted about the plane's normal (EC0A for an A
    carried by the plane's carriages, ISO 230-7) turns the work against the travels
    alike: the named form alone then carries a squareness and the line's tilt together,
    and no one alternative reproduces it. Judged as :func:`alternatives` judges one: the
    named contribution fitted by ``base``, the other form's column and the candidate's,
    within ``limit``; a candidate already said alone, one the other form reproduces
    alone, and one holding the lines of one said so are left out.

    Parameters
    ----------
    selector : Selector
        The selection (its rows and noise).
    base : ndarray, shape (R, q)
        The offsets and the other named effects' columns at the rows [m per unit].
    contribution : ndarray, shape (R,)
        The named squareness' fitted contribution [m].
    term : Term
        The named effect (a squareness; any other gives nothing).
    terms : list of Term
        The candidates the selection considered.
    limit : float
        The bound on the fits' sums of squares [m^2].
    found : list of dict
        What is already said of the named effect (alternatives alone).

    Returns
    -------
    list of dict
        ``{"name", "parameters" (SI, the candidate's share), "with" ({form: {"angle_rad":
        value}}, the other form's share, SI), "reason"}`` per candidate, or empty.
    """
    if term.family.name != "squareness":
        return []
    plane = _plane(term.variant)
    forms = [t for t in terms if t.family.name == "squareness" and t.name != term.name and
             _plane(t.variant) == plane]
    others = sorted((t for t in terms if _comparable(term, t) and len(t.settings) == 1 and
                     not (t.family.name == "squareness" and _plane(t.variant) == plane)),
                    key=lambda t: selector.design_rows(t, t.settings[0]).shape[1])
    said = {entry["name"] for entry in found}
    stated: list[Term] = []
    out = []
    for form in forms:
        form_columns = selector.design_rows(form, form.settings[0])
        if not np.any(form_columns) or \
                _refit(np.column_stack([base, form_columns]), contribution)[1] <= limit:
            continue
        for other in others:
            if other.name in said or any(_same_lines(other, s) for s in stated):
                continue
            columns = selector.design_rows(other, other.settings[0])
            if not np.any(columns):
                continue
            solution, misfit = _refit(np.column_stack([base, form_columns, columns]),
                                      contribution)
            if misfit > limit:
                continue
            share = float(solution[base.shape[1]])
            entry = _statement(term, other, other.settings[0], solution[base.shape[1] + 1:])
            entry["with"] = {form.name: {"angle_rad": share}}
            entry["reason"] = (f"{term.name} is {form.name} ({share * 1e6:.3g} urad, the same "
                               "plane's squareness with the other axis as reference, ISO "
                               "230-1) together with this: the two forms differ by a turn "
                               "of the plane's travels against the work, which on these "
                               "poses this candidate makes too (a rotary line turned about "
                               "the plane's normal, ISO 230-7), so the named squareness may "
                               "stand for the sum of the two")
            out.append(entry)
            stated.append(other)
            said.add(other.name)
    return out


def plane_tilts(selector: Selector, base: NDArray[np.float64], block: NDArray[np.float64],
                term: Term, terms: list[Term], limit: float) -> list[dict]:
    """The tilts with a constant part that fit the readings as well as a named squareness:
    :func:`plane_squareness` read the other way.

    A table's constant turn about the normal of a plane is that plane's squareness (ISO
    230-1) wherever its tilt changes too little over the travel the survey made to be seen:
    a carriage moved a few millimetres of its stroke turns the work once. The selection then
    names the squareness (it assumes less); the output says which tilt would fit the
    readings as well, with that tilt's numbers, so a user knows the squareness may be a
    carriage's pitch or yaw. The turn also moves the tool along its arm, which a squareness
    slope does not: a tilt can fit the readings better than the squareness without
    reproducing its contribution, so the two are judged on the readings - the tilt's first
    setting with a constant part that, in the squareness' place beside ``base``, leaves a
    sum of squares at most ``limit`` above the squareness'.

    Parameters
    ----------
    selector : Selector
        The selection (its rows, residual ``y`` [m] and noise).
    base : ndarray, shape (R, q)
        The offsets and the other named effects' columns at the rows [m per unit].
    block : ndarray, shape (R, p)
        The named squareness' columns [m per rad].
    term : Term
        The named effect (a squareness; any other gives nothing).
    terms : list of Term
        The candidates the selection considered (the angular family's among them).
    limit : float
        The bound on the fits' sums of squares [m^2].

    Returns
    -------
    list of dict
        ``{"name", "parameters" (SI, the tilt's fit of the readings), "reason"}`` per
        tilt of the squareness' plane that fits them as well, or empty.
    """
    if term.family.name != "squareness":
        return []
    plane = _plane(term.variant)
    _, named_misfit = _refit(np.column_stack([base, block]), selector.y)
    found = []
    for other in terms:
        if other.family.name != "angular" or _plane(other.variant) != plane:
            continue
        # A tilt about a pivot off the table's origin holds the squareness' slope among
        # its own columns: it fits as well by construction, and says nothing.
        for setting in (s for s in other.settings if s.get("constant") and
                        not (s.get("lever_slope") and not s.get("located"))):
            columns = selector.design_rows(other, setting)
            if not np.any(columns):
                continue
            solution, misfit = _refit(np.column_stack([base, columns]), selector.y)
            if misfit <= named_misfit + limit:
                found.append(_statement(term, other, setting, solution[base.shape[1]:]))
                break
    return found


def plane_squareness(selector: Selector, base: NDArray[np.float64], block: NDArray[np.float64],
                     contribution: NDArray[np.float64], named: tuple[Term, dict],
                     terms: list[Term], limit: float) -> list[dict]:
    """The squarenesses of a named tilt's plane that the readings cannot part from its
    constant part.

    A constant turn P0 of a carriage turns its travel's frame and all it carries about its
    pivot; a squareness tilts one axis' travel in the same plane (ISO 230-1). Where the
    target sits where the tool is (a laser tracker on the tool tip, a table brought under
    the tool), the turn moves it by P0 e_k x (tip - pivot), and the pivot moves with the
    carriage: the move grows with the carriage's own travel as a squareness slope does,
    and the two are one rotation on these poses. Judged as :func:`head_constant` judges the
    head's lines: the tilt refitted with the squareness' column in place of its P0, within
    the same bound.

    Parameters
    ----------
    selector : Selector
        The selection (its rows and noise).
    base : ndarray, shape (R, q)
        The offsets and the other named effects' columns at the rows [m per unit].
    block : ndarray, shape (R, p)
        The named tilt's columns [m per unit].
    contribution : ndarray, shape (R,)
        The named tilt's fitted contribution [m].
    named : tuple of (Term, dict)
        The named effect and its setting.
    terms : list of Term
        The candidates the selection considered (the squareness family's among them).
    limit : float
        The bound on the fits' sums of squares [m^2].

    Returns
    -------
    list of dict
        ``{"name", "parameters" ({"angle_rad": value}, SI), "reason"}`` per squareness
        that stands for P0, or empty.
    """
    term, setting = named
    if term.family.name != "angular" or not setting.get("constant") or \
            setting.get("located") == HEAD:
        return []
    kept = _without_constant(term, setting, base, block)
    if kept is None:
        return []
    plane = _plane(term.variant)
    found = []
    for other in terms:
        if other.family.name != "squareness" or _plane(other.variant) != plane:
            continue
        columns = selector.design_rows(other, other.settings[0])
        if not np.any(columns):
            continue
        solution, misfit = _refit(np.column_stack([kept, columns]), contribution)
        if misfit <= limit:
            found.append({"name": other.name, "parameters": {"angle_rad": float(solution[-1])},
                          "reason": "the tilt's constant part P0 and this squareness of its "
                                    "plane are one rotation on these poses: the carriage's "
                                    "turn about its pivot, which moves with its travel, "
                                    "grows with that travel as the squareness does (ISO "
                                    "230-1); the tilt's other numbers are its own"})
    return found


def _without_constant(term: Term, setting: dict, base: NDArray[np.float64],
                      block: NDArray[np.float64]) -> NDArray[np.float64] | None:
    """``base`` beside the named tilt's columns but its constant part P0 (R, q + p - 1)
    [m per unit]: what a refit that puts another effect in P0's place keeps; None when the
    tilt has no P0."""
    names = term.family.parameter_names(term.variant, setting)
    if "P0" not in names or len(names) != block.shape[1]:
        return None
    return np.column_stack([base, np.delete(block, names.index("P0"), axis=1)])


def _plane(variant: str) -> frozenset[str]:
    """The two linear axes a squareness or a tilt lies in: ``EB0Z`` and ``EXZ`` (X, Z), an
    angular error ``EBX`` (X, Z: turned about y)."""
    if len(variant) == 4 or variant[1] in "ABC":
        return frozenset("XYZ") - {"XYZ"["ABC".index(variant[1])]}
    return frozenset(variant[1:3])


def head_constant(selector: Selector, base: NDArray[np.float64], block: NDArray[np.float64],
                  contribution: NDArray[np.float64], named: tuple[Term, dict],
                  terms: list[Term], limit: float) -> list[dict]:
    """The head's rotary lines that the readings cannot part from a named head-located
    tilt's constant part.

    A constant turn of a carriage that carries the head and nothing more (a swivel head's
    Z ram) turns the head's lines and the tool alike: it is those lines' tilts and
    offsets (ISO 230-7), on any poses. Where the carriage carries a further linear axis
    its turn also tilts that axis' travel, which no line does. Judged as
    :func:`head_turns` judges a parameter: the tilt refitted with the lines' columns in
    place of its P0, within the same bound.

    Parameters
    ----------
    selector : Selector
        The selection (its rows and noise).
    base : ndarray, shape (R, q)
        The offsets and the other named effects' columns at the rows [m per unit].
    block : ndarray, shape (R, p)
        The named tilt's columns [m per unit].
    contribution : ndarray, shape (R,)
        The named tilt's fitted contribution [m].
    named : tuple of (Term, dict)
        The named effect and its setting.
    terms : list of Term
        The candidates the selection considered (the head's ``rotary_location`` among
        them).
    limit : float
        The bound on the fits' sums of squares [m^2].

    Returns
    -------
    list of dict
        ``{"name", "parameters" (SI, the lines' fit), "reason"}``, or empty.
    """
    term, setting = named
    if setting.get("located") != HEAD or not setting.get("constant"):
        return []
    kept = _without_constant(term, setting, base, block)
    if kept is None:
        return []
    machine = selector.ctx.machine
    head = {a for a in machine.tool_branch if machine.axes[a].is_rotary}
    for other in terms:
        if other.family.name != "rotary_location" or not set(other.variant) <= head:
            continue
        line_setting = other.settings[0]
        columns = selector.design_rows(other, line_setting)
        x = np.column_stack([kept, columns])
        solution, misfit = _refit(x, contribution)
        if np.any(columns) and misfit <= limit:
            lines = other.family.parameter_names(other.variant, line_setting)
            return [{"name": other.name,
                     "parameters": dict(zip(lines, map(float, solution[kept.shape[1]:]))),
                     "reason": "the tilt's constant part P0 turns the head's lines and the "
                               "tool alike: a carriage that carries only the head turns "
                               "as its lines' tilts and offsets do (ISO 230-7); the "
                               "tilt's other numbers are its own"}]
    return []


#: The located families a constant turn of a carriage that carries the head can stand for.
HEAD_TURNED = ("rotary_location", "setup_location")


def head_turns(selector: Selector, base: NDArray[np.float64], block: NDArray[np.float64],
               contribution: NDArray[np.float64], named: tuple[Term, dict],
               terms: list[Term], limit: float) -> list[dict]:
    """The constant turns of tool-side carriages that carry the head which the readings
    cannot part from a named rotary line's or set-up location's parameter.

    A constant turn eps of such a carriage turns the head's lines and the tool about its
    pivot; the tool, located at the head's set-up, took the turn's move there in, and that
    belief turns with the head (ISO 10791-6): it reads eps x a(q) - R_T(q) R_T(q_s)^T
    eps x a(q_t), a the arm to the tool tip. Where the carriages stand still (a sweep of a
    head axis with the tip on its line) this is a circle, as a line's offset draws: the
    parameter and the turn are one here. Each parameter of the named effect is judged on
    its own (the others refitted with the turn in its place), within the same bound.

    Parameters
    ----------
    selector : Selector
        The selection (its rows and noise).
    base : ndarray, shape (R, q)
        The offsets and the other named effects' columns at the rows [m per unit].
    block : ndarray, shape (R, p)
        The named effect's columns [m per unit].
    contribution : ndarray, shape (R,)
        The named effect's fitted contribution [m].
    named : tuple of (Term, dict)
        The named effect and its setting.
    terms : list of Term
        The candidates the selection considered (an angular family is taken from them).
    limit : float
        The bound on the fits' sums of squares [m^2].

    Returns
    -------
    list of dict
        ``{"name", "parameters" (SI), "reason"}`` per carriage turn that stands for one of
        the named parameters (``reason`` names which).
    """
    ctx = selector.ctx
    machine = ctx.machine
    term, named_setting = named
    if term.family.name not in HEAD_TURNED or head_setup_row(ctx) is None:
        return []
    angular = next((t.family for t in terms if t.family.name == "angular"), None) or \
        family_named("angular")
    names = _parameter_labels(term, named_setting, block)
    needed = _parameters_needed(base, block, contribution, limit)
    found = []
    for axis in machine.tool_branch:
        if not carries_head(machine, axis):
            continue
        for component in "ABC":
            variant = f"E{component}{axis}"
            setting = {"order": 0, "constant": True, "located": HEAD}
            if turns_about_carried_rotary(machine, variant):
                continue    # that axis' zero and line offset (ISO 230-7)
            turn = Term(angular, variant, [setting])
            columns = selector.design_rows(turn, setting)
            if not np.any(columns):
                continue
            stands = _in_place_of(base, block, contribution, columns, needed, limit)
            if stands is not None:
                j, value = stands
                why = ("a constant turn of a carriage that carries the head turns its "
                       "lines and the tool located at the head's set-up along the same "
                       "circles")
                found.append({"name": turn.name, "parameters": {"P0": value},
                              "reason": why + (f" as {names[j]} does" if names[j] else "")})
    return found


def still_slide_squareness(selector: Selector, base: NDArray[np.float64],
                           block: NDArray[np.float64], contribution: NDArray[np.float64],
                           named: tuple[Term, dict], limit: float, said: set[str]
                           ) -> list[dict]:
    """The squarenesses of a still slide carrying the head that the readings cannot part
    from a named rotary line's or set-up location's parameter.

    A slide out of square (ISO 230-1) moves what it carries by the angle times its
    position, across its travel (the slope form EXZ: Z's travel tilted toward X). Where
    the slide carries the head and stood at one position off its zero over the readings,
    that move is one constant; the tool, located at the head's set-up, took it in, and
    that belief turns with the head (ISO 10791-6) along the circles a line's offset
    draws. Such a squareness is no candidate (a slide that never moved shows no slope),
    so it is said here, with its value, for the parameter it stands for - judged as
    :func:`head_turns` judges a carriage's turn.

    Parameters
    ----------
    selector : Selector
        The selection (its rows and noise).
    base : ndarray, shape (R, q)
        The offsets and the other named effects' columns at the rows [m per unit].
    block : ndarray, shape (R, p)
        The named effect's columns [m per unit].
    contribution : ndarray, shape (R,)
        The named effect's fitted contribution [m].
    named : tuple of (Term, dict)
        The named effect and its setting (of :data:`HEAD_TURNED`; any other gives nothing).
    limit : float
        The bound on the fits' sums of squares [m^2].
    said : set of str
        The alternatives already said (not said again).

    Returns
    -------
    list of dict
        ``{"name", "parameters" ({"angle_rad": value}, SI), "reason"}`` per squareness
        that stands for one of the named parameters.
    """
    ctx = selector.ctx
    machine = ctx.machine
    term, setting = named
    if term.family.name not in HEAD_TURNED or head_setup_row(ctx) is None:
        return []
    square = family_named("squareness")
    names = _parameter_labels(term, setting, block)
    needed = _parameters_needed(base, block, contribution, limit)
    found = []
    for slide in machine.tool_branch:
        if machine.axes[slide].is_rotary or not carries_head(machine, slide):
            continue
        stance = ctx.variables.positions[slide]
        if np.ptp(stance) > 0 or not np.any(stance):
            continue    # a moving slide's squareness is a candidate; at zero it moves nothing
        for variant, reference in square.OTHER_REFERENCE.items():
            if variant[2] != slide or reference[-1] not in machine.axes or \
                    f"squareness:{variant}" in said:
                continue
            other = Term(square, variant, [{}])
            columns = selector.design_rows(other, {})
            if not np.any(columns):
                continue
            stands = _in_place_of(base, block, contribution, columns, needed, limit)
            if stands is not None:
                j, value = stands
                found.append({"name": other.name, "parameters": {"angle_rad": value},
                              "reason": f"{slide} stood at one position, where its travel "
                                        "out of square (ISO 230-1) moves the head once; the "
                                        "tool located at the head's set-up turns that move "
                                        "with the head along the same circles"
                                        + (f" as {names[j]} does" if names[j] else "")})
    return found


def _parameter_labels(term: Term, setting: dict, block: NDArray[np.float64]) -> list[str]:
    """The named effect's parameter names, one per column of ``block``; "" each where it
    has one parameter (the sentence then names the effect, not a parameter)."""
    names = term.family.parameter_names(term.variant, setting)
    return names if len(names) == block.shape[1] > 1 else [""] * block.shape[1]


def _parameters_needed(base: NDArray[np.float64], block: NDArray[np.float64],
                       contribution: NDArray[np.float64], limit: float) -> list[bool]:
    """Per column of the named effect's ``block``: whether it carries a part of the
    ``contribution`` that ``base`` and the effect's other columns do not reproduce within
    ``limit`` [m^2]. Only such a parameter has anything for another effect to stand for
    (one fitted near zero has not)."""
    needed = []
    for j in range(block.shape[1]):
        _, misfit = _refit(np.column_stack([base, np.delete(block, j, axis=1)]), contribution)
        needed.append(misfit > limit)
    return needed


def _in_place_of(base: NDArray[np.float64], block: NDArray[np.float64],
                 contribution: NDArray[np.float64], columns: NDArray[np.float64],
                 needed: list[bool], limit: float) -> tuple[int, float] | None:
    """The first needed parameter j of the named effect that the one column ``columns``
    (R, 1) stands for: the effect refitted with it in j's place, beside ``base``, leaves
    a sum of squares of at most ``limit`` [m^2]; (j, the column's coefficient), or None."""
    for j, wanted in enumerate(needed):
        if not wanted:
            continue
        x = np.column_stack([base, np.delete(block, j, axis=1), columns])
        solution, misfit = _refit(x, contribution)
        if misfit <= limit:
            return j, float(solution[-1])
    return None


def line_squareness(selector: Selector, base: NDArray[np.float64], block: NDArray[np.float64],
                    contribution: NDArray[np.float64], named: tuple[Term, dict],
                    terms: list[Term], limit: float, said: set[str]) -> list[dict]:
    """The squarenesses the readings cannot part from one parameter of a named rotary
    line.

    A slide that moves only to follow the turn of a rotary axis - the Z travel an RTCP
    makes to keep the tool's tip on one sphere as a head or a table tilts - moves the
    target, where its travel is out of square (ISO 230-1), by the angle times that
    travel, which follows the circle a tilt of the line draws (ISO 230-7): a swivel
    head's B on a Z ram, its tip L under B's line turned by b, keeps the tip on the
    sphere by Z travel L (1 - cos b), and B's line tilted about x by e moves the tip
    along y by e L (1 - cos b) - the Y-Z squareness' slope EYZ times that travel. A
    line often holds another error too (its offset): the whole effect is then
    reproduced by no squareness, so each parameter is judged on its own as
    :func:`head_turns` judges it (the others refitted with the squareness in its
    place), within the same bound.

    Parameters
    ----------
    selector : Selector
        The selection (its rows and noise).
    base : ndarray, shape (R, q)
        The offsets and the other named effects' columns at the rows [m per unit].
    block : ndarray, shape (R, p)
        The named line's columns [m per m or rad].
    contribution : ndarray, shape (R,)
        The named line's fitted contribution [m].
    named : tuple of (Term, dict)
        The named effect and its setting (a ``rotary_location``; any other gives nothing).
    terms : list of Term
        The candidates the selection considered (the squareness family's among them).
    limit : float
        The bound on the fits' sums of squares [m^2].
    said : set of str
        The alternatives already said for the whole effect (not said again).

    Returns
    -------
    list of dict
        ``{"name", "parameters" ({"angle_rad": value}, SI), "reason"}`` per squareness
        that stands for one of the line's parameters (``reason`` names which).
    """
    term, setting = named
    if term.family.name != "rotary_location" or block.shape[1] < 2:
        return []
    names = _parameter_labels(term, setting, block)
    needed = _parameters_needed(base, block, contribution, limit)
    found = []
    for other in terms:
        if other.family.name != "squareness" or other.name in said:
            continue
        columns = selector.design_rows(other, other.settings[0])
        if not np.any(columns):
            continue
        stands = _in_place_of(base, block, contribution, columns, needed, limit)
        if stands is not None:
            j, value = stands
            found.append({"name": other.name, "parameters": {"angle_rad": value},
                          "reason": "on these poses the slide's travel follows the rotary "
                                    "axes' turns (the tool kept on the target), so its "
                                    "travel out of square (ISO 230-1) moves the target "
                                    f"along the circle {names[j]} draws (ISO 230-7); the "
                                    "line's other numbers are its own"})
    return found


def _lever_statement(selector: Selector, term: Term, setting: dict,
                     coefficients: NDArray[np.float64]) -> list[dict]:
    """A located tilt's lever (its pivot off the carriage's origin) said as what it equals
    on any poses: the carried rotary lines' offsets (:func:`lever_line_offsets`), and - in
    words, with its values - the work's located set-up error v = -lever
    (:func:`located_lever` is minus :func:`located_design`'s columns across the tilt's
    axis). Only the lever's numbers are said so; the tilt's others are its own, so no
    whole alternative to the tilt is listed."""
    names = term.family.parameter_names(term.variant, setting)
    fitted = dict(zip(names, map(float, coefficients)))
    machine = selector.ctx.machine
    offsets = lever_line_offsets(machine, term.variant, fitted)
    if not offsets:
        raise ValueError(f"{term.name}: a lever, but its carriage carries no rotary line")
    carried = "".join(sorted({name[3] for name in offsets},
                             key=machine.axis_order.index))
    # The constant lever only: its slope offsets the lines by an amount that changes
    # along the carriage's travel, which no line's offset holds.
    lever = {name: fitted[name] for name in lever_names(term.variant)}
    located = ", ".join(f"v_{name[-1]} {-value * 1e6:.3g} µm" for name, value in lever.items())
    return [{"name": f"rotary_location:{carried}", "parameters": offsets,
             "reason": f"the tilt's lever ({', '.join(lever)}; -P0 (e_k x p), a translation "
                       "of the carriage) is the offset of every rotary line it carries "
                       "(ISO 230-7) and, as a target located at the set-up reads it, the "
                       f"work's located set-up error ({located}; ISO 10791-6): the three "
                       "move the readings alike on any poses; the tilt's other numbers "
                       "are its own"}]


def shared_pivot_slopes(selected: list[tuple[Term, dict]],
                        coefficients: list[NDArray[np.float64]]) -> list[dict[str, float]]:
    """Per named effect, the slopes of its pivot's move it is to say, by direction.

    Two tilts of one table about pivots off its origin (its pitch and its yaw) both move
    it along its own travel's direction: -P1 L1(u) (e_k x p) has a component along the
    axis for each. The readings hold their sum alone, so the first named tilt says the sum
    and the later ones say nothing of that direction.

    Parameters
    ----------
    selected : list of tuple of (Term, dict)
        (term, setting) of each named effect, in order.
    coefficients : list of ndarray, shape (p_k,)
        Their joint-fit coefficients, SI, in :meth:`parameter_names` order.

    Returns
    -------
    list of dict of str to float
        Per named effect ``{"x": slope [m], ...}``: the directions across its tilt's axis
        it says, with the slope summed over the named tilts of its carriage; empty for an
        effect without a plain pivot slope.
    """
    out: list[dict[str, float]] = []
    said: dict[tuple[str, str], int] = {}
    for k, (term, setting) in enumerate(selected):
        out.append({})
        if not setting.get("lever_slope") or setting.get("located"):
            continue
        fitted = dict(zip(term.family.parameter_names(term.variant, setting),
                          map(float, coefficients[k])))
        for component, name in zip(lever_components(term.variant),
                                   lever_slope_names(term.variant)):
            first = said.setdefault((term.variant[2], component), k)
            out[first][component] = out[first].get(component, 0.0) + fitted[name]
    return out


def pivot_slope_statement(selector: Selector, named: tuple[Term, dict],
                          block: NDArray[np.float64], slopes: dict[str, float],
                          terms: list[Term], limit: float) -> list[dict]:
    """A table's tilt about a pivot off its origin: each direction of the pivot's move
    said as the squareness or positioning slope that ISO 230-1 books it as.

    About a pivot p the tilt's slope moves the table by -P1 L1(u) (e_k x p) (:func:`
    lever_slope_move`): along the table's own travel a positioning slope, across it a
    straightness slope - its plane's squareness, referred to the origin. Each direction
    whose share exceeds ``limit`` is said as the one candidate whose column alone, beside
    the offsets, reproduces it within ``limit``, with that candidate's value.

    Parameters
    ----------
    selector : Selector
        The selection (its rows, offsets and noise).
    named : tuple of (Term, dict)
        The named tilt and its setting (a plain ``lever_slope`` one).
    block : ndarray, shape (R, p)
        The named tilt's columns at the rows [m per unit].
    slopes : dict of str to float
        The pivot's slopes to say, by direction [m] (:func:`shared_pivot_slopes`).
    terms : list of Term
        The candidates the selection considered.
    limit : float
        The bound on the fits' sums of squares [m^2].

    Returns
    -------
    list of dict
        ``{"name", "parameters" (SI), "reason"}`` per direction said.
    """
    term, setting = named
    names = term.family.parameter_names(term.variant, setting)
    axis = term.variant[2]
    found = []
    for component, value in slopes.items():
        column = block[:, names.index(f"lever_slope_{component}")]
        share = column * value
        if float(share @ share) <= limit:
            continue
        for other, other_setting in _slope_candidates(terms, axis, component):
            columns = selector.design_rows(other, other_setting)
            if not np.any(columns):
                continue
            solution, misfit = _refit(np.column_stack([selector.offsets, columns]), share)
            if misfit <= limit:
                own = other.family.parameter_names(other.variant, other_setting)
                found.append({
                    "name": other.name,
                    "parameters": dict(zip(own, map(float, solution[-columns.shape[1]:]))),
                    "reason": f"the tilt's pivot slope lever_slope_{component} "
                              f"{value * 1e6:.3g} µm (-P1 L1(u) (e_k x p): its pivot off "
                              f"the {axis} table's origin) moves the table along "
                              f"{component} as this does; ISO 230-1 books it so at the "
                              "origin"})
                break
    return found


def _slope_candidates(terms: list[Term], axis: str, component: str):
    """(term, setting) that move a table linearly along ``component`` with its own travel:
    its positioning slope (order 1) along its own direction, else the squarenesses of the
    plane it spans with ``component``."""
    for other in terms:
        if component == axis.lower() and other.family.name == "positioning" and \
                other.variant == f"E{axis}{axis}":
            yield other, {"order": 1}
        elif component != axis.lower() and other.family.name == "squareness" and \
                _plane(other.variant) == frozenset({axis, component.upper()}):
            yield other, other.settings[0]


def _carried_zero(machine, term: Term, setting: dict, coefficients: NDArray[np.float64]
                  ) -> list[dict]:
    """A located tilt's constant part about the direction of the first rotary axis its
    carriage carries, said as that axis' zero.

    The carriage's constant turn P0 turns that axis' body by P0 about a line parallel to
    its own, which is its zero-angle error, and moves the lines it carries by the turn's
    lever (ISO 230-7): the same rigid motion on any poses, position and direction, where
    every linear axis between the carriage and that rotary axis travels along the turn's
    direction (the turn leaves their travel as it is; else it also turns their travel, a
    squareness, and nothing is said here). The line family never fits an outer axis' zero
    (it folds it into the carried line's tilt, which a sphere alone reads alike and a
    located tool direction does not), so the output says it here, with P0's value.

    Parameters
    ----------
    machine : MachineDescription
        The machine (branches from the bed outwards).
    term : Term
        The named effect.
    setting : dict
        Its setting.
    coefficients : ndarray, shape (p,)
        Its fitted coefficients, SI, in :meth:`parameter_names` order.

    Returns
    -------
    list of dict
        ``[{"name": "rotary_location:A", "parameters": {"EA0A": P0}, "reason"}]``, or empty.
    """
    if term.family.name != "angular" or setting.get("located") is not True or \
            not setting.get("constant") or setting == STILL_TURN or \
            not turns_about_carried_rotary(machine, term.variant):
        return []
    branch = next(b for b in (machine.workpiece_branch, machine.tool_branch)
                  if term.variant[2] in b)
    carried = branch[branch.index(term.variant[2]) + 1:]
    axis = next(a for a in carried if machine.axes[a].is_rotary)
    turn = "ABC".index(term.variant[1])
    if any(machine.axes[a].direction != turn for a in carried[:carried.index(axis)]):
        return []       # the turn tilts a carried travel too: not the zero alone
    names = term.family.parameter_names(term.variant, setting)
    zero = float(dict(zip(names, map(float, coefficients)))["P0"])
    return [{"name": f"rotary_location:{axis}", "parameters": {f"E{axis}0{axis}": zero},
             "reason": f"the tilt's constant part P0 turns the {axis} axis and all it carries "
                       f"about {axis}'s direction: {axis}'s zero-angle error (E{axis}0{axis} "
                       f"{zero * 1e6:.3g} µrad) with its carried lines moved by the turn's "
                       "lever (ISO 230-7), the same rigid motion on any poses"}]


def _reproduces(selector: Selector, base: NDArray[np.float64], contribution: NDArray[np.float64],
                term: Term, other: Term, limit: float) -> list[dict]:
    """[the statement] when ``other`` (with ``base``) fits ``contribution`` within
    ``limit``: a located family's alternative at its one setting, an axis' tilt or
    straightness at the first of its settings (the simplest) that does."""
    axis_pair = other.family.name in AXIS_FAMILIES
    for setting in other.settings if axis_pair or len(other.settings) == 1 else ():
        columns = selector.design_rows(other, setting)
        if not np.any(columns):
            continue
        x = np.column_stack([base, columns])
        solution, misfit = _refit(x, contribution)
        if misfit <= limit:
            return [_statement(term, other, setting, solution[base.shape[1]:])]
    return []


def _statement(term: Term, other: Term, setting, own: NDArray[np.float64]) -> dict:
    """The alternative ``other`` at ``setting`` with its coefficients ``own``, and why."""
    names = other.family.parameter_names(other.variant, setting)
    why = _WHY.get(frozenset({term.family.name, other.family.name}),
                   "these poses cannot part them")
    return {"name": other.name, "parameters": dict(zip(names, map(float, own))),
            "reason": why}


def sentence(name: str, found: list[dict]) -> str:
    """One sentence naming what the poses cannot part ``name`` from ("" for none).

    Parameters
    ----------
    name : str
        The named effect (``family:variant``, or the family alone).
    found : list of dict
        Its alternatives, as one entry of :func:`alternatives` gives them (``"name"`` and
        ``"reason"`` are read).

    Returns
    -------
    str
        The sentence, or "" when ``found`` is empty.
    """
    if not found:
        return ""
    listed = "; ".join(f"{f['name']} ({f['reason']})" for f in found)
    return (f"these poses cannot part {name} from {listed}: the readings are fitted as "
            "well either way")
