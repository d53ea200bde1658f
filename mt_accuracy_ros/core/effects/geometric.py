"""Geometric effect families: the ISO 230-1 errors of every axis, squareness, rotary axes.

* **Component errors of a linear axis** (ISO 230-1; Kidani eqs. 2.6-2.12):
  positioning E_XX, straightness E_YX/E_ZX, angular E_AX/E_BX/E_CX of axis X
  (likewise Y, Z) as functions of that axis' position q. Each reaches the TCP
  through the kinematic chain, d e = J(q_all) E(q), with J the sensitivity of
  the HTM product - for an angular error the cross product with its Abbe arm
  (Kidani eq. 2.10, Khan & Chen eq. 17), which depends on the *other* axes'
  positions. Two bases:

  - smooth: Legendre polynomials P_k(u), u = q mapped to [-1, 1] over the
    stroke; k from 1 (positioning, angular: the constant is an offset or a
    location error) or 2 (straightness: its linear part is a squareness,
    ISO 230-1 3.4.8), up to an order chosen in-fold by BIC; a table's tilt
    (a work-side carriage carrying no rotary axis) may also take its constant
    P_0, chosen the same way: one rotation of the table, its constant the
    squareness of its plane (ISO 230-1). A work-side carriage that carries the
    rotary axes turns them with the table and the work; under a target located
    at the set-up (an R-test's or a probed sphere) its tilt is read as
    e(q) - R_S(q) R_S(q_s)^T e(q_s) (ISO 10791-6), orders 1-2, with its constant
    part unless the turn is about the first carried rotary axis' direction. A
    tool-side carriage that carries the head's rotary axes turns them and the tool,
    which was located at the head's set-up: e(q) - R_T(q) R_T(q_s)^T e(q_t), the
    tool's direction alike (:func:`located_head_tilt`). Where the instrument measured
    the tool's direction, a work-side tilt's turn is read located with the work
    (:func:`located_turn`);
  - periodic: cos/sin of 2 pi q / lambda and its second harmonic, the period
    lambda searched from 2 to 50 mm (ball-screw pitch, rack, guideway waviness)
    by a weighted least-squares periodogram of the training readings.

* **Squareness** of the three axis pairs: location errors E_C0Y, E_B0Z, E_A0Z
  (Khan & Chen's eps_xy, eps_zx, eps_zy), one candidate each; under a target located
  at the set-up on a work side that turns, read located like a tilt (ISO 10791-6).
* **Rotary axes** (Khan & Chen eqs. 9-16, section 3): position-dependent errors
  E_XA ... E_CA of a rotary axis as Fourier series in its angle (harmonics 2-4;
  the first is the location errors'),
  and the axis' location errors (offsets of its centre line perpendicular to it,
  tilts, zero of its angle) as one candidate per rotary axis.
* **Cross-axis twist**: an error in the product of two axis positions (a twist
  of the travel plane that a rigid-body model with per-axis errors cannot
  express), on each TCP component.
* **Abbe offset**: the model's own orientation error times an unknown lever
  (tool or workpiece offset from the scales' line), e = eps x l.
"""
from __future__ import annotations

import hashlib

import numpy as np

from ..kinematics.machine import outer_zeros
from .base import Context, EffectFamily, along, normalised_stroke
from .setup_location import located_design, side_rotations
from .spectral import (direct_basis, frequency_grid, resolvable, strongest_frequencies,
                       weight_sums)

#: ISO 230-1 component letters of a linear axis' errors, by kind.
_KIND_COMPONENTS = {"positioning": "self", "straightness": "XYZ", "angular": "ABC"}
#: Legendre orders searched per smooth error (from its first order on), and the largest.
_ORDERS = 6
#: Legendre orders of a located tilt of a carriage that carries the rotary axes.
_LOCATED_ORDERS = 2
#: The largest squareness any machine tool has [rad]: 10 mm per metre of travel, a hundred
#: times a poorly built machine's (ISO 230-1 squareness errors are tens of urad).
LARGEST_SQUARENESS_RAD = 1e-2
_LARGEST_ORDER = 2 + _ORDERS - 1


def _legendre_columns(u, first: int, last: int):
    """P_first(u) .. P_last(u) as columns, by Bonnet's recurrence
    (k + 1) P_{k+1} = (2k + 1) u P_k - k P_{k-1}."""
    u = np.asarray(u, dtype=np.float64)
    columns = [np.ones_like(u), u]
    for k in range(1, last):
        columns.append(((2 * k + 1) * u * columns[k] - k * columns[k - 1]) / (k + 1))
    return np.column_stack(columns[first:last + 1])


def component_names(ctx: Context, kind: str) -> list[str]:
    """ISO names of every component error of this kind over the machine's linear axes.

    Parameters
    ----------
    ctx : Context
        The machine and readings (only axes that moved count).
    kind : {"positioning", "straightness", "angular"}
        The kind of component error.

    Returns
    -------
    list of str
        ISO 230-1 names, e.g. ``EXX`` / ``EYX, EZX`` / ``EAX, EBX, ECX`` per axis.
    """
    names = []
    for axis in ctx.linear_axes(moving=True):
        if kind == "positioning":
            names.append(f"E{axis}{axis}")
        elif kind == "straightness":
            names += [f"E{c}{axis}" for c in "XYZ" if c != axis]
        else:
            names += [f"E{c}{axis}" for c in "ABC"]
    return names


def moves_within_a_target(ctx: Context, axis: str) -> bool:
    """Whether ``axis`` moved while one target was read: each target (a probed sphere) reads
    from a zero of its own, which takes in whatever an axis' error is where that target
    stood, so an error growing with an axis that moved only between targets shows none of
    its growth.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings (``target_groups``: None for one).
    axis : str
        Axis letter.

    Returns
    -------
    bool
        True when its positions span a non-zero range within some target's readings.
    """
    groups = ctx.target_groups
    positions = ctx.variables.positions[axis]
    if groups is None:
        return bool(np.ptp(positions) > 0)
    return any(np.ptp(positions[groups == g]) > 0 for g in np.unique(groups))


def seen_through_located_turn(ctx: Context, axis: str) -> bool:
    """Whether an error of ``axis`` shows where the axis stood still while each target was
    read: each target was located at the set-up and the work turned while it was read, so
    the error's move where a target stood, constant over its readings, turns away from the
    located value with the work, (I - R_W(q) R_W(q_s)^T) e (ISO 10791-6); it is told from a
    line offset of the turning axis (the same circle for one constant e) only when the axis
    stood elsewhere for another target.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings (``target_groups``: None for one).
    axis : str
        A linear axis' letter.

    Returns
    -------
    bool
        True when the readings are located, a work-side rotary axis turned within some
        target's readings and ``axis`` stood at more than one position over the readings.
    """
    machine = ctx.machine
    if setup_rows(ctx) is None or not np.ptp(ctx.variables.positions[axis]) > 0:
        return False
    return any(machine.axes[a].is_rotary and moves_within_a_target(ctx, a)
               for a in machine.workpiece_branch)


def carries_rotary(machine, axis: str) -> bool:
    """Whether ``axis`` carries a rotary axis on its branch of the chain.

    Parameters
    ----------
    machine : MachineDescription
        The machine (its workpiece and tool branches, from the bed outwards).
    axis : str
        A linear axis' letter.

    Returns
    -------
    bool
        True when an axis further out on the same branch is rotary.
    """
    for branch in (machine.workpiece_branch, machine.tool_branch):
        if axis in branch:
            return any(machine.axes[a].is_rotary for a in branch[branch.index(axis) + 1:])
    return False


def turns_about_carried_rotary(machine, variant: str) -> bool:
    """Whether the angular error ``variant`` of a carriage turns about the direction of the
    first rotary axis the carriage carries: a constant turn of it is that axis' zero and
    line offset (ISO 230-7 location errors), offered with the tilt at order 1 only unless
    the tool's direction was located with the work (:meth:`ComponentError.settings`).

    Parameters
    ----------
    machine : MachineDescription
        The machine (branches from the bed outwards).
    variant : str
        An angular error, e.g. ``EBX``.

    Returns
    -------
    bool
        True when the first rotary axis outward of the carriage turns about the same
        direction (linear axes between them do not turn it).
    """
    for branch in (machine.workpiece_branch, machine.tool_branch):
        if variant[2] in branch:
            for axis in branch[branch.index(variant[2]) + 1:]:
                if machine.axes[axis].is_rotary:
                    return machine.axes[axis].direction == "ABC".index(variant[1])
    return False


def located_tilt_seen(ctx: Context) -> bool:
    """Whether the work side holds a rotary axis that moved: then what was located at the
    set-up (the sphere, the part) turns with it, and a tilt's value there shows.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings.

    Returns
    -------
    bool
        True when a rotary axis of the workpiece branch moved over the readings.
    """
    machine = ctx.machine
    return any(machine.axes[a].is_rotary and ctx.moves(a) for a in machine.workpiece_branch)


def head_turned(ctx: Context) -> bool:
    """Whether the tool side holds a rotary axis that moved over the readings (the head
    turned): the tool-side counterpart of :func:`located_tilt_seen`.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings.

    Returns
    -------
    bool
        True when a rotary axis of the tool branch moved over the readings.
    """
    machine = ctx.machine
    return any(machine.axes[a].is_rotary and ctx.moves(a) for a in machine.tool_branch)


#: How close [rad] a rotary command must be to its set-up angle for a reading to be taken at
#: the set-up pose (commands written in degrees to a few decimals).
_AT_SETUP_RAD = 1e-5


def _at_setup(ctx: Context, branch) -> np.ndarray:
    """(N,) whether every rotary axis of ``branch`` stands at its set-up angle, modulo a
    full turn (within :data:`_AT_SETUP_RAD`)."""
    machine = ctx.machine
    at_setup = np.ones(ctx.n, dtype=bool)
    for axis in branch:
        if machine.axes[axis].is_rotary:
            turn = ctx.variables.positions[axis] - machine.setup_angle(axis)
            wrapped = np.angle(np.exp(1j * turn))    # an angle modulo a full turn
            at_setup &= np.abs(wrapped) < _AT_SETUP_RAD
    return at_setup


def _turned_from_setup(ctx: Context, side: str, then: np.ndarray) -> np.ndarray:
    """(N, 3, P) R_S(q) R_S(q_s)^T v: a value v at the set-up - one (3, P) or each
    reading's own (N, 3, P) - turning with the side's rotary axes since (ISO 10791-6)."""
    turned, at_setup = side_rotations(ctx, side)
    if then.ndim == 2:
        return np.einsum("nij,jk,kp->nip", turned, at_setup.T, then)
    return np.einsum("nij,jk,nkp->nip", turned, at_setup.T, then)


def setup_rows(ctx: Context) -> np.ndarray | None:
    """(N,) for each reading, the first reading of its target taken at the set-up pose
    (every work-side rotary axis at its set-up angle, modulo a turn): where the target was
    located. None when a target has no reading there.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings.

    Returns
    -------
    ndarray of intp, shape (N,), or None
        Row index of each reading's set-up reading.
    """
    key = "tilt_setup_rows"
    if not ctx.located_readings:
        return None     # a CNC's own commands: nothing was located among them
    if key not in ctx.cache:
        at_setup = _at_setup(ctx, ctx.machine.workpiece_branch)
        groups = ctx.target_groups
        groups = np.zeros(ctx.n, dtype=np.intp) if groups is None else groups
        rows = np.empty(ctx.n, dtype=np.intp)
        found = True
        for g in np.unique(groups):
            member = groups == g
            first = np.flatnonzero(member & at_setup)
            if first.size == 0:
                found = False
                break
            rows[member] = first[0]
        ctx.cache[key] = rows if found else None
    return ctx.cache[key]


def located_tilt(ctx: Context, design: np.ndarray) -> np.ndarray:
    """(N, 3, P) a work-side tilt's design as a target located at the set-up reads it:
    e(q) - R_S(q) R_S(q_s)^T e(q_s), e(q_s) the tilt's move of the same target at the
    reading where it was located (ISO 10791-6 set-up).

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings (:func:`setup_rows` not None).
    design : ndarray, shape (N, 3, P)
        The tilt's move of the target per unit coefficient [m per unit], bed frame.

    Returns
    -------
    ndarray, shape (N, 3, P)
        [m per unit], bed frame.
    """
    # ISO 10791-6: the value where the target was located turns with the work.
    return design - _turned_from_setup(ctx, "work", design[setup_rows(ctx)])


def lever_components(variant: str) -> str:
    """The bed's directions across a tilt's axis, along which its pivot's lever moves the
    carriage: ``xz`` for ``EBY``.

    Parameters
    ----------
    variant : str
        An angular error, e.g. ``EBY``.

    Returns
    -------
    str
        Two of ``x``, ``y``, ``z``.
    """
    return "".join(c for c in "xyz" if c != "xyz"["ABC".index(variant[1])])


def lever_names(variant: str) -> list[str]:
    """Parameter names of a located tilt's lever, e.g. ``["lever_x", "lever_z"]`` [m].

    Parameters
    ----------
    variant : str
        An angular error, e.g. ``EBY``.

    Returns
    -------
    list of str
        One per direction of :func:`lever_components`.
    """
    return [f"lever_{c}" for c in lever_components(variant)]


def machine_reach(ctx: Context) -> float:
    """[m] the farthest a lever of the machine's own can reach: its linear strokes end to
    end, the tool's length and half a metre of structure. A fitted arm or pivot beyond it
    is no machine's: a vanishing tilt divided into another error's share."""
    return sum(high - low for low, high in (ctx.machine.axes[a].stroke
                                            for a in ctx.linear_axes())) + \
        float(np.linalg.norm(ctx.machine.tool)) + 0.5


def lever_slope_names(variant: str) -> list[str]:
    """Parameter names of a located tilt's lever slope, e.g. ``["lever_slope_x",
    "lever_slope_z"]`` [m]: the pivot's move P1 (e_k x p) at the stroke's end."""
    return [f"lever_slope_{c}" for c in lever_components(variant)]


def located_lever_slope(ctx: Context, variant: str, slope: np.ndarray) -> np.ndarray:
    """(N, 3, 2) the reading's change per metre of a located tilt's lever slope: about a
    pivot p the tilt's slope P1 L1(u) moves what the carriage carries by
    -P1 L1(u) (e_k x p), growing along the carriage's travel; the target located at the
    set-up took in that move there, turning with the work since (ISO 10791-6):
    -(L1(u) I - R_S(q) R_S(q_s)^T L1(u_s)) along the two directions across e_k; on a batch
    with no reading at the set-up (a CNC's commands), -L1(u) I.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings (:func:`setup_rows` not None).
    variant : str
        An angular error of a work-side carriage that carries the rotary axes.
    slope : ndarray, shape (N,)
        L1(u) at the readings, the carriage's command normalised over its stroke.

    Returns
    -------
    ndarray, shape (N, 3, 2)
        [m per m of the lever slope], bed frame.
    """
    moved = lever_slope_move(ctx, variant, slope)
    # A CNC's own commands locate nothing: the move as the machine makes it, from the
    # stroke's middle (where L1 is zero).
    return moved if setup_rows(ctx) is None else located_tilt(ctx, moved)


def lever_slope_move(ctx: Context, variant: str, slope: np.ndarray) -> np.ndarray:
    """(N, 3, 2) the move -P1 L1(u) (e_k x p) per metre of a tilt's lever slope, as the
    machine makes it: about a pivot p off the carriage's origin, the tilt's slope turns the
    carriage, and all it carries, about p rather than about the origin (ISO 230-1).

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings.
    variant : str
        An angular error of a work-side carriage.
    slope : ndarray, shape (N,)
        L1(u) at the readings, the carriage's command normalised over its stroke.

    Returns
    -------
    ndarray, shape (N, 3, 2)
        [m per m of the lever slope], bed frame, along the two directions across e_k.
    """
    across = ["xyz".index(c) for c in lever_components(variant)]
    moved = np.zeros((ctx.n, 3, 2))
    moved[:, across, [0, 1]] = -slope[:, None]     # -L1(u) (e_k x p), component-wise
    return moved


def located_lever(ctx: Context, variant: str) -> np.ndarray:
    """(N, 3, 2) the reading's change per metre of a located tilt's lever: a tilt eps(q)
    about a pivot p off the carriage's origin turns what it carries about p, which moves it
    by v = -P0 (e_k x p) more than a turn about the origin does (x -> p + R (x - p); ISO
    230-1: an angular error about a point off the reference point moves it by the lever);
    v is taken across the tilt's axis e_k. A target located at the set-up took that move
    in there, and it turns with the carried rotary axes, so the reading (the tool relative
    to the work) changes by -(I - R_S(q) R_S(q_s)^T) v (ISO 10791-6): the located set-up
    error's shape, of the opposite sign, along the two directions across.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings (:func:`setup_rows` not None).
    variant : str
        An angular error of a work-side carriage that carries the rotary axes, e.g. ``EBY``.

    Returns
    -------
    ndarray, shape (N, 3, 2)
        [m per m of the carriage's move v], bed frame.
    """
    across = ["xyz".index(c) for c in lever_components(variant)]
    return -located_design(ctx, "work")[:, :, across]


def lever_line_offsets(machine, variant: str, lever: dict[str, float]) -> dict[str, float]:
    """A located tilt's lever as the offsets of the rotary lines its carriage carries: a
    translation v of the carriage moves each carried line by v (ISO 230-7 location errors,
    the body turning about the moved line), and the readings alike on any poses, since
    (I - R_1 R_2) v = (I - R_1) v + R_1 (I - R_2) v; each line keeps v's components across
    its own direction.

    Parameters
    ----------
    machine : MachineDescription
        The machine (branches from the bed outwards).
    variant : str
        The tilt, an angular error of a carriage that carries rotary axes, e.g. ``EBY``.
    lever : dict of str to float
        The lever's components, ``{"lever_x": ..., "lever_z": ...}``: the carriage's move
        [m], bed frame.

    Returns
    -------
    dict of str to float
        ISO 230-7 line offsets [m], e.g. ``{"EZ0A": lever_z, "EX0C": lever_x}``; empty when
        the carriage carries no rotary axis.
    """
    branch = next((b for b in (machine.workpiece_branch, machine.tool_branch)
                   if variant[2] in b), ())
    carried = [a for a in branch[branch.index(variant[2]) + 1:] if machine.axes[a].is_rotary] \
        if branch else []
    out = {}
    for axis in carried:
        for component in lever_components(variant):
            if "xyz".index(component) != machine.axes[axis].direction:
                out[f"E{component.upper()}0{axis}"] = float(lever[f"lever_{component}"])
    return out


#: The ``located`` value of a tilt's setting on the tool side: the tool was located (its
#: length set) at the head's set-up pose, and that location turns with the head.
HEAD = "head"


#: The one setting of a still carriage's tilt: its constant turn, located (P0 alone).
STILL_TURN = {"order": 0, "constant": True, "located": True}


def still_turns(ctx: Context) -> list[str]:
    """The constant turns of work-side carriages that stood still and carry the rotary
    axes, about the first carried rotary axis' direction (``EAX`` for an X that carries A),
    where a target was located at the set-up and the work turned.

    Such a carriage's tilt is one constant turn over these readings. It turns the rotary
    axes, the table and the work about the carriage's origin (ISO 230-1): the carried
    axis' zero and the offset of its line by the turn's lever (ISO 230-7). A sphere located
    at the set-up by a translation reads the offset's circle, and an instrument that
    located the tool's direction with the work reads the turn itself, turning with the
    work (ISO 10791-6), which no line offset makes.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings.

    Returns
    -------
    list of str
        Angular error names (``EAX`` ...), each offered at :data:`STILL_TURN` only.
    """
    machine = ctx.machine
    if not located_tilt_seen(ctx) or setup_rows(ctx) is None:
        return []
    return [f"E{c}{axis}" for axis in machine.workpiece_branch
            if not machine.axes[axis].is_rotary and not ctx.moves(axis) and
            carries_rotary(machine, axis) for c in "ABC"
            if turns_about_carried_rotary(machine, f"E{c}{axis}")]


def under_rotary(machine, axis: str) -> bool:
    """Whether a rotary axis lies between the bed and ``axis`` on its branch: then the
    carriage's frame turns with it, and a move fixed in the carriage is none in the bed's."""
    branch = next(b for b in (machine.workpiece_branch, machine.tool_branch) if axis in b)
    return any(machine.axes[a].is_rotary for a in branch[:branch.index(axis)])


def located_turns(ctx: Context) -> bool:
    """Whether the readings were located at a set-up and a rotary axis turned them from it:
    the work side's (the target located at its set-up reading) or the head's (the tool
    located at the head's). Then every effect's move at the set-up went into one located
    value, their sum, which turns with the rotary axes (ISO 10791-6): the readings show
    that sum's circle, not each effect's.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings.

    Returns
    -------
    bool
        True when :func:`located_tilt_seen` with :func:`setup_rows`, or
        :func:`head_turned` with :func:`head_setup_row`.
    """
    if located_tilt_seen(ctx) and setup_rows(ctx) is not None:
        return True
    return head_turned(ctx) and head_setup_row(ctx) is not None


def carries_head(machine, axis: str) -> bool:
    """Whether ``axis`` is a tool-side carriage that carries rotary axes of the head.

    Parameters
    ----------
    machine : MachineDescription
        The machine (branches from the bed outwards).
    axis : str
        A linear axis' letter.

    Returns
    -------
    bool
        True when ``axis`` is on the tool branch with a rotary axis further out on it.
    """
    return axis in machine.tool_branch and carries_rotary(machine, axis)


def head_setup_row(ctx: Context) -> int | None:
    """The first reading taken with every rotary axis of the head at its set-up angle (modulo
    a turn): where the tool was located - its length and position set in its own frame - by
    the instrument (ISO 10791-6 set-up). None when the head never was there.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings.

    Returns
    -------
    int or None
        Row index of that reading.
    """
    key = "tilt_head_setup_row"
    if not ctx.located_readings:
        return None     # a CNC's own commands: no tool was located among them
    if key not in ctx.cache:
        first = np.flatnonzero(_at_setup(ctx, ctx.machine.tool_branch))
        ctx.cache[key] = int(first[0]) if first.size else None
    return ctx.cache[key]


def head_located_settings(ctx: Context, variant: str) -> list[dict]:
    """The located settings of a tilt of a carriage that carries the head's rotary axes:
    ``{"order": k, "located": "head"}``, k = 1, 2, and with the constant part P0 unless the
    turn is about the first carried rotary axis' direction; none when the head did not turn
    or never stood at its set-up pose.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings.
    variant : str
        An angular error of a tool-side carriage that carries the head (e.g. ``EAZ``).

    Returns
    -------
    list of dict
        The settings (:func:`located_head_tilt` makes their designs).
    """
    machine = ctx.machine
    if not head_turned(ctx) or head_setup_row(ctx) is None:
        return []
    # The carriage turns the head, its rotary lines and the tool about its pivot; the tool
    # located at the head's set-up took the tilt's move there into where the tool is
    # believed to be, and that belief turns with the head (ISO 10791-6): one rotation, its
    # value at the set-up tied to its shape. Low orders only, as on the work side. A
    # constant turn about the first carried rotary axis' direction is that axis' zero and
    # line offset (ISO 230-7), not offered as the tilt's.
    located = [{"order": k, "located": HEAD} for k in range(1, _LOCATED_ORDERS + 1)]
    if turns_about_carried_rotary(machine, variant):
        return located
    return located + [{"order": k, "constant": True, "located": HEAD}
                      for k in range(1, _LOCATED_ORDERS + 1)]


def located_head_tilt(ctx: Context, design: np.ndarray) -> np.ndarray:
    """(N, 3, P) a tilt of a carriage carrying the head as the located instruments read it:
    the tool located at the head's set-up (row t), then the target at the work's (rows s),

        f(q) = e(q) - R_T(q) R_T(q_s)^T e(q_t),   f(q) - R_W(q) R_W(q_s)^T f(q_s)

    (ISO 10791-6 set-up; R_T, R_W the tool's and the work's end-frame rotations). The second
    step only where the work side turns; else it is a constant, which the datum takes.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings (:func:`head_setup_row` not None).
    design : ndarray, shape (N, 3, P)
        The tilt's move of the tool tip per unit coefficient [m per unit], bed frame.

    Returns
    -------
    ndarray, shape (N, 3, P)
        [m per unit], bed frame.
    """
    # e(q) - R_T(q) R_T(q_s)^T e(q_t): the tool's believed position turns with the head.
    located = design - _turned_from_setup(ctx, "tool", design[head_setup_row(ctx)])
    if located_tilt_seen(ctx) and setup_rows(ctx) is not None:
        located = located_tilt(ctx, located)     # then the target, located with the work
    return located


def located_head_turn(ctx: Context, turn: np.ndarray) -> np.ndarray:
    """(N, 3, P) the tool direction's turn of a tilt of a carriage carrying the head, as an
    instrument that located the tool's direction at the head's set-up reads it:
    w(q) - R_T(q) R_T(q_s)^T w(q_t) (ISO 10791-6 set-up). Its part along the tool axis is
    no direction change (the instrument sees the part across it): R_T(q) R_T(q_s)^T carries
    the set-up's tool axis onto the reading's, so the two parts stay apart.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings (:func:`head_setup_row` not None).
    turn : ndarray, shape (N, 3, P)
        The tilt's turn of the tool per unit coefficient [rad per unit], bed frame.

    Returns
    -------
    ndarray, shape (N, 3, P)
        [rad per unit], bed frame.
    """
    # w(q) - R_T(q) R_T(q_s)^T w(q_t) (ISO 10791-6): the located direction turns with the head.
    return turn - _turned_from_setup(ctx, "tool", turn[head_setup_row(ctx)])


def located_turn(ctx: Context, turn: np.ndarray) -> np.ndarray:
    """(N, 3, P) a work-side error's turn of the tool as a two-sphere instrument located at
    the set-up with the work reads it: the direction's change du(q_s) = w(q_s) x u(q_s) there
    went into the located spheres and turns with the work,

        w(q) - u(q) x R_W(q) R_W(q_s)^T du(q_s)         (ISO 10791-6 set-up)

    (its part across the tool axis u is what the instrument sees; the same reading as
    :meth:`KinematicModel.located_sensitivities` gives a rotary line's error).

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings (:func:`setup_rows` not None).
    turn : ndarray, shape (N, 3, P)
        The error's turn of the tool relative to the work per unit coefficient [rad per
        unit], bed frame.

    Returns
    -------
    ndarray, shape (N, 3, P)
        [rad per unit], bed frame.
    """
    rows = setup_rows(ctx)
    axis = ctx.tool_axis()
    then = np.cross(turn[rows], axis[rows][:, :, None], axisa=1, axisb=1, axisc=1)
    moved = _turned_from_setup(ctx, "work", then)     # ISO 10791-6: turns with the work
    return turn - np.cross(axis[:, :, None], moved, axisa=1, axisb=1, axisc=1)


class ComponentError(EffectFamily):
    """Positioning / straightness / angular error of a linear axis, smooth or periodic.

    Parameters
    ----------
    kind : {"positioning", "straightness", "angular"}
        Which component errors the family holds.
    periodic : bool
        Periodic (cos/sin of 2 pi q / lambda and its second harmonic) instead of smooth
        (Legendre polynomials).
    """

    group = "geometric"
    reference = "ISO 230-1; Kidani eqs. 2.6-2.12; Khan & Chen eqs. 8, 17"

    def __init__(self, kind: str, periodic: bool) -> None:
        self.kind = kind
        self.periodic = periodic
        self.continuous_setting = "period_m" if periodic else None
        self.nested_settings = not periodic   # Legendre P_first .. P_order
        # A rotation acting through a lever is a more elaborate hypothesis than a
        # translation: when the data cannot tell them apart (a constant arm), the
        # translation is named.
        self.complexity = (3 if periodic else 2) + (kind == "angular")
        self.name = f"{kind}_periodic" if periodic else kind
        what = {"positioning": "positioning error", "straightness": "straightness error",
                "angular": "angular error (pitch, yaw or roll)"}[kind]
        self.summary = (f"a periodic {what} of an axis (ball-screw pitch, rack or guideway "
                        "waviness)" if periodic else f"a {what} of an axis that changes "
                        "smoothly along its travel")

    def variants(self, ctx: Context) -> list[str]:
        """The component errors of this kind of every linear axis that moved.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            ISO 230-1 names (``EXX``, ``EYX`` ...); for the smooth angular kind also the
            turns of still carriages (:func:`still_turns`).
        """
        names = component_names(ctx, self.kind)
        if self.kind == "angular" and not self.periodic:
            names += still_turns(ctx)
        return names

    def settings(self, ctx: Context, variant: str) -> list[dict]:
        """Periods searched (periodic) or Legendre orders (smooth).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).

        Returns
        -------
        list of dict
            ``{"period_m": lambda}`` [m] on a resolvable frequency grid, or ``{"order": k}``;
            a table's tilt also ``{"order": k, "constant": True}`` (P1 .. Pk and P0) and
            ``{"order": 1, "constant": True, "lever_slope": True}`` (about a pivot off its
            origin, :func:`lever_slope_move`); the
            tilt of a work-side carriage that carries rotary axes, under a target located
            at the set-up, also ``{"order": k, "located": True}`` with or without the
            constant (:func:`located_tilt`), k = 1, 2; the tilt of a tool-side carriage that
            carries the head's rotary axes ``{"order": k, "located": "head"}`` alike
            (:func:`head_located_settings`).
        """
        if self.kind == "angular" and not self.periodic and not ctx.moves(variant[2]) and \
                variant in still_turns(ctx):
            # A carriage that stood still: its tilt is one constant turn (still_turns).
            return [dict(STILL_TURN)]
        if self.periodic:
            low, high = ctx.machine.axes[variant[2]].stroke
            # Frequencies a quarter cycle apart over the stroke: no peak falls between;
            # none the readings' positions would alias (a raster's few lines).
            grid = resolvable(frequency_grid(high - low), ctx.variables.positions[variant[2]])
            return [{"period_m": float(1.0 / f)} for f in grid]
        first = 2 if self.kind == "straightness" else 1
        orders = [{"order": k} for k in range(first, first + _ORDERS)]
        if self.kind == "angular" and carries_head(ctx.machine, variant[2]):
            return orders + head_located_settings(ctx, variant)
        if self.kind != "angular" or variant[2] not in ctx.machine.workpiece_branch:
            return orders
        if carries_rotary(ctx.machine, variant[2]):
            if not located_tilt_seen(ctx) or setup_rows(ctx) is None:
                return orders
            # A carriage that carries the rotary axes turns them, the table and the work
            # about its pivot; the target located at the set-up took in the tilt there,
            # which then turns with the rotary axes (ISO 10791-6): one rotation, read as
            # the located instrument reads it (its value at the set-up tied to its shape).
            # Smooth and of low order only: a located tilt of higher order, on a sweep where
            # the carriage follows one rotary axis, would stand in for that axis' own errors.
            located = [{"order": k, "located": True} for k in range(1, _LOCATED_ORDERS + 1)]
            if turns_about_carried_rotary(ctx.machine, variant) and \
                    not self._turn_located(ctx, variant):
                # A constant turn about the direction of the first rotary axis carried is that
                # axis' zero and line offset (rotary_location, ISO 230-7): no lever and no
                # higher order with it. But the tilt's mean over the stroke is no part of its
                # Legendre slope, and a tilt that grows from its command's zero rather than
                # from the stroke's middle needs it: order 1 only (separability._carried_zero).
                # Its slope still moves the carried lines about a pivot off the origin.
                return orders + located + [{"order": 1, "constant": True, "located": True},
                                           {"order": 1, "located": True, "lever_slope": True}]
            # Where the tool's direction was located with the work, it parts the carriage's
            # turn from the carried line's tilt (into which the line family folds that zero):
            # the zero turns the work at the set-up too, so the located direction reads
            # -[eps x u - R_W(q) R_W(q_s)^T (eps x u)], the line's tilt -(eps - R_W(q)
            # R_W(q_s)^T eps) x u (located_turn): the tilt is offered as any other there.
            # Its pivot, off the carriage's origin, moves what the carriage carries by the
            # constant part's lever (located_lever): offered with the constant part, at
            # order 1 only (at order 2 it led the first step where a squareness and a line
            # offset were the truth).
            return orders + located + \
                [{"order": 1, "constant": True, "located": True, "lever": True},
                 {"order": 1, "constant": True, "located": True, "lever": True,
                  "lever_slope": True}] + \
                [{"order": k, "constant": True, "located": True}
                 for k in range(1, _LOCATED_ORDERS + 1)]
        # A table's tilt with a constant part turns the table, and the work on it, about
        # its pivot: the constant is the squareness of the tilt's plane (ISO 230-1), booked
        # with the tilt as one rotation rather than as a pair of squareness slopes. On a
        # carriage that carries rotary axes the constant turn is their lines' tilts
        # (rotary_location) and its carried axes' squareness: candidates of their own. On
        # the tool side a constant turn of a carriage differs from the table's own tilt
        # about the same direction by the pivot alone, which this family does not fit, so
        # it could stand in for it: there the squareness family holds a constant turn.
        constant = [{"order": k, "constant": True} for k in range(first, first + _ORDERS)]
        if under_rotary(ctx.machine, variant[2]):
            return orders + constant
        # About a pivot off the table's origin the tilt's slope also moves the table by
        # -P1 L1(u) (e_k x p): a positioning and a straightness slope of its own axis,
        # which a survey made about another pivot reads with the tilt. Order 1 only, with
        # the constant part: the pivot is the one thing it adds. In the bed's frame only
        # where no rotary axis below turns the table's.
        return orders + constant + [{"order": 1, "constant": True, "lever_slope": True}]

    def fit_problems(self, ctx: Context, variant: str, setting: dict, coefficients
                     ) -> list[str]:
        """A pivot beyond the machine's reach is no tilt's: about a pivot p the lever is
        -P0 (e_k x p) and its slope -P1 (e_k x p), so the pivot lies |lever| / |P0| (or
        |lever slope| / |P1|) across the axis; a fit that puts it farther than
        :func:`machine_reach` makes a line offset or a straightness of the tilt's lever,
        dividing by a turn that is not the carriage's.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).
        coefficients : sequence of float, length P
            The fitted coefficients, SI (P0, P1 [rad], the lever and its slope [m] ...).

        Returns
        -------
        list of str
            One sentence per part (the lever, its slope) whose pivot lies beyond the
            machine's reach, else none.
        """
        parts = [(part, names, turn) for key, part, names, turn in (
            ("lever", "lever", lever_names, "P0"),
            ("lever_slope", "lever's slope", lever_slope_names, "P1")) if setting.get(key)]
        if not parts:
            return []
        fitted = dict(zip(self.parameter_names(variant, setting),
                          np.asarray(coefficients, dtype=np.float64)))
        reach = machine_reach(ctx)
        out = []
        for part, names_of, turn in parts:
            names = names_of(variant)
            moved = float(np.hypot(*(fitted[n] for n in names)))
            if moved <= reach * abs(fitted[turn]):
                continue
            pivot = moved / abs(fitted[turn]) if fitted[turn] else float("inf")
            out.append(f"the pivot its {part} puts {pivot:.3g} m from the {variant[2]} "
                       f"carriage's origin is beyond the machine's reach ({reach:.2f} m): "
                       "not a tilt about a pivot, another error's share divided by a "
                       "vanishing turn")
        return out

    def nested_columns(self, variant: str, setting: dict, largest: dict) -> list[int] | None:
        """Columns of the largest setting's design: P1 .. Pk, then P0 for a constant part.

        Parameters
        ----------
        variant : str
            The variant.
        setting : dict
            ``{"order": k}``, with ``"constant": True`` for a tilt with a constant part.
        largest : dict
            The last setting (the highest order, with the constant part on an angular
            error).

        Returns
        -------
        list of int or None
            Column indices into the largest design (None for a periodic error).
        """
        if self.periodic:
            return None
        first = 2 if self.kind == "straightness" else 1
        if bool(setting.get("located")) != bool(largest.get("located")):
            return None     # a located tilt's columns are not the plain ones'
        if setting.get("lever_slope") or largest.get("lever_slope"):
            return None     # a lever's slope columns are made on their own
        if setting.get("lever") and not largest.get("lever"):
            return None     # nor are a lever's
        if setting["order"] > largest["order"] or \
                (setting.get("constant") and not largest.get("constant")):
            return None     # the largest holds no such column
        columns = list(range(setting["order"] - first + 1))
        if setting.get("constant"):
            columns.append(largest["order"] - first + 1)
        if setting.get("lever"):
            # the lever's two columns follow the largest setting's P0
            columns += [largest["order"] - first + 2, largest["order"] - first + 3]
        return columns

    def parameter_names(self, variant: str, setting: dict) -> list[str]:
        """Harmonic or Legendre coefficients.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``cos1, sin1, cos2, sin2`` or ``P<k>``; each in the error's unit, [m] (positioning,
            straightness) or [rad] (angular).
        """
        if self.periodic:
            return ["cos1", "sin1", "cos2", "sin2"]
        first = 2 if self.kind == "straightness" else 1
        return [f"P{k}" for k in range(first, setting["order"] + 1)] + \
            (["P0"] if setting.get("constant") else []) + \
            (lever_names(variant) if setting.get("lever") else []) + \
            (lever_slope_names(variant) if setting.get("lever_slope") else [])

    def _basis(self, q, u, setting):
        if self.periodic:
            phase = 2.0 * np.pi * np.asarray(q, dtype=np.float64) / setting["period_m"]
            basis = np.empty((phase.size, 4))
            basis[:, 0] = np.cos(phase)
            basis[:, 1] = np.sin(phase)
            # The second harmonic from the first (double-angle identities: no more trig).
            basis[:, 2] = 2.0 * basis[:, 0] ** 2 - 1.0
            basis[:, 3] = 2.0 * basis[:, 0] * basis[:, 1]
            return basis
        first = 2 if self.kind == "straightness" else 1
        # Order 0 (a still carriage's turn) holds the constant part alone.
        columns = _legendre_columns(u, first, setting["order"]) if setting["order"] >= first \
            else np.zeros((np.asarray(u).size, 0))
        if setting.get("constant"):
            columns = np.column_stack([columns, np.ones(columns.shape[0])])
        return columns

    def design(self, ctx: Context, variant: str, setting: dict):
        """(N, 3, P) TCP error per unit coefficient: the error's sensitivity along its basis.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, P)
            [m per m] or [m per rad] of coefficient.
        """
        if setting.get("located") == HEAD:
            return self._head_located_design(ctx, variant, setting)
        if setting.get("located"):
            # e(q) - R_S(q) R_S(q_s)^T e(q_s): the tilt, and its value at the set-up located
            # into the work and turning with it (ISO 10791-6); the datum takes the rest.
            plain = along(*self._plain_separable(ctx, variant, setting))
            # Readings with no target at the set-up pose (a CNC's own commands) get the
            # tilt as the machine makes it: the located part is the instrument's. The lever
            # is the machine's own (its carried lines' offsets, referred to the machine's
            # set-up pose as a rotary line is): the same on any batch of commands.
            tilt = plain if setup_rows(ctx) is None else located_tilt(ctx, plain)
            if setting.get("lever"):
                tilt = np.concatenate([tilt, located_lever(ctx, variant)], axis=2)
            if setting.get("lever_slope"):
                # L1(u) = u: the command normalised over the stroke.
                slope = ctx.normalised_position(variant[2])
                tilt = np.concatenate([tilt, located_lever_slope(ctx, variant, slope)], axis=2)
            return tilt
        plain = along(*self._plain_separable(ctx, variant, setting))
        if setting.get("lever_slope"):
            # A table's tilt about a pivot off its origin (no rotary axis carried).
            slope = lever_slope_move(ctx, variant, ctx.normalised_position(variant[2]))
            return np.concatenate([plain, slope], axis=2)
        return plain

    def _head_located_design(self, ctx: Context, variant: str, setting: dict):
        """(N, 3, P) the tilt of a carriage carrying the head, the tool located at the head's
        set-up (:func:`located_head_tilt`); the tilt as the machine makes it at readings
        where the head never stood at its set-up (a CNC's own commands)."""
        plain = along(*self._plain_separable(ctx, variant, setting))
        return plain if head_setup_row(ctx) is None else located_head_tilt(ctx, plain)

    def separable_design(self, ctx: Context, variant: str, setting: dict):
        """The error's sensitivity and its basis columns (shared between the axis' errors).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        tuple of ndarray
            (sensitivity (N, 3) [m per error unit], basis (N, P) dimensionless).
        """
        if setting.get("located") or self._turn_located(ctx, variant):
            return None     # the located set-up error is no product of one sensitivity
        if setting.get("lever_slope"):
            return None     # nor is a pivot's move, along two directions of its own
        return self._plain_separable(ctx, variant, setting)

    def _turn_located(self, ctx: Context, variant: str) -> bool:
        """Whether the instrument measured the tool's direction and located it with the work
        at the set-up: a work-side tilt's turn is then read as located (:func:`located_turn`)."""
        return self.kind == "angular" and ctx.direction_measured and \
            variant[2] in ctx.machine.workpiece_branch and setup_rows(ctx) is not None

    def _plain_separable(self, ctx: Context, variant: str, setting: dict):
        """(sensitivity (N, 3), basis (N, P)) of the error as the machine makes it (no set-up
        located into it): see :meth:`separable_design`."""
        axis = variant[2]
        if self.periodic:
            # Every periodic error of an axis has the same harmonics at one period.
            basis = ctx.shared_columns(
                ("harmonics", axis, float(setting["period_m"])),
                lambda: self._basis(ctx.variables.positions[axis], None, setting))
        elif setting["order"] > _LARGEST_ORDER:
            basis = self._basis(ctx.variables.positions[axis], ctx.normalised_position(axis),
                                setting)
        else:
            # Every smooth error of an axis shares its Legendre columns: computed once.
            key = ("legendre", axis)
            if key not in ctx.cache:
                ctx.cache[key] = _legendre_columns(ctx.normalised_position(axis), 0,
                                                   _LARGEST_ORDER)
            first = 2 if self.kind == "straightness" else 1
            basis = ctx.cache[key][:, first:setting["order"] + 1]
            if setting.get("constant"):
                basis = np.column_stack([basis, ctx.cache[key][:, 0]])
        return ctx.jacobian(variant), basis

    def orientation_sensitivity(self, ctx: Context, variant: str, setting: dict):
        """The tool's turn per unit angular error; None for positioning and straightness.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3), or None
            [rad per rad], or None.
        """
        # Pitch, yaw and roll turn the tool; positioning and straightness do not.
        return ctx.orientation_jacobian(variant) if self.kind == "angular" else None

    def orientation_design(self, ctx: Context, variant: str, setting: dict):
        """(N, 3, P) the tool's turn per unit coefficient [rad per unit]: the tilt's turn
        along its basis, read as the instrument located the direction: with the tool at the
        head's set-up (:func:`located_head_turn`) or with the work (:func:`located_turn`,
        where the direction was measured); else the tilt's own turn.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, P), or None
            [rad per parameter unit], bed frame; None for positioning and straightness.
        """
        turn = self.orientation_sensitivity(ctx, variant, setting)
        if turn is None:
            return None
        turn = along(turn, self._plain_separable(ctx, variant, setting)[1])
        if setting.get("located") == HEAD:
            # The tool's direction located at the head's set-up too (two spheres).
            return turn if head_setup_row(ctx) is None else located_head_turn(ctx, turn)
        # The two spheres located at the set-up with the work: the direction's change there
        # turns with the work (ISO 10791-6).
        turn = located_turn(ctx, turn) if self._turn_located(ctx, variant) else turn
        width = 2 * bool(setting.get("lever")) + 2 * bool(setting.get("lever_slope"))
        if not width:
            return turn
        # The lever and its slope (translations) turn nothing.
        return np.concatenate([turn, np.zeros((ctx.n, 3, width))], axis=2)

    def motion_error(self, machine, variant: str, setting: dict, coefficients, q):
        """The error motion itself, E(q) [m or rad] at axis positions q: what a CNC's
        per-axis compensation table holds (not its effect at the TCP).

        Parameters
        ----------
        machine : MachineDescription
            The machine (the axis' stroke maps q to Legendre's domain).
        variant : str
            ISO name, e.g. ``ECX``.
        setting : dict
            The fitted setting.
        coefficients : sequence of float, length P
            Fitted coefficients [m] or [rad].
        q : array_like, shape (K,)
            Axis positions [m].

        Returns
        -------
        ndarray, shape (K,)
            E(q) [m] or [rad].
        """
        q = np.asarray(q, dtype=np.float64)
        basis = self._basis(q, normalised_stroke(machine, variant[2], q), setting)
        # The located set-up error (last, with ``located``) is no motion of the axis.
        return basis @ np.asarray(coefficients, dtype=np.float64)[:basis.shape[1]]

    def pivot_motion_errors(self, kinematics, variant: str, setting: dict, coefficients,
                            q) -> dict[str, np.ndarray]:
        """What a CNC's per-axis tables hold of a table's tilt about a pivot off its origin
        (``lever_slope`` without ``located``): the pivot's move -P1 L1(u) (e_k x p) as the
        positioning and straightness error motions of the tilted axis that make it at the
        TCP (each translation's sensitivity is sign R e_C, :meth:`KinematicModel.
        error_frames`, constant on a table no rotary axis turns); nothing for another.

        Parameters
        ----------
        kinematics : KinematicModel
            The machine's chain (the translations' frames).
        variant : str
            ISO name, e.g. ``EBX``.
        setting : dict
            The fitted setting.
        coefficients : sequence of float, length P
            Fitted coefficients, in :meth:`parameter_names` order [rad] and [m].
        q : array_like, shape (K,)
            Positions of the variant's axis [m].

        Returns
        -------
        dict of str to ndarray, shape (K,)
            ISO motion error name (``EXX``, ``EZX`` ...) -> values [m].

        Raises
        ------
        ValueError
            A direction of the pivot's move that no translation of the axis makes alone
            (the axis' frame not along the bed's).
        """
        if not setting.get("lever_slope") or setting.get("located"):
            return {}
        machine = kinematics.machine
        axis = variant[2]
        slope = normalised_stroke(machine, axis, q)     # L1(u)
        fitted = dict(zip(self.parameter_names(variant, setting),
                          np.asarray(coefficients, dtype=np.float64)))
        middle = {a: np.full(1, 0.5 * sum(machine.axes[a].stroke)) for a in machine.axis_order}
        frames = kinematics.error_frames(middle)
        out: dict[str, np.ndarray] = {}
        for component, name in zip(lever_components(variant), lever_slope_names(variant)):
            row = "xyz".index(component)
            for motion in "XYZ":
                sign, rotation, _ = frames[f"E{motion}{axis}"]
                along = float(sign * rotation[0, row, "XYZ".index(motion)])
                if abs(along) > 1.0 - 1e-9:
                    out[f"E{motion}{axis}"] = -slope * fitted[name] / along
                    break
            else:
                raise ValueError(f"{variant}: no translation of the {axis} axis moves the TCP "
                                 f"along {component} alone; its pivot's slope has no table")
        return out

    def location_error(self, machine, variant: str, setting: dict,
                       coefficients) -> dict[str, float]:
        """What a CNC table's location block holds of it: a tilt's pivot lever, as the
        offsets of the rotary lines its carriage carries (:func:`lever_line_offsets`: the
        same move of the work on any poses); nothing for an effect without a lever (its
        error motion is all in the axis' table, :meth:`motion_error`).

        Parameters
        ----------
        machine : MachineDescription
            The machine (which rotary lines the carriage carries).
        variant : str
            ISO name, e.g. ``EBY``.
        setting : dict
            The fitted setting.
        coefficients : sequence of float, length P
            Fitted coefficients, in :meth:`parameter_names` order [m] or [rad].

        Returns
        -------
        dict of str to float
            ISO 230-7 line offsets [m], e.g. ``{"EZ0A": ...}``; empty without a lever.
        """
        if not setting.get("lever"):
            return {}
        fitted = dict(zip(self.parameter_names(variant, setting), coefficients))
        return lever_line_offsets(machine, variant, {n: fitted[n] for n in lever_names(variant)})

    @property
    def preselects(self) -> bool:
        return self.periodic    # by the periodogram

    def preselect(self, ctx, variant, settings, residual, mask, train):
        """The period by the periodogram of the training residual (periodic only; None for smooth).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        settings : list of dict
            Periods to choose from.
        residual : ndarray, shape (N, 3)
            Residual [m].
        mask : ndarray of bool, shape (N, 3)
            Components measured.
        train : ndarray of bool, shape (N,)
            Training readings.

        Returns
        -------
        dict or None
            The chosen setting, or None.
        """
        return self.preselect_folds(ctx, variant, settings, residual[None], mask,
                                    np.asarray(train)[None])[0]

    def preselect_folds(self, ctx, variant, settings, residuals, mask, trains):
        """The period per fold by a weighted periodogram of its training residual along the error's
        sensitivity (fundamental alone).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        settings : list of dict
            Periods to choose from.
        residuals : ndarray, shape (F, N, 3)
            Residual per fold [m].
        mask : ndarray of bool, shape (N, 3)
            Components measured.
        trains : ndarray of bool, shape (F, N)
            Training readings per fold.

        Returns
        -------
        list of (dict or None)
            One setting per fold (None for smooth).
        """
        if not self.periodic:
            return [None] * len(trains)
        jac = ctx.jacobian(variant)
        trains = np.asarray(trains, dtype=bool)
        targets = np.einsum("fnc,nc->fn", residuals, np.where(mask, jac, 0.0)) * trains
        frequencies = np.array([1.0 / s["period_m"] for s in settings])
        # The weights' sums depend on the readings, mask and training sets alone, not on
        # the residual: a selection's later steps reuse them.
        key = ("periodogram_weights", variant, trains.shape, hash(trains.tobytes()),
               hash(mask.tobytes()), hash(frequencies.tobytes()))
        # The choice depends on nothing else than these and the targets; a selection asks
        # for the same targets again (its other look, a step whose residual along this
        # error did not move), so it is kept by the targets' digest.
        choice_key = ("periodogram_choice", key,
                      hashlib.blake2b(targets.tobytes(), digest_size=16).digest())
        if choice_key not in ctx.cache:
            ctx.cache[choice_key] = self._strongest_periods(ctx, variant, frequencies, key,
                                                            targets, mask, trains)
        return [settings[int(i)] for i in ctx.cache[choice_key]]

    @staticmethod
    def _strongest_periods(ctx, variant, frequencies, key, targets, mask, trains):
        """Index of the strongest frequency of each fold's (row of ``targets``) periodogram,
        shape (F,)."""
        jac = ctx.jacobian(variant)
        q = ctx.variables.positions[variant[2]]
        # The exponentials of an axis' positions serve every variant on that axis.
        basis_key = ("periodogram_basis", variant[2], hash(frequencies.tobytes()))
        if basis_key not in ctx.cache:
            ctx.cache[basis_key] = direct_basis(q, frequencies)
        basis = ctx.cache[basis_key]
        if key not in ctx.cache:
            # Readings outside a training set get zero weight.
            weight = np.sum(np.where(mask, jac ** 2, 0.0), axis=1)
            ctx.cache[key] = weight_sums(q, np.where(trains, weight[None, :], 0.0).T,
                                         frequencies, basis=basis)
        # The period is chosen by the fundamental alone: with its harmonic too, readings
        # taken on the fly (positions on a near-lattice) let aliases fit as well.
        return strongest_frequencies(q, targets.T, frequencies, weights=ctx.cache[key],
                                     basis=basis)

    def explanation(self, variant: str, setting: dict) -> str:
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        str
            The sentence.
        """
        axis = variant[2]
        if self.periodic:
            return (f"{variant} repeats every {setting['period_m'] * 1e3:.2f} mm of {axis} "
                    "travel - typical of a ball-screw pitch error, a rack or a wavy guideway "
                    "(ISO 230-1 periodic error)")
        if setting == STILL_TURN:
            # ISO 230-1: the tilt of a carriage that stood still is one constant turn of
            # all it carries; ISO 230-7: about the carried axis' direction that is the
            # axis' zero and its line's offset by the turn's lever.
            return (f"the {axis} axis stood still over these readings: its angular error "
                    f"{variant} is one constant turn P0 of the carriage and all it carries "
                    "about the carriage's origin - the zero of the rotary axis it carries "
                    "and its line's offset by the turn's lever, which these readings cannot "
                    "part - read as the sphere, and the tool's direction, located at the "
                    "set-up read it, turning with the work (ISO 230-1, ISO 230-7, ISO "
                    "10791-6)")
        kind = {"positioning": "positioning", "straightness": "straightness",
                "angular": "angular"}[self.kind]
        reach = " reaching the TCP through its Abbe arms" if self.kind == "angular" else ""
        if setting.get("constant") and setting.get("located") == HEAD:
            # A constant turn of a carriage that carries the head turns the head's lines
            # together: their tilts about the same direction (ISO 230-7).
            reach += ("; its constant part P0 turns the head and all it carries - its rotary "
                      "axes' lines tilted alike about the same direction")
        elif setting.get("constant"):
            # ISO 230-1: a constant turn of a carriage that carries one axis of its plane
            # turns that axis' travel against the other's - their squareness; carrying
            # neither (the outermost table), it turns only the work on it.
            plane = {"A": "Y and Z", "B": "X and Z", "C": "X and Y"}[variant[1]]
            reach += (f"; its constant part P0 turns the carriage and all it carries - the "
                      f"squareness of {plane} where it carries one of them, else a turn of "
                      "the work on it")
        if setting.get("located") == HEAD:
            reach += ("; the tilt turns the head's rotary axes the carriage carries, and its "
                      "value where the tool was located at the head's set-up turns with the "
                      "head (ISO 10791-6)")
        elif setting.get("located"):
            reach += ("; the tilt turns the rotary axes the carriage carries, and its value "
                      "where the target was located at the set-up turns with them "
                      "(ISO 10791-6)")
        if setting.get("lever"):
            reach += (f"; about a pivot p off the carriage's origin, whose lever "
                      f"-P0 (e_k x p) ({', '.join(lever_names(variant))}) moves all it "
                      "carries, located alike")
        if setting.get("lever_slope") and setting.get("located"):
            reach += (f"; the pivot's move growing with the tilt's slope, -P1 L1(u) (e_k x p) "
                      f"({', '.join(lever_slope_names(variant))}), offsets the lines it "
                      "carries along its travel, located alike")
        elif setting.get("lever_slope"):
            # ISO 230-1 books a turn about the origin: the pivot's move is, there, a slope of
            # the axis' own positioning and straightness - its squareness.
            reach += (f"; about a pivot p off the carriage's origin, the pivot's move growing "
                      f"with the tilt's slope, -P1 L1(u) (e_k x p) "
                      f"({', '.join(lever_slope_names(variant))}), shifts the table along its "
                      "travel, which ISO 230-1 books at the origin as the carriage's "
                      "squareness and positioning slope")
        return (f"the {kind} error {variant} of the {axis} axis, smooth along its travel "
                f"(Legendre order {setting.get('order')}){reach} (ISO 230-1, Kidani eq. 2.6)")

    def describe_setting(self, setting: dict) -> str:
        """The setting in words, e.g. ``"period 5.000 mm"`` or ``"order 3"``.

        Parameters
        ----------
        setting : dict
            The setting.

        Returns
        -------
        str
            The words.
        """
        if self.periodic:
            return f"period {setting['period_m'] * 1e3:.3f} mm"
        constant = ", with a constant part (its plane's squareness)" if \
            setting.get("constant") else ""
        located = ", located at the set-up with the work" if setting.get("located") else ""
        if setting.get("located") == HEAD:
            located = ", the tool located at the head's set-up"
            constant = ", with a constant part (the head's lines tilted alike)" if \
                setting.get("constant") else ""
        lever = ", about a pivot off its origin" if setting.get("lever") or \
            setting.get("lever_slope") else ""
        return f"order {setting['order']}{constant}{located}{lever}"


class Squareness(EffectFamily):
    name = "squareness"
    group = "geometric"
    complexity = 1
    summary = "two axes out of square: the error grows linearly with another axis' position"
    reference = "ISO 230-1 location errors; Khan & Chen eps_xy, eps_zx, eps_zy"

    #: The same pair out of square with the *other* axis as the reference: the first
    #: form tilts the later axis (EC0Y: e_x ~ y), this one the earlier axis' travel -
    #: a straightness slope of it (EYX: e_y ~ x). The two differ by a rigid rotation of
    #: the instrument's frame, which a survey aligned to the machine does not remove,
    #: so both are candidates; by ISO 230-1 convention a straightness has no slope, so
    #: no other family holds this one. A CNC table holds it as that axis' motion error.
    #: The later axis' travel tilted (EXY: e_x ~ y) is a slope too: on a tool-side axis it
    #: equals the location error (EC0Y) up to a constant, but on an axis that carries the
    #: workpiece the location error turns the table about a pivot that may lie under the
    #: tool - where the error is taken (the machining point) it then moves nothing, while
    #: a tilted travel moves the part by angle x position.
    OTHER_REFERENCE = {"EYX": "EC0Y", "EZX": "EB0Z", "EZY": "EA0Z",
                       "EXY": "EC0Y", "EXZ": "EB0Z", "EYZ": "EA0Z"}
    PAIRS = {"EC0Y": "X and Y", "EB0Z": "X and Z", "EA0Z": "Y and Z", "EYX": "X and Y",
             "EZX": "X and Z", "EZY": "Y and Z", "EXY": "X and Y", "EXZ": "X and Z",
             "EYZ": "Y and Z"}

    def variants(self, ctx: Context) -> list[str]:
        """Location errors EC0Y, EB0Z, EA0Z of pairs whose later axis moved, and the slopes
        (EYX, EXY ...) whose growing axis moved - each while one target was read
        (:func:`moves_within_a_target`); the other axis of the pair may stand still.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            Variant names.
        """
        axes = ctx.linear_axes()
        moving = [axis for axis in ctx.linear_axes(moving=True)
                  if moves_within_a_target(ctx, axis) or
                  (self._seen_located(ctx, axis) and seen_through_located_turn(ctx, axis))]
        # The error grows with the last letter's axis: it must have moved while one target
        # was read (each target reads from its own zero, which takes a move between them),
        # or the work turned under a located target while the axis stood still (its move
        # there then turns away from the located value).
        first = [name for name in ("EC0Y", "EB0Z", "EA0Z") if name[-1] in moving and
                 {"C": "X", "B": "X", "A": "Y"}[name[1]] in axes]
        # The other reference: the slope along the earlier axis; both must have moved.
        return first + [name for name, base in self.OTHER_REFERENCE.items()
                        if name[2] in moving and base[-1] in axes]

    def parameter_names(self, variant, setting):
        """One angle.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``["angle_rad"]`` [rad].
        """
        return ["angle_rad"]

    def design(self, ctx, variant, setting):
        """Location error's sensitivity, or the slope's: sensitivity times position; read
        as a target located at the set-up reads it where the work side turns
        (:func:`located_tilt`: the squareness' move there went into the target).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, 1)
            (N, 3, 1) [m per rad].
        """
        if variant in self.OTHER_REFERENCE:
            position = ctx.variables.positions[variant[2]]
            design = (ctx.jacobian(variant) * position[:, None])[:, :, None]
        else:
            design = ctx.jacobian(variant)[:, :, None]
        if self._head_located(ctx, variant):
            # The tool, located at the head's set-up, took the squareness' move there in,
            # and that belief turns with the head (ISO 10791-6), as a tilt's does.
            return located_head_tilt(ctx, design)
        if self._located(ctx, variant):
            design = located_tilt(ctx, design)
        return design

    @staticmethod
    def _slide(variant: str) -> str:
        """The axis whose travel the squareness tilts: K of E R 0 K, or of E C K."""
        return variant[3] if len(variant) == 4 else variant[2]

    @classmethod
    def _head_located(cls, ctx: Context, variant: str) -> bool:
        """Whether the tilted slide carries a head that turned and stood at its set-up pose
        among the readings: the tool was located there (:func:`located_head_tilt`)."""
        return carries_head(ctx.machine, cls._slide(variant)) and head_turned(ctx) and \
            head_setup_row(ctx) is not None

    @staticmethod
    def _seen_located(ctx: Context, slide: str) -> bool:
        """Whether a squareness of ``slide`` reads as a located target reads it
        (:meth:`_located`): not where the slide carries a head that turned among the
        readings. A head that stood still keeps the tool located in its own frame as one
        constant, as a head without rotary axes does."""
        return not (head_turned(ctx) and slide in ctx.machine.tool_branch)

    @staticmethod
    def _located(ctx: Context, variant: str) -> bool:
        """Whether a target located at the set-up took in this squareness' move there, turning
        with the work-side rotary axes: not where the tilted slide is on a head that turns
        (there the tool was located in its own frame first, and its part turns with the head)."""
        if not located_tilt_seen(ctx) or setup_rows(ctx) is None:
            return False
        return Squareness._seen_located(ctx, Squareness._slide(variant))

    def orientation_design(self, ctx, variant, setting):
        """The turn of the later axis' frame; None for the other-reference (translational) form.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, 1), or None
            (N, 3, 1) [rad per rad], or None.
        """
        # The first form turns the later axis' frame (and what it carries); the other
        # reference is a straightness slope, a translation.
        if variant in self.OTHER_REFERENCE:
            return None
        turn = ctx.orientation_jacobian(variant)[:, :, None]
        # The tool's direction located at the head's set-up too (two spheres, ISO 10791-6).
        return located_head_turn(ctx, turn) if self._head_located(ctx, variant) else turn

    def fit_problems(self, ctx: Context, variant: str, setting: dict, coefficients
                     ) -> list[str]:
        """A squareness no machine has, said in words without its number: the poses barely
        see this form (a work-side slide's location error turns the table with its travel
        about a point where the tool stands, which moves nothing there), so its fit
        follows the readings' noise.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).
        coefficients : sequence of float, length 1
            The fitted angle [rad].

        Returns
        -------
        list of str
            One sentence when the angle is beyond :data:`LARGEST_SQUARENESS_RAD` or not
            finite, else none.
        """
        angle = float(np.asarray(coefficients, dtype=np.float64)[0])
        if np.isfinite(angle) and abs(angle) <= LARGEST_SQUARENESS_RAD:
            return []
        reach = float(np.max(np.abs(self.design(ctx, variant, setting)), initial=0.0))
        return [f"{variant} would put {self.PAIRS[variant]} out of square by more than "
                f"{LARGEST_SQUARENESS_RAD * 1e3:g} mrad, which no machine tool is: these "
                f"poses barely see it (it moves the readings by at most {reach * 1e-6:.2g} m "
                "per urad), so its fit follows the noise and is not reported"]

    def location_error(self, machine, variant: str, setting: dict,
                       coefficients) -> dict[str, float]:
        """The location error it stands for (a CNC table's squareness entry) [rad]; the
        other-reference form is a motion error (:meth:`motion_error`), not one.

        Parameters
        ----------
        machine : MachineDescription
            The machine (unused: a squareness is its own entry).
        variant : str
            The variant.
        setting : dict
            The fitted setting (unused).
        coefficients : sequence of float, length 1
            The fitted angle [rad].

        Returns
        -------
        dict of str to float
            ``{variant: angle}`` [rad], or empty.
        """
        if variant in self.OTHER_REFERENCE:
            return {}
        return {variant: float(coefficients[0])}

    def motion_error(self, machine, variant: str, setting: dict, coefficients, q):
        """The other-reference form as its axis' error motion: angle x position [m]
        (the first form has none: it is a location error).

        Parameters
        ----------
        machine : MachineDescription
            Unused (the common signature).
        variant : str
            The variant.
        setting : dict
            Unused.
        coefficients : sequence of float, length 1
            The fitted angle [rad].
        q : array_like, shape (K,)
            Positions of the variant's axis [m].

        Returns
        -------
        ndarray, shape (K,)
            Error motion [m] (zeros for a location error).
        """
        q = np.asarray(q, dtype=np.float64)
        if variant not in self.OTHER_REFERENCE:
            return np.zeros_like(q)
        return float(np.asarray(coefficients, dtype=np.float64)[0]) * q

    def explanation(self, variant, setting):
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        str
            The sentence.
        """
        pair = self.PAIRS[variant]
        if variant in self.OTHER_REFERENCE:
            return (f"the residual in {variant[1].lower()} grows linearly with the "
                    f"{variant[2]} position - {pair} are out of square, {variant[2]}'s travel "
                    f"tilted (a straightness slope {variant})")
        return (f"the residual grows linearly with the other axes' positions - {pair} are out "
                f"of square (location error {variant})")


class RotaryError(EffectFamily):
    """Position-dependent errors of a rotary axis as a Fourier series in its angle."""

    name = "rotary_error"
    group = "rotary"
    complexity = 2
    summary = "a position-dependent error of a rotary axis (runout, wobble, angular positioning)"
    reference = "Khan & Chen eqs. 9-16 (E_XA ... E_CA); Zhu ch. 5"

    def variants(self, ctx):
        """The six error motions of every rotary axis that moved.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            ISO names ``E<XYZABC><axis>``.
        """
        return [f"E{c}{a}" for a in ctx.rotary_axes(moving=True) for c in "XYZABC"]

    def settings(self, ctx, variant):
        """Number of harmonics: 1, 2 or 3.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).

        Returns
        -------
        list of dict
            ``{"harmonics": h}``.
        """
        return [{"harmonics": h} for h in (1, 2, 3)]

    def variant_complexity(self, variant: str) -> int:
        """One more for an angular error (a wobble acting through a lever) than for a runout.

        Parameters
        ----------
        variant : str
            The variant.

        Returns
        -------
        int
            Occam's complexity of the variant.
        """
        # As for a linear axis: a wobble acting through a lever assumes more than a runout.
        # With a constant lever the two are the same signature to the last bit, and
        # the tie must not be broken by rounding.
        return self.complexity + (variant[1] in "ABC")

    @staticmethod
    def first_harmonic(variant: str) -> int:
        """The lowest harmonic of ``variant`` that no location error of the axis holds.

        The chain applies a rotary axis' error motions in its turning frame. There, a
        tilt of the centre line (a location error, :class:`RotaryLocation`) is a
        once-per-revolution wobble about the two directions across the axis, so those
        start at the second harmonic (as ISO 230-7 separates them). A once-per-revolution
        radial or axial runout and angular positioning error (an eccentric bearing or
        encoder disc) is no location error: those start at the first.

        Parameters
        ----------
        variant : str
            ISO name of a rotary axis' error motion, e.g. ``EAC``.

        Returns
        -------
        int
            1 or 2.
        """
        along_axis = "ABC".index(variant[2])
        tilt = variant[1] in "ABC" and "ABC".index(variant[1]) != along_axis
        return 2 if tilt else 1

    def harmonics(self, variant, setting) -> range:
        """The harmonics of ``variant`` at ``setting``.

        Parameters
        ----------
        variant : str
            ISO name.
        setting : dict
            ``{"harmonics": h}``.

        Returns
        -------
        range
            From :meth:`first_harmonic`, h of them.
        """
        first = self.first_harmonic(variant)
        return range(first, first + setting["harmonics"])

    def parameter_names(self, variant, setting):
        """Fourier coefficients in the axis angle.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``cos<h>, sin<h>`` per harmonic, [m] (runout) or [rad] (wobble, positioning).
        """
        return [f"{f}{h}" for h in self.harmonics(variant, setting) for f in ("cos", "sin")]

    def design(self, ctx, variant, setting):
        """(N, 3, P) TCP error per unit Fourier coefficient.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, P)
            [m per m] or [m per rad].
        """
        return along(*self.separable_design(ctx, variant, setting))

    def separable_design(self, ctx, variant, setting):
        """The error's sensitivity and cos/sin of h times the angle.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        tuple of ndarray
            (sensitivity (N, 3), basis (N, P) dimensionless).
        """
        angle = ctx.variables.positions[variant[2]]
        columns = np.column_stack([f(h * angle) for h in self.harmonics(variant, setting)
                                   for f in (np.cos, np.sin)])
        return ctx.jacobian(variant), columns

    def orientation_sensitivity(self, ctx, variant, setting):
        """The tool's turn per unit angular error motion; None for a runout.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3), or None
            [rad per rad], or None.
        """
        return ctx.orientation_jacobian(variant) if variant[1] in "ABC" else None

    def explanation(self, variant, setting):
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        str
            The sentence.
        """
        what = {"X": "radial/axial runout", "Y": "radial/axial runout", "Z": "radial/axial runout",
                "A": "wobble or angular positioning", "B": "wobble or angular positioning",
                "C": "wobble or angular positioning"}[variant[1]]
        return (f"{variant}: the {variant[2]} axis' {what} repeating with its angle "
                f"({setting['harmonics']} harmonics; Khan & Chen eqs. 9-16)")


class RotaryLocation(EffectFamily):
    """Where a rotary axis really is: offsets and tilts of its centre line, zero of its angle."""

    name = "rotary_location"
    group = "rotary"
    complexity = 1
    summary = "a rotary axis' centre line offset or tilted (ISO 230-7)"
    reference = "Khan & Chen position-independent errors (section 5); Zhu ch. 5"

    def variants(self, ctx):
        """Every rotary axis, and all of them at once when there are several.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            Axis letters, e.g. ``["B", "C", "BC"]``.
        """
        rotary = ctx.rotary_axes()
        # Every rotary axis at once as well: a tilt of one axis and of the next turn the
        # tool alike (in Khan & Chen's chain both are constant rotations of the tool
        # against the table), so the tool's direction sees their sum and only the levers
        # part them - one axis at a time, the first would take the other's tilt.
        return rotary + (["".join(rotary)] if len(rotary) > 1 else [])

    def variant_complexity(self, variant: str) -> int:
        """One more for several axes at once.

        Parameters
        ----------
        variant : str
            The variant.

        Returns
        -------
        int
            Occam's complexity of the variant.
        """
        return self.complexity + (len(variant) > 1)

    def _names(self, variant):
        # ISO 230-7's location errors of the line: two offsets and two tilts. An offset
        # along the line moves nothing, nor does the zero-angle error of the last axis of a
        # side: the located set-up takes them out. An outer axis' zero (EA0A where A carries
        # C) turns the carried line about its own: said as that line's tilt and offset
        # (outer_zeros, in the setting), never fitted.
        names = []
        for axis in variant:
            along_axis = "XYZ"["ABC".index(axis)]
            offsets = [f"E{c}0{axis}" for c in "XYZ" if c != along_axis]
            tilts = [f"E{c}0{axis}" for c in "ABC" if c != axis]
            names += offsets + tilts
        return names

    def settings(self, ctx, variant):
        """One setting: the line errors these readings cannot part (or none when nothing is seen).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).

        Returns
        -------
        list of dict
            ``[{"inseparable": str}]`` (:func:`inseparable_location_errors`) or ``[]``.
        """
        # The location errors these poses cannot part are folded into those they move
        # the readings as (one setting: which, and by how much); so is the zero of an
        # outer axis, which turns the lines it carries (said, never fitted).
        said_only = outer_zeros(ctx.machine, variant) + still_outer_lines(ctx, variant)
        setting = {"inseparable": inseparable_location_errors(
            ctx, self._names(variant), said_only=said_only)}
        # A variant none of whose errors these poses see is no candidate.
        return [setting] if self.parameter_names(variant, setting) else []

    def parameter_names(self, variant, setting):
        """The line errors (two offsets, two tilts per axis) not folded.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ISO names: offsets ``EX0C`` ... [m], tilts ``EA0C`` ... [rad].
        """
        folded = parse_inseparable(setting.get("inseparable", ""))
        return [name for name in self._names(variant) if name not in folded]

    def design(self, ctx, variant, setting):
        """(N, 3, P) as an instrument located at the set-up reads them (:meth:`Context.located`).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, P)
            [m per m] (offsets) or [m per rad] (tilts).
        """
        # As an instrument located at the set-up reads them (Context.located).
        return np.stack([ctx.located(name)[0] for name in self.parameter_names(variant,
                                                                                setting)],
                        axis=2)

    def orientation_design(self, ctx, variant, setting):
        """(N, 3, P) the tool's turn per unit line error.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, P)
            [rad per m] or [rad per rad].
        """
        return np.stack([ctx.located(name)[1] for name in self.parameter_names(variant,
                                                                                setting)],
                        axis=2)

    def explanation(self, variant, setting):
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        str
            The sentence.
        """
        which = f"the {variant} axis is" if len(variant) == 1 else \
            f"the {' and '.join(variant)} axes are"
        text = (f"{which} not where the model puts it: centre line offset or tilted "
                f"({', '.join(self.parameter_names(variant, setting))}; ISO 230-7 location "
                "errors, the body turning about the actual line, the target located at the "
                "set-up pose; Khan & Chen position-independent errors)")
        folded = inseparable_sentence(setting.get("inseparable", ""))
        return f"{text}; {folded}" if folded else text

    def location_error(self, machine, variant: str, setting: dict,
                       coefficients) -> dict[str, float]:
        """The line errors as a CNC table's location block holds them: ISO 230-7's offsets and
        tilts of each line, the body turning about the actual line from the set-up pose, as
        the chain reads a described axis' location errors (:mod:`..kinematics.chain`). A
        folded error is not listed: the one kept stands for the sum the readings gave.

        Parameters
        ----------
        machine : MachineDescription
            The machine (unused: the names carry the axis).
        variant : str
            The variant, e.g. ``AC``.
        setting : dict
            The fitted setting (its folds).
        coefficients : sequence of float, length P
            Fitted values in :meth:`parameter_names` order [m] or [rad].

        Returns
        -------
        dict of str to float
            ``{"EX0C": ..., "EA0C": ...}`` [m] or [rad].
        """
        return {name: float(value) for name, value in
                zip(self.parameter_names(variant, setting), coefficients)}

    def describe_setting(self, setting):
        """The setting in words, e.g. the folds in words.

        Parameters
        ----------
        setting : dict
            The setting.

        Returns
        -------
        str
            The words.
        """
        return inseparable_sentence(setting.get("inseparable", "")) or "every line error seen"


#: A location error whose column keeps less than this fraction of its norm once the
#: columns kept before it (and the offsets) are taken out is not parted from them: its
#: parameter would be known this many times worse than if it were.
INSEPARABLE_FRACTION = 1e-4
#: [m per m or m per rad] RMS: a location error that moves the readings less than this
#: per unit moves nothing (a tilt of a line that never turned, to rounding: its fit would
#: be 1e10 rad).
NULL_SENSITIVITY = 1e-9


def inseparable_location_errors(ctx: Context, names: list[str],
                                said_only: list[str] | tuple[str, ...] = ()) -> str:
    """Which of a rotary axis' location errors ``names`` the readings cannot part, as the
    setting string ``"EB0C=EX0C*-0.093;EX0B="``: EB0C moves them as -0.093 m/rad of EX0C
    (EX0C then stands for EX0C - 0.093 m/rad x EB0C); EX0B moves nothing here (less than
    :data:`NULL_SENSITIVITY` per unit).

    The columns are taken in order (the line's offsets before its tilts: the centre a
    calibration measures first), each against the offsets (an instrument's own zero, on
    the position rows) and the columns kept before it; one that keeps less than
    :data:`INSEPARABLE_FRACTION` of its norm is folded into them (least squares).

    Parameters
    ----------
    ctx : Context
        The machine and the readings.
    names : list of str
        Location error names, offsets [m] before tilts [rad].
    said_only : list of str, optional
        Location errors judged after ``names`` against what was kept and never kept
        themselves (an outer axis' zero, :func:`outer_zeros`): said when folded or unseen,
        left out when the readings part them.

    Returns
    -------
    str
        The setting string (ratios in the kept error's unit per the folded one's).
    """
    columns = []
    for name in list(names) + list(said_only):
        position, turn = ctx.located(name)
        if ctx.width == 6:      # the direction as the instrument saw it (Context)
            position = np.concatenate([position, ctx._direction_rows(turn[:, :, None])[:, :, 0]],
                                      axis=1)
        columns.append(position)
    flat = []
    for column in columns:
        column = column.copy()
        column[:, :3] -= column[:, :3].mean(axis=0)      # the offsets take the mean out
        flat.append(column.ravel())
    kept: list[int] = []
    parts = []
    names = list(names) + list(said_only)
    # The axes that turned first: a line error of one that stood still is read as the
    # line of one that turned (a B offset at a fixed B moves the C table's line).
    order = sorted(range(len(names) - len(said_only)), key=lambda k: not ctx.moves(names[k][3]))
    for i in order + list(range(len(names) - len(said_only), len(names))):
        column = flat[i]
        norm = float(np.linalg.norm(column))
        if norm <= NULL_SENSITIVITY * np.sqrt(column.size):
            parts.append(f"{names[i]}=")
            continue
        if kept:
            basis = np.column_stack([flat[k] for k in kept])
            weights, *_ = np.linalg.lstsq(basis, column, rcond=None)
            rest = float(np.linalg.norm(column - basis @ weights))
            if rest < INSEPARABLE_FRACTION * norm:
                terms = "&".join(f"{names[k]}*{w:.6e}" for k, w in zip(kept, weights)
                                 if abs(w) * float(np.linalg.norm(flat[k])) > 1e-6 * norm)
                parts.append(f"{names[i]}={terms}")
                continue
        if i < len(names) - len(said_only):
            kept.append(i)
    return ";".join(parts)


def still_outer_lines(ctx: Context, axes: str) -> list[str]:
    """The line errors of the rotary axes that carry one of ``axes`` on its side and stood
    still over these readings.

    A body that never turned moves what it carries by one constant rigid motion: its
    line's offsets shift the carried lines, its tilts tilt them (ISO 230-7), so on these
    readings they are the carried lines' own errors. Judged after those (said when they
    fold into them, never fitted as the carried variant's), they are said beside the line
    that turned rather than named for it.

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings.
    axes : str
        Rotary axis letters of a variant, e.g. ``"C"``.

    Returns
    -------
    list of str
        ISO names, e.g. ``["EY0A", "EZ0A", "EB0A", "EC0A"]`` for ``"C"`` on a
        ``[w C A X Y b Z t]`` trunnion whose A stood still.
    """
    machine = ctx.machine
    out: list[str] = []
    for branch in (machine.workpiece_branch, machine.tool_branch):
        for axis in axes:
            if axis not in branch:
                continue
            for outer in branch[:branch.index(axis)]:
                if not machine.axes[outer].is_rotary or ctx.moves(outer) or outer in axes:
                    continue
                along = "XYZ"["ABC".index(outer)]
                names = [f"E{c}0{outer}" for c in "XYZ" if c != along] + \
                    [f"E{c}0{outer}" for c in "ABC" if c != outer]
                out += [name for name in names if name not in out]
    return out


def parse_inseparable(text: str) -> dict[str, dict[str, float]]:
    """The setting string of :func:`inseparable_location_errors` as {folded: {kept: ratio}}
    (ratio in the kept parameter's unit per the folded one's; {} for one that moves
    nothing).

    Parameters
    ----------
    text : str
        The setting string.

    Returns
    -------
    dict of str to dict of str to float
        Folded name -> kept name -> ratio [m/rad, rad/m, m/m or rad/rad].
    """
    out: dict[str, dict[str, float]] = {}
    for part in filter(None, str(text).split(";")):
        name, _, terms = part.partition("=")
        out[name] = {kept: float(ratio) for kept, ratio in
                     (term.split("*") for term in filter(None, terms.split("&")))}
    return out


def inseparable_sentence(text: str) -> str:
    """The folds of a setting string in words ("" when there are none).

    Parameters
    ----------
    text : str
        The setting string of :func:`inseparable_location_errors`.

    Returns
    -------
    str
        The sentence(s).
    """
    folded = parse_inseparable(text)
    if not folded:
        return ""
    unseen = [name for name, into in folded.items() if not into]
    said = []
    for name, into in folded.items():
        if into:
            moves = " + ".join(f"{ratio:.4g} {_ratio_unit(name, kept)} x {kept}"
                               for kept, ratio in into.items())
            stands = "; ".join(f"{kept} stands for {kept} + {ratio:.4g} "
                               f"{_ratio_unit(name, kept)} x {name}"
                               for kept, ratio in into.items())
            # An outer axis' zero turns the lines it carries about its own (ISO 230-7).
            what = f"{name} (the {name[3]} axis' zero error, turning the lines it carries)" \
                if name[1] == name[3] else name
            said.append(f"{what} moves these readings as {moves} would, which these poses "
                        f"cannot part: {stands}")
    if unseen:
        said.append(f"{', '.join(unseen)} move(s) nothing on these poses (not seen)")
    return "; ".join(said)


def _ratio_unit(folded: str, kept: str) -> str:
    """The unit of a fold's ratio: kept's unit per folded's (m/rad, rad/m, m/m, rad/rad)."""
    unit = {True: "m", False: "rad"}
    return f"{unit[kept[1] in 'XYZ']}/{unit[folded[1] in 'XYZ']}"


class CrossAxis(EffectFamily):
    name = "cross_axis"
    group = "geometric"
    complexity = 2
    summary = "an error in the product of two axis positions: a twist of the travel plane"
    reference = "beyond the rigid-body model (Kidani eq. 2.12 holds one axis' errors per axis)"

    def variants(self, ctx):
        """Every pair of linear axes that moved.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            Pairs, e.g. ``"XY"``.
        """
        axes = sorted(ctx.linear_axes(moving=True))
        return [a + b for i, a in enumerate(axes) for b in axes[i + 1:]]

    def parameter_names(self, variant, setting):
        """One coefficient per TCP component.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``on_x, on_y, on_z`` [m].
        """
        return ["on_x", "on_y", "on_z"]

    def design(self, ctx, variant, setting):
        """The product of the two normalised positions on each TCP component.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, P)
            (N, 3, 3) dimensionless (parameters in [m]).
        """
        product = ctx.normalised_position(variant[0]) * ctx.normalised_position(variant[1])
        design = np.zeros((ctx.n, 3, 3))
        for c in range(3):
            design[:, c, c] = product
        return design

    def explanation(self, variant, setting):
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        str
            The sentence.
        """
        return (f"the residual follows {variant[0]} x {variant[1]}: the {variant[0]}{variant[1]} "
                "travel plane is twisted (a cross-axis error no single axis' error motion "
                "can express)")


class AbbeOffset(EffectFamily):
    name = "abbe_offset"
    group = "geometric"
    complexity = 2
    summary = "the measured angular errors acting through an unknown extra lever"
    reference = "Kidani eq. 2.10; ISO 230-1 (Abbe principle)"

    def variants(self, ctx):
        """``["tool"]`` when the model has an orientation error at the readings, else none.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            Variant names.
        """
        if ctx.orientation is None or not np.any(ctx.orientation):
            return []
        return ["tool"]

    def parameter_names(self, variant, setting):
        """The lever's components.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``ox, oy, oz`` [m].
        """
        return ["ox", "oy", "oz"]

    def design(self, ctx, variant, setting):
        """eps x e_k for each unit lever direction, eps the model's orientation error.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, P)
            (N, 3, 3) [m per m] (eps in [rad]).
        """
        return np.stack([np.cross(ctx.orientation, unit) for unit in np.eye(3)], axis=2)

    def explanation(self, variant, setting):
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        str
            The sentence.
        """
        return ("the residual follows the measured angular errors times a lever - the tool or "
                "workpiece is offset from the scales' line (Abbe)")


class AngularWithArm(EffectFamily):
    """An angular error of a linear axis whose Abbe arm along the tool is not known.

    The chain knows the arm of a tilt up to what the machine description (or a
    survey's column map) says: the tool length, the offsets between the axes. When
    the real arm is longer by a constant l along the tool axis t, the tilt E(q)
    moves the TCP by J(q_all) E(q) + l sign (r x t) E(q), r the tilt's axis: the
    second term depends on the axis' own position alone and looks like a
    straightness or positioning error of the same axis. This family fits both with
    the same Legendre shape, E(q) = sum a_k P_k(u) and l E(q) = sum b_k P_k(u), so
    the tilt is named once with the arm the data identify (l = <a, b> / <a, a>),
    not as an angular error plus substitute terms. Offered on a machine known only from
    a survey (``MachineDescription.abbe_arms_known`` False); a described machine's arms
    are its description's.
    """

    name = "angular_arm"
    group = "geometric"
    reference = "ISO 230-1 (Abbe principle); Kidani eq. 2.10 with an unknown arm"
    summary = ("an angular error of an axis acting through a longer or shorter arm than the "
               "machine description gives (a tool offset that is wrong or not given)")
    # One more assumption than the angular error: the arm is fitted, not known.
    complexity = 4
    nested_settings = False

    def variants(self, ctx: Context) -> list[str]:
        """Angular errors of moving linear axes with an arm along the tool, on a machine whose arms
        are not known.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            ISO names (none on a described machine).
        """
        # A machine whose description gives its offsets has its arms: nothing to fit.
        if getattr(ctx.machine, "abbe_arms_known", True):
            return []
        # A turn about the tool's own axis has no arm along it (a yaw under a vertical
        # spindle): that tilt is the plain angular error.
        return [name for name in component_names(ctx, "angular") if ctx.arm_moves(name)]

    def settings(self, ctx: Context, variant: str) -> list[dict]:
        """Legendre orders 1 ..

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).

        Returns
        -------
        list of dict
            ``{"order": k}``.
        """
        return [{"order": k} for k in range(1, 1 + _ORDERS)]

    def parameter_names(self, variant: str, setting: dict) -> list[str]:
        """The tilt's Legendre coefficients, then the arm's.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``P<k>`` [rad] then ``arm_P<k>`` [rad m].
        """
        orders = range(1, setting["order"] + 1)
        return [f"P{k}" for k in orders] + [f"arm_P{k}" for k in orders]

    def _basis(self, ctx: Context, variant: str, setting: dict):
        key = ("legendre", variant[2])
        if key not in ctx.cache:
            ctx.cache[key] = _legendre_columns(ctx.normalised_position(variant[2]), 0,
                                               _LARGEST_ORDER)
        if setting["order"] > _LARGEST_ORDER:
            return _legendre_columns(ctx.normalised_position(variant[2]), 1, setting["order"])
        return ctx.cache[key][:, 1:setting["order"] + 1]

    def nested_columns(self, variant: str, setting: dict, largest: dict) -> list[int]:
        """The tilt's orders, then the arm's: a lower order's are the first of each half.

        Parameters
        ----------
        variant : str
            The variant.
        setting : dict
            ``{"order": k}``.
        largest : dict
            ``{"order": K}``, K >= k.

        Returns
        -------
        list of int
            Column indices into the largest design.
        """
        # The tilt's orders, then the arm's: a lower order's are the first of each half.
        order, most = setting["order"], largest["order"]
        return list(range(order)) + list(range(most, most + order))

    def design(self, ctx: Context, variant: str, setting: dict):
        """Tilt columns along the chain's sensitivity, then the same basis along the arm's.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, P)
            (N, 3, 2k) [m per rad], then [m per (rad m)].
        """
        basis = self._basis(ctx, variant, setting)
        return np.concatenate([along(ctx.jacobian(variant), basis),
                               along(ctx.arm_jacobian(variant), basis)], axis=2)

    def orientation_design(self, ctx: Context, variant: str, setting: dict):
        """The tilt's turn; the arm turns nothing.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, P)
            (N, 3, 2k) [rad per rad], the arm's half zero.
        """
        basis = self._basis(ctx, variant, setting)
        turn = along(ctx.orientation_jacobian(variant), basis)
        return np.concatenate([turn, np.zeros_like(turn)], axis=2)

    def fit_problems(self, ctx: Context, variant: str, setting: dict, coefficients
                     ) -> list[str]:
        """An arm beyond the machine's reach is no tilt.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting.
        coefficients : sequence of float, length 2k
            Tilt [rad] and arm [rad m] coefficients.

        Returns
        -------
        list of str
            Problems (empty: none).
        """
        # An arm beyond the machine's reach is no tilt: the "arm" part is then a
        # straightness or squareness of the axis that a vanishing tilt divides.
        reach = machine_reach(ctx)
        arm = self.arm_m(coefficients)
        if not abs(arm) <= reach:
            return [f"the fitted arm along the tool ({arm:+.2f} m) is beyond the machine's "
                    f"reach ({reach:.2f} m): not a tilt, a straightness or squareness of "
                    f"{variant[2]}"]
        return []

    @staticmethod
    def arm_m(coefficients) -> float:
        """The extra arm l [m] the fitted coefficients (a..., b...) identify.

        Parameters
        ----------
        coefficients : sequence of float, length 2k
            Tilt coefficients a [rad], then arm coefficients b [rad m].

        Returns
        -------
        float
            l = <a, b> / <a, a> [m] (0 when a is zero).
        """
        values = np.asarray(coefficients, dtype=np.float64)
        a, b = values[:values.size // 2], values[values.size // 2:]
        return float(a @ b / (a @ a)) if a @ a > 0 else 0.0

    def explanation(self, variant: str, setting: dict) -> str:
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        str
            The sentence.
        """
        return (f"the angular error {variant} of the {variant[2]} axis (Legendre order "
                f"{setting.get('order')}), acting through an Abbe arm along the tool that the "
                "machine description does not give - the fit names the arm (ISO 230-1)")

    def describe_setting(self, setting: dict) -> str:
        """The setting in words, e.g. ``"order 2, arm fitted"``.

        Parameters
        ----------
        setting : dict
            The setting.

        Returns
        -------
        str
            The words.
        """
        return f"order {setting['order']}, arm fitted"


def families() -> list[EffectFamily]:
    out: list[EffectFamily] = []
    for kind in ("positioning", "straightness", "angular"):
        out += [ComponentError(kind, False), ComponentError(kind, True)]
    return out + [AngularWithArm(), Squareness(), RotaryError(), RotaryLocation(), CrossAxis(),
                  AbbeOffset()]
