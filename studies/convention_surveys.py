"""Independent generator of convention-heavy machine-tool surveys.

Written from rigid-body physics alone (ISO 230-1, ISO 230-7, ISO 10791-6) to judge
a consumer of the documented survey format (``survey.csv`` + ``map.yaml`` +
``machine.yaml``) honestly.  Conventions of this module, all written into each
trial's ``truth.json``:

* Bodies stack from the bed outwards on each side; every body is a 4x4 transform
  of its carried frame in its base frame.  Rotations are exact (Rodrigues).
* A rotary axis turns its carried body about its actual line: point ``c`` (the
  line's offset, base frame) and direction ``Rod(tilt) e_k``, by ``sign*q + zero``.
* A linear carriage translates by ``sign*q`` along ``Rod(square) e_k`` and tilts by
  ``eps(q)`` (polynomial in the command ``q``) about a pivot ``p`` (carriage frame,
  relative to its frame origin).
* Reported error = (tool point - work point)_actual - (...)_nominal in the bed
  frame, where the nominal uses the located target (and, with head rotaries, the
  located tool): locating at the setup pose is a translation of the target in the
  workpiece frame (tool: in the tool frame), so every error is zero there.
* The error columns are then written in a convention drawn per trial from a stream of
  its own (half the trials the default above): ``of: work`` is the work relative to
  the tool, ``as: correction`` nominal minus actual (each turns the sign), ``frame:
  work``/``tool`` the components along the nominal end frame of the work/tool side at
  each row's commands: ``e_written = s R^T e``.  Tool-direction columns likewise.

Run: ``python -m studies.convention_surveys --out DIR --trials N --seed S``.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path

import numpy as np
import yaml

AXIS_INDEX = {"X": 0, "Y": 1, "Z": 2, "A": 0, "B": 1, "C": 2}
ROTARY = ("A", "B", "C")
LEN_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "in": 0.0254}
ANG_UNITS = {"rad": 1.0, "mrad": 1e-3, "urad": 1e-6, "deg": math.pi / 180.0,
             "arcsec": math.pi / 648000.0}
TIME_UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0}
TOPOLOGIES = ("trunnion_AC", "trunnion_BC", "swivel_head_BC", "mixed_table_head",
              "vmc_3axis", "hmc_3axis")
FIVE_AXIS = TOPOLOGIES[:4]
INSTRUMENTS = ("r_test", "laser_tracker", "probing", "machining_point")
# ISO 230-7 location-error names per rotary axis: offsets, tilts, zero.
LOC_NAMES = {"C": (("EX0C", "EY0C"), ("EA0C", "EB0C"), "EC0C"),
             "A": (("EY0A", "EZ0A"), ("EB0A", "EC0A"), "EA0A"),
             "B": (("EX0B", "EZ0B"), ("EA0B", "EC0B"), "EB0B")}
SQUARENESS = (("EC0Y", "Y", "X"), ("EB0Z", "Z", "X"), ("EA0Z", "Z", "Y"))
TOL_SIGNATURE = 1e-9  # m or rad: below this an effect leaves no trace in the survey
DIR_LEVER = 0.1       # m, distance of the R-test's second sphere (direction noise)


# ----------------------------------------------------------------- geometry
def skew(v):
    """Cross-product matrix ``[v x]`` of a 3-vector (same unit as ``v``)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rodrigues(rotvec):
    """Exact rotation matrix of a rotation vector ``rotvec`` [rad]."""
    v = np.asarray(rotvec, float)
    th = float(np.linalg.norm(v))
    if th == 0.0:
        return np.eye(3)
    k = skew(v / th)
    return np.eye(3) + math.sin(th) * k + (1.0 - math.cos(th)) * (k @ k)


def homog(rot=None, trans=None):
    """4x4 homogeneous transform from a rotation (3x3) and a translation [m]."""
    t = np.eye(4)
    if rot is not None:
        t[:3, :3] = rot
    if trans is not None:
        t[:3, 3] = trans
    return t


def poly_eval(coeffs, q):
    """Evaluate per-component polynomials ``coeffs`` (3 x m, powers of q [m]) at q."""
    return coeffs @ (q ** np.arange(coeffs.shape[1]))


def axis_motion(ax, q, err):
    """Transform of the body carried by axis ``ax`` in its base frame.

    Parameters
    ----------
    ax : dict
        Axis description (``k`` index, ``rotary``, ``sign``).
    q : float
        Command, SI (m or rad).
    err : dict
        Errors of this axis (empty for nominal): ``offset`` [m], ``tilt`` [rad],
        ``zero`` [rad] for rotaries; ``square`` [rad], ``poly`` (3 x m) [rad, rad/m..],
        ``pivot`` [m] for linear axes.
    """
    e_k = np.eye(3)[ax["k"]]
    zero3 = np.zeros(3)
    if ax["rotary"]:
        u = rodrigues(err.get("tilt", zero3)) @ e_k
        rot = rodrigues(u * (ax["sign"] * q + err.get("zero", 0.0)))
        c = err.get("offset", zero3)
        return homog(rot, c - rot @ c)   # x -> c + R (x - c): a turn about the real line
    direction = rodrigues(err.get("square", zero3)) @ e_k
    eps = poly_eval(err["poly"], q) if "poly" in err else zero3
    rot, piv = rodrigues(eps), err.get("pivot", zero3)
    return homog(rot, ax["sign"] * q * direction + piv - rot @ piv)


def side_frame(axes, q, errs):
    """Frame (4x4, bed coordinates) of a side's end: last axis frame moved by its offset."""
    frame = np.eye(4)
    for ax in axes:
        frame = frame @ axis_motion(ax, q[ax["name"]], errs.get(ax["name"], {}))
        frame = frame @ homog(trans=ax["offset"])
    return frame


def end_points(machine, q, target, errs):
    """Tool point, work point [m] and the two end frames for commands ``q``."""
    ft = side_frame(machine["tool"], q, errs)
    fw = side_frame(machine["work"], q, errs)
    tool = ft[:3, :3] @ machine["tool_vec"] + ft[:3, 3]
    work = fw[:3, :3] @ (machine["work_vec"] + target) + fw[:3, 3]
    return tool, work, ft, fw


def nominal_relative(machine, q, target):
    """Nominal tool point minus work point (target, workpiece frame) [m], bed frame."""
    tool, work, _, _ = end_points(machine, q, np.asarray(target, float), {})
    return tool - work


def solve_linear(machine, rot_q, target):
    """Linear commands (SI) putting the nominal tool tip on ``target`` (RTCP).

    Linear axes sit inboard of every rotary here, so tool - work is affine in them.
    """
    names = [a["name"] for a in machine["work"] + machine["tool"] if not a["rotary"]]
    q = dict(rot_q, **{n: 0.0 for n in names})
    f0 = nominal_relative(machine, q, target)
    if "jac" not in machine:  # constant: the same for every pose and target
        machine["jac"] = np.column_stack(
            [nominal_relative(machine, dict(q, **{n: 1.0}), target) - f0 for n in names])
    sol = np.linalg.solve(machine["jac"], -f0)
    return dict(q, **{n: float(v) for n, v in zip(names, sol)})


def raw_row(machine, errs, q, target):
    """Unlocated errors of one row: relative and tool-only parts, position and direction."""
    tn, wn, ftn, fwn = end_points(machine, q, target, {})
    ta, wa, fta, fwa = end_points(machine, q, target, errs)
    u = machine["tool_vec"] / np.linalg.norm(machine["tool_vec"])
    rtn, rwn, rta, rwa = ftn[:3, :3], fwn[:3, :3], fta[:3, :3], fwa[:3, :3]
    return {"pos": (ta - wa) - (tn - wn), "pos_t": ta - tn,
            # tool direction seen in the actual work frame, mapped back through the
            # nominal work orientation: the tool's direction relative to the work.
            "dir": rwn @ rwa.T @ rta @ u - rtn @ u, "dir_t": (rta - rtn) @ u,
            "rtn": rtn, "rwn": rwn}


def located_errors(machine, errs, rows):
    """Located errors [m] and direction errors [-] of all rows, bed frame.

    The tool (head rotaries only) is located in its frame at ``rows['tool_setup']``;
    each target group is then located in the workpiece frame at its setup row, so
    the error is zero there.
    """
    raw = [raw_row(machine, errs, q, t) for q, t in zip(rows["q"], rows["target"])]
    head = any(a["rotary"] for a in machine["tool"])
    s0 = raw[rows["tool_setup"]]
    out = []
    for key in ("pos", "dir"):
        d_t = s0["rtn"].T @ s0[key + "_t"] if head else np.zeros(3)
        d_w = {g: raw[s]["rwn"].T @ (raw[s]["rtn"] @ d_t - raw[s][key])
               for g, s in rows["setup"].items()}
        out.append(np.array([r[key] - r["rtn"] @ d_t + r["rwn"] @ d_w[g]
                             for r, g in zip(raw, rows["group"])]))
    return out[0], out[1]


DEFAULT_ERROR_CONVENTION = {"of": "tool", "as": "deviation", "frame": "machine"}
ERROR_CONVENTION_WORDS = {"of": ("tool", "work"), "as": ("deviation", "correction"),
                          "frame": ("machine", "work", "tool")}


def nominal_end_rotations(machine, rows):
    """Nominal orientations (bed frame) of the tool-side and work-side end frames.

    Parameters
    ----------
    machine : dict
        A drawn machine (``build_machine``).
    rows : dict
        Survey rows (``make_rows``): commands ``q`` [SI] and targets [m].

    Returns
    -------
    tool, work : ndarray, shape (n, 3, 3)
        ``R_tn``, ``R_wn`` of each row: columns are the end frame's axes in bed
        coordinates (the targets do not turn them).
    """
    ends = [end_points(machine, q, t, {}) for q, t in zip(rows["q"], rows["target"])]
    return (np.array([e[2][:3, :3] for e in ends]), np.array([e[3][:3, :3] for e in ends]))


def convention_factors(convention, rot_tool, rot_work):
    """Sign and per-row rotation taking default-convention errors to ``convention``.

    Parameters
    ----------
    convention : dict
        ``{"of": tool|work, "as": deviation|correction, "frame": machine|work|tool}``.
    rot_tool, rot_work : ndarray, shape (n, 3, 3)
        Nominal end-frame orientations (``nominal_end_rotations``).

    Returns
    -------
    sign : float
        -1 for each of ``of: work`` (work - tool = -(tool - work)) and ``as:
        correction`` (nominal - actual = -(actual - nominal)); +1 otherwise.
    rot : ndarray, shape (n, 3, 3)
        ``R`` whose columns are the frame's axes in bed coordinates (identity for
        ``machine``): components along them are ``R^T e``.
    """
    sign = (-1.0 if convention["of"] == "work" else 1.0) * (
        -1.0 if convention["as"] == "correction" else 1.0)
    n = len(rot_tool)
    rot = {"machine": np.broadcast_to(np.eye(3), (n, 3, 3)), "work": rot_work,
           "tool": rot_tool}[convention["frame"]]
    return sign, rot


def to_error_convention(values, convention, rot_tool, rot_work):
    """Default-convention errors (n x 3, bed frame) as written in ``convention``: s R^T e."""
    sign, rot = convention_factors(convention, rot_tool, rot_work)
    return sign * np.einsum("nji,nj->ni", rot, values)


def from_error_convention(values, convention, rot_tool, rot_work):
    """Inverse of ``to_error_convention``: e = s R e_written (n x 3, bed frame)."""
    sign, rot = convention_factors(convention, rot_tool, rot_work)
    return sign * np.einsum("nij,nj->ni", rot, values)


def draw_error_convention(rng):
    """The error columns' convention: (convention dict, written in the map or not).

    Half the trials take the default (seven in ten of those omit the key, the rest
    write its default words); the others one of the eleven other combinations.  Every
    survey here writes all three error components, so every frame is allowed.
    """
    if rng.random() < 0.5:
        return dict(DEFAULT_ERROR_CONVENTION), bool(rng.random() < 0.3)
    combos = [{"of": o, "as": a, "frame": f} for o in ERROR_CONVENTION_WORDS["of"]
              for a in ERROR_CONVENTION_WORDS["as"] for f in ERROR_CONVENTION_WORDS["frame"]]
    combos = [c for c in combos if c != DEFAULT_ERROR_CONVENTION]
    return combos[int(rng.integers(len(combos)))], True


# ----------------------------------------------------------------- machines
def _ax(name, sign, offset):
    """One axis description; ``offset`` [m] is in the axis' moving frame."""
    return {"name": name, "k": AXIS_INDEX[name], "rotary": name in ROTARY,
            "sign": int(sign), "offset": np.array(offset, float), "stroke": None}


def _u(rng, lo, hi):
    """Uniform draw rounded to 1 mm, so the YAML states the geometry exactly [m]."""
    return round(float(rng.uniform(lo, hi)), 3)


def _sgn(rng):
    """Random direction sign (+1 or -1)."""
    return int(rng.choice([-1, 1]))


def _five_axis_geometry(topology, rng):
    """Work/tool axes of a five-axis topology with drawn signs and offsets [m]."""
    s = lambda: _sgn(rng)  # noqa: E731 - keeps the tables below readable
    spindle = [_ax("Z", s(), [0, 0, _u(rng, 0.5, 0.8)])]
    if topology in ("trunnion_AC", "trunnion_BC"):
        tilt = "A" if topology == "trunnion_AC" else "B"
        drop, side = -_u(rng, 0.0, 0.15), (_u(rng, -0.02, 0.02) if rng.random() < 0.3 else 0.0)
        t_off = [0, side, drop] if tilt == "A" else [side, 0, drop]
        work = [_ax("Y", s(), [0, 0, _u(rng, 0.05, 0.15)]),
                _ax("X", s(), [0, 0, _u(rng, 0.15, 0.35)]),
                _ax(tilt, s(), t_off), _ax("C", s(), [0, 0, 0])]
        return work, spindle
    head_b = [_ax("B", s(), [0, 0, -_u(rng, 0.05, 0.2)])]
    if topology == "mixed_table_head":
        work = [_ax("Y", s(), [0, 0, _u(rng, 0.05, 0.15)]),
                _ax("X", s(), [0, 0, _u(rng, 0.05, 0.15)]), _ax("C", s(), [0, 0, 0])]
        return work, spindle + head_b
    head = [_ax("C", s(), [0, 0, -_u(rng, 0.1, 0.3)])] + head_b
    if rng.random() < 0.7:  # tables carry the work; else a gantry carries the head
        work = [_ax("Y", s(), [0, 0, _u(rng, 0.05, 0.15)]), _ax("X", s(), [0, 0, 0.05])]
        return work, spindle + head
    tool = [_ax("Y", s(), [0, 0, 0]), _ax("X", s(), [0, 0, _u(rng, 0.2, 0.5)])]
    return [], tool + spindle + head


def _three_axis_geometry(topology, rng, machine_given):
    """Axes of a three-axis VMC/HMC; without a machine file, CNC signs and no offsets.

    Without ``machine:`` the map cannot state signs, so the positions must then be
    the tool relative to the work: tables move against the command (sign -1).
    """
    def sign(table):
        return _sgn(rng) if machine_given else (-1 if table else 1)

    def off(z=None):
        xyz = [_u(rng, -0.05, 0.05) if machine_given else 0.0 for _ in range(3)]
        return xyz if z is None else xyz[:2] + [z]

    if topology == "vmc_3axis":
        work = [_ax("Y", sign(True), off()), _ax("X", sign(True), off())]
        return work, [_ax("Z", sign(False), off(_u(rng, 0.4, 0.7)))]
    work = [_ax("Z", sign(True), off())]
    return work, [_ax("X", sign(False), off(0.0)), _ax("Y", sign(False), off(_u(rng, 0.4, 0.7)))]


ROT_STROKES = {"A": [(-110, 30), (-30, 110), (-120, 120)],
               "B": [(-120, 120), (-30, 110), (-110, 30)],
               "C": [(-360, 360), (-180, 180), (0, 360)]}
SETUP_CHOICES = {"A": (-90, -30, 20, 30), "B": (-90, -30, 20, 30), "C": (45, 90, -90, 180)}


def _draw_rotaries(machine, rng):
    """Draw rotary strokes [deg] and setup angles (0 most often) in place."""
    setup = {}
    for ax in machine["work"] + machine["tool"]:
        if not ax["rotary"]:
            continue
        lo, hi = ROT_STROKES[ax["name"]][int(rng.integers(3))]
        ax["stroke"] = (math.radians(lo), math.radians(hi))
        pick = [v for v in SETUP_CHOICES[ax["name"]] if lo <= v < hi]
        angle = 0 if (rng.random() < 0.6 or not pick) else int(rng.choice(pick))
        setup[ax["name"]] = math.radians(angle)
    return setup


def build_machine(topology, rng, machine_given=True):
    """Draw a machine of ``topology``: axes, tool and work vectors [m], setup pose [rad]."""
    if topology in FIVE_AXIS:
        work, tool = _five_axis_geometry(topology, rng)
    else:
        work, tool = _three_axis_geometry(topology, rng, machine_given)
    wv = [_u(rng, -0.05, 0.05), _u(rng, -0.05, 0.05), 0.0] if (
        machine_given and rng.random() < 0.3) else [0.0, 0.0, 0.0]
    chain = "[w " + " ".join([a["name"] for a in work][::-1] + ["b"]
                             + [a["name"] for a in tool]) + " t]"
    m = {"topology": topology, "chain": chain, "work": work, "tool": tool,
         "tool_vec": np.array([0.0, 0.0, -_u(rng, 0.08, 0.2)]), "work_vec": np.array(wv)}
    m["setup"] = _draw_rotaries(m, rng)
    m["pivots"] = {}  # tilt pivot of each carriage: its frame origin, or a few 100 mm away
    for a in (a for a in work + tool if not a["rotary"]):
        v = rng.normal(size=3)
        m["pivots"][a["name"]] = np.zeros(3) if rng.random() < 0.5 else \
            np.round(v / np.linalg.norm(v) * rng.uniform(0.2, 0.5), 3)
    return m


# ----------------------------------------------------------------- rows
def rotary_panel(machine, rng):
    """Rotary poses [rad]: setup first, then a serpentine grid (A/B every 10 deg,
    C every 15 deg) or a sweep of one axis with the other at its setup angle."""
    names = [a["name"] for a in machine["work"] + machine["tool"] if a["rotary"]]
    strokes = {a["name"]: np.degrees(a["stroke"]) for a in machine["work"] + machine["tool"]
               if a["rotary"]}
    grids = {}
    for n in names:
        lo, hi = strokes[n]
        step = 15 if n == "C" else 10
        if n == "C":
            lo, hi = (0, 345) if lo >= 0 else (-180, 165)
        grids[n] = [math.radians(v) for v in np.arange(lo, hi + 1e-9, step)]
    kind = str(rng.choice(["grid", "sweep_" + names[0], "sweep_" + names[1]], p=[0.6, 0.2, 0.2]))
    for n in names:
        if kind.startswith("sweep") and not kind.endswith(n):
            grids[n] = [machine["setup"][n]]
    outer, inner = grids[names[0]], grids[names[1]]
    poses = [dict(machine["setup"])]
    for i, a in enumerate(outer):
        for b in (inner if i % 2 == 0 else inner[::-1]):
            poses.append({names[0]: a, names[1]: b})
    return poses, kind


def _box_targets(machine, rng, n):
    """Random target points [m] in the workpiece frame, in front of the tool."""
    if machine["topology"] == "hmc_3axis":
        lo, hi = [-0.3, 0.05, 0.02], [0.3, 0.5, 0.4]
    elif machine["topology"] in FIVE_AXIS:
        lo, hi = [-0.12, -0.12, 0.02], [0.12, 0.12, 0.2]
    else:
        lo, hi = [-0.3, -0.2, 0.02], [0.3, 0.2, 0.35]
    return rng.uniform(lo, hi, size=(n, 3))


def _raster_targets(machine, rng, n):
    """Machining path [m]: serpentine lines in x, stepping in y, over a few z levels."""
    levels = np.sort(rng.uniform(0.02, 0.15, size=int(rng.integers(2, 5))))[::-1]
    lines, per_line = 8, max(2, int(math.ceil(n / (len(levels) * 8))))
    pts = []
    for z in levels:
        for j, y in enumerate(np.linspace(-0.15, 0.15, lines)):
            xs = np.linspace(-0.25, 0.25, per_line)
            pts += [[x, y, z] for x in (xs if j % 2 == 0 else xs[::-1])]
    pts = np.array(pts[:n])
    if machine["topology"] == "hmc_3axis":  # work in front of the table, above it
        pts[:, 1] += 0.2
    return pts


def make_rows(machine, instrument, rng, n_rows=None):
    """Commands (SI), targets (workpiece frame, m), groups and setup rows of a survey.

    R-test/probing: the machine follows fixed spheres with RTCP (each sphere a
    group, located at the setup pose).  Tracker/machining: the tool visits points
    of the work volume (one group, located at the first row).
    """
    five = machine["topology"] in FIVE_AXIS
    n = n_rows or (600 if five else int(rng.integers(300, 1001)))
    poses, panel = rotary_panel(machine, rng) if five else ([{}], "none")
    k = 1 if instrument != "probing" else int(rng.integers(2, 5) if five else rng.integers(3, 7))
    need = math.ceil(n / k)
    if len(poses) > need:  # thin the grid evenly so every angle of the panel is reached
        keep = np.linspace(1, len(poses) - 1, need - 1).round().astype(int)
        poses = [poses[0]] + [poses[i] for i in keep]
    if instrument in ("r_test", "probing"):
        spheres = _box_targets(machine, rng, k).round(4)
        idx = [(p, s) for p in range(len(poses)) for s in range(k)]
        picks = [idx[i % len(idx)] for i in range(n)]
        targets = np.array([spheres[s] for _, s in picks])
        group = [s for _, s in picks]
        rot = [poses[p] for p, _ in picks]
    else:
        targets = (_raster_targets if instrument == "machining_point" else _box_targets)(
            machine, rng, n)
        rot = [poses[i % len(poses)] for i in range(n)]
        group = [0] * n
    q = [solve_linear(machine, r, t) for r, t in zip(rot, targets)]
    setup = {}
    for i, g in enumerate(group):
        setup.setdefault(g, i)
    return {"q": q, "target": targets, "group": group, "setup": setup, "tool_setup": 0,
            "panel": panel}


def set_linear_strokes(machine, rows):
    """Linear strokes [m]: the commanded range plus a 50 mm margin, rounded to 10 mm."""
    for ax in machine["work"] + machine["tool"]:
        if not ax["rotary"]:
            v = [q[ax["name"]] for q in rows["q"]]
            ax["stroke"] = (math.floor((min(v) - 0.05) * 100) / 100,
                            math.ceil((max(v) + 0.05) * 100) / 100)


# ----------------------------------------------------------------- effects
def _draw_rotary_effect(machine, rng):
    """One ISO 230-7 location error of a rotary axis (offset, tilt or zero)."""
    rot = [a for a in machine["work"] + machine["tool"] if a["rotary"]]
    ax = rot[int(rng.integers(len(rot)))]
    offs, tilts, zero = LOC_NAMES[ax["name"]]
    kind = str(rng.choice(["location_offset", "location_tilt", "zero"], p=[0.45, 0.4, 0.15]))
    if kind == "location_offset":
        iso, value, unit = str(rng.choice(offs)), _sgn(rng) * rng.uniform(5e-6, 40e-6), "m"
    else:
        iso = str(rng.choice(tilts)) if kind == "location_tilt" else zero
        value, unit = _sgn(rng) * rng.uniform(10e-6, 60e-6), "rad"
    side = "work" if ax in machine["work"] else "tool"
    return {"iso_name": iso, "kind": kind, "axis": ax["name"], "side": side,
            "value_si": float(value), "unit_si": unit, "constant_part_si": None,
            "pivot_m": None, "note": ""}


def _draw_tilt_effect(machine, rng):
    """Angular error motion of a linear body (table first): eps(q) = c0 + c1 q + c2 q^2."""
    lin = [a for a in machine["work"] if not a["rotary"]] or \
        [a for a in machine["tool"] if not a["rotary"]]
    ax = lin[int(rng.integers(len(lin)))]
    comp = int(rng.integers(3))
    reach = max(abs(ax["stroke"][0]), abs(ax["stroke"][1]), 0.1)  # m: |c1 q| <= 60 urad
    c0 = _sgn(rng) * rng.uniform(10e-6, 60e-6) if rng.random() < 0.5 else 0.0
    c1 = _sgn(rng) * rng.uniform(10e-6, 60e-6) / reach
    c2 = _sgn(rng) * rng.uniform(5e-6, 30e-6) / reach ** 2 if rng.random() < 0.3 else 0.0
    pivot = machine["pivots"][ax["name"]]
    note = "pivot at the carriage's frame origin"
    if np.any(pivot):
        straight = np.cross(pivot, np.eye(3)[comp] * c1)
        note = ("pivot away from the carriage's frame origin: the origin also moves by "
                f"p x eps(q), a straightness-like term of {straight.tolist()} m per m of q")
    side = "work" if ax in machine["work"] else "tool"
    return {"iso_name": "E" + "ABC"[comp] + ax["name"], "kind": "table_tilt",
            "axis": ax["name"], "side": side, "value_si": [float(c0), float(c1), float(c2)],
            "unit_si": "rad, rad/m, rad/m^2 (powers of the command q)",
            "constant_part_si": float(c0), "pivot_m": pivot.tolist(), "note": note}


def _draw_squareness(machine, rng):
    """Orientation error of a linear axis' motion direction (squareness)."""
    iso, axis, other = SQUARENESS[int(rng.integers(len(SQUARENESS)))]
    side = "work" if any(a["name"] == axis for a in machine["work"]) else "tool"
    return {"iso_name": iso, "kind": "squareness", "axis": axis, "side": side,
            "value_si": float(_sgn(rng) * rng.uniform(10e-6, 60e-6)), "unit_si": "rad",
            "constant_part_si": None, "pivot_m": None,
            "note": f"slide {axis} moves along Rod(v) e_{axis.lower()} (tilted toward {other})"}


def draw_effects(machine, rng, null=None):
    """1 or 2 effects, or none for a NULL trial (noise only)."""
    null = bool(rng.random() < 0.15) if null is None else null
    if null:
        return []
    five = machine["topology"] in FIVE_AXIS
    cats = ["rotary", "tilt", "square"] if five else ["tilt", "square"]
    probs = [0.55, 0.3, 0.15] if five else [0.65, 0.35]
    drawers = {"rotary": _draw_rotary_effect, "tilt": _draw_tilt_effect,
               "square": _draw_squareness}
    effects, n = [], int(rng.integers(1, 3))
    while len(effects) < n:
        e = drawers[str(rng.choice(cats, p=probs))](machine, rng)
        if e["iso_name"] not in {x["iso_name"] for x in effects}:
            effects.append(e)
    return effects


def errs_from_effects(effects):
    """Per-axis error dict (see ``axis_motion``) from a list of effects."""
    errs = {}
    key = {"location_offset": "offset", "location_tilt": "tilt", "squareness": "square"}
    for e in effects:
        d = errs.setdefault(e["axis"], {})
        c = AXIS_INDEX[e["iso_name"][1]]  # the direction the name's 2nd letter points at
        if e["kind"] == "zero":
            d["zero"] = e["value_si"]
        elif e["kind"] == "table_tilt":
            d.setdefault("poly", np.zeros((3, 3)))[c] = e["value_si"]
            d["pivot"] = np.array(e["pivot_m"])
        else:
            d.setdefault(key[e["kind"]], np.zeros(3))[c] = e["value_si"]
    return errs


def judge_identifiable(machine, rows, effect, with_dir):
    """Mark an effect (in place) identifiable when its located signature is not null."""
    pos, dirs = located_errors(machine, errs_from_effects([effect]), rows)
    sig_pos, sig_dir = float(np.abs(pos).max()), float(np.abs(dirs).max())
    effect["signature_max_um"] = round(sig_pos * 1e6, 6)
    effect["signature_max_dir_urad"] = round(sig_dir * 1e6, 6) if with_dir else None
    visible = sig_pos > TOL_SIGNATURE or (with_dir and sig_dir > TOL_SIGNATURE)
    effect["identifiable"], effect["why_not"] = bool(visible), ""
    if visible:
        return
    axis = effect["axis"]
    poses = {}
    for q, g in zip(rows["q"], rows["group"]):
        poses.setdefault(g, set()).add(tuple(round(v, 9) for v in q.values()))
    if axis in ROTARY and len({round(q[axis], 9) for q in rows["q"]}) == 1:
        why = (f"{axis} never leaves its setup angle: the error is a fixed displacement "
               "absorbed by locating")
    elif effect["kind"] == "zero":
        why = ("a zero-angle error turns the work (or tool) rigidly about the axis line; the "
               "translation located at the setup pose absorbs it at each target")
    elif all(len(p) == 1 for p in poses.values()):
        why = "each target is only seen at the pose where it was located"
    else:
        why = "after locating at the setup pose its signature is below 1 nm over these poses"
    effect["why_not"] = why


# ----------------------------------------------------------------- files
def draw_units(rng):
    """Declared units of every column group (all converted exactly from SI)."""
    c = lambda opts, p: str(rng.choice(opts, p=p))  # noqa: E731
    return {"length": c(["mm", "m", "um", "in"], [0.55, 0.25, 0.12, 0.08]),
            "angle": c(["deg", "rad"], [0.7, 0.3]),
            "error": c(["um", "mm", "m", "in"], [0.7, 0.18, 0.06, 0.06]),
            "direction": c(["urad", "rad", "mrad", "arcsec"], [0.6, 0.2, 0.1, 0.1]),
            "time": c(["s", "min", "h"], [0.7, 0.2, 0.1]),
            "target": c(["mm", "m", "um"], [0.6, 0.3, 0.1]),
            "uncertainty": c(["um", "mm"], [0.8, 0.2]),
            "setup": c(["deg", "rad"], [0.7, 0.3]),
            "stroke": c(["deg", "rad"], [0.7, 0.3])}


def column_names(rng, axis_names, units):
    """Column names in one of three styles (names never collide)."""
    style = int(rng.integers(3))
    fmt = [lambda k, n, u: f"{n}_{u}" if k == "pos" else f"{k[0]}{n.lower()}_{u}",
           lambda k, n, u: f"{k}_{n.lower()}",
           lambda k, n, u: f"{k.upper()} {n} [{u}]"][style]
    ang = lambda n: units["angle"] if n in ROTARY else units["length"]  # noqa: E731
    cols = {"time": ["t_" + units["time"], "time", f"Time [{units['time']}]"][style]}
    cols["pos"] = {n: fmt("pos", n, ang(n)) for n in axis_names}
    cols["err"] = {c: fmt("err", c, units["error"]) for c in "xyz"}
    cols["dir"] = {c: fmt("dir", c, units["direction"]) for c in "xyz"}
    cols["tgt"] = {c: fmt("sphere", c, units["target"]) for c in "xyz"}
    return cols


def _num(x, digits=12):
    """Plain float for YAML/JSON, rounded to drop float noise of unit conversion."""
    return float(round(float(x), digits))


def build_map(trial):
    """The column map (``map.yaml`` content) of a trial."""
    u, cols, m = trial["units"], trial["columns"], trial["machine"]
    out = {"machine": "machine.yaml"} if trial["machine_given"] else {}
    out["time"] = {"column": cols["time"], "unit": u["time"]}
    out["positions"] = {n: {"column": c, "unit": u["angle"] if n in ROTARY else u["length"]}
                        for n, c in cols["pos"].items()}
    out["errors"] = {c: {"column": cols["err"][c], "unit": u["error"]} for c in "xyz"}
    if trial["with_dir"]:
        out["direction_errors"] = {c: {"column": cols["dir"][c], "unit": u["direction"]}
                                   for c in "xyz"}
    if trial["error_convention_written"]:
        out["error_convention"] = dict(trial["error_convention"])
    f = LEN_UNITS[u["target"]]
    if trial["instrument"] == "r_test":
        out["target_point"] = {"value": [_num(v / f) for v in trial["rows"]["target"][0]],
                               "unit": u["target"]}
    elif trial["instrument"] != "machining_point":
        out["target_point"] = {"columns": dict(cols["tgt"]), "unit": u["target"]}
    if m["setup"]:
        out["setup_pose"] = {n: {"value": _num(v / ANG_UNITS[u["setup"]]), "unit": u["setup"]}
                             for n, v in m["setup"].items()}
    out["uncertainty"] = {"value": _num(trial["uncertainty_m"] / LEN_UNITS[u["uncertainty"]]),
                          "unit": u["uncertainty"]}
    if not trial["machine_given"]:
        out["work_axes"] = [a["name"] for a in m["work"]]
        if trial["tool_offset_given"]:
            out["tool_offset"] = {"value": _num(trial["tool_offset_m"] / LEN_UNITS["mm"]),
                                  "unit": "mm"}
    return out


def build_machine_yaml(trial, rng):
    """The ISO 10791-1 style machine description (``machine.yaml`` content)."""
    m, u = trial["machine"], trial["units"]
    out = {"name": trial["name"], "chain": m["chain"], "tool": m["tool_vec"].tolist(),
           "workpiece": m["work_vec"].tolist()}
    if trial["machine_setup_deg"] is not None:
        out["setup_pose"] = {n: {"value": v, "unit": "deg"}
                             for n, v in trial["machine_setup_deg"].items()}
    axes = {}
    for ax in m["work"] + m["tool"]:
        lo, hi = ax["stroke"]
        if ax["rotary"] and u["stroke"] == "deg":
            stroke = {"value": [_num(math.degrees(lo), 9), _num(math.degrees(hi), 9)],
                      "unit": "deg"}
        else:
            stroke = [_num(lo), _num(hi)]
        entry = {"stroke": stroke, "sign": ax["sign"], "offset": ax["offset"].tolist()}
        if ax["sign"] == 1 and rng.random() < 0.3:
            del entry["sign"]  # the documented default
        axes[ax["name"]] = entry
    out["axes"] = axes
    return out


def survey_columns(trial):
    """(name, values) pairs of the CSV, values converted to the declared units."""
    u, cols, rows = trial["units"], trial["columns"], trial["rows"]
    errors, dirs = trial["errors_m"], trial["dir_errors"]
    if trial["error_convention"] != DEFAULT_ERROR_CONVENTION:
        rot_tool, rot_work = nominal_end_rotations(trial["machine"], rows)
        errors, dirs = (to_error_convention(v, trial["error_convention"], rot_tool, rot_work)
                        for v in (errors, dirs))
    out = [(cols["time"], trial["time_s"] / TIME_UNITS[u["time"]])]
    for n, c in cols["pos"].items():
        f = ANG_UNITS[u["angle"]] if n in ROTARY else LEN_UNITS[u["length"]]
        out.append((c, np.array([q[n] for q in rows["q"]]) / f))
    for i, c in enumerate("xyz"):
        out.append((cols["err"][c], errors[:, i] / LEN_UNITS[u["error"]]))
        if trial["with_dir"]:
            out.append((cols["dir"][c], dirs[:, i] / ANG_UNITS[u["direction"]]))
        if trial["instrument"] in ("probing", "laser_tracker"):
            out.append((cols["tgt"][c], rows["target"][:, i] / LEN_UNITS[u["target"]]))
    return out


# ----------------------------------------------------------------- trials
CONVENTION_TEXT = {
    "error_definition": "(tool point - work target)_actual - (same)_nominal, bed frame; the "
                        "nominal uses the located target/tool at the recorded commands",
    "direction_definition": "R_wn R_wa^T R_ta u - R_tn u (R: end-frame orientations, n/a = "
                            "nominal/actual, t/w = tool/work side), u = unit tool vector "
                            "(spindle to tip); located and zeroed at setup like positions",
    "target_frame": "origin at the work reference point (last work-side axis frame moved by "
                    "its offset, then by `workpiece`), axes of the last work-side axis",
    "location": "tool located (translation in its own frame) at tool_setup_row when the head "
                "has rotaries; then each target group located (translation in the workpiece "
                "frame) at its row in located_rows: the error is zero there",
    "rotary_location": "line through the axis frame origin + offset (EX0C, EY0C ..., base "
                       "frame), direction Rod(tilt) e_k (EA0C, EB0C ...), angle sign*q + zero",
    "tilt_polynomial": "eps(q) = c0 + c1 q + c2 q^2 [rad], q the command [m]: rotation of the "
                       "physical carriage about its own x/y/z, about pivots_m (carriage frame, "
                       "from its frame origin)",
    "squareness": "the slide of axis K moves along Rod(v) e_K, v carrying the named component",
    "positions": "commands as sent, SI before unit conversion; rotary sign: +q turns the body "
                 "by sign*q about +k",
    "error_convention_definition": "columns written as s R^T e (e: error_definition / "
                                   "direction_definition), s = -1 per of: work and per as: "
                                   "correction, R = I (frame: machine) or the nominal "
                                   "orientation of the work-side (R_wn) / tool-side (R_tn) "
                                   "end frame at the row's commands"}
TARGET_KIND = {"r_test": "one fixed sphere (map value)",
               "probing": "spheres, per row in columns, each located separately",
               "laser_tracker": "material point nominally at the tool tip, per row in columns",
               "machining_point": "material point nominally at the tool tip (no target_point)"}


def draw_trial(rng, name, topology=None, instrument=None, n_rows=None, null=None):
    """Draw one complete trial (machine, rows, effects, noisy errors, units)."""
    topology = topology or str(rng.choice(TOPOLOGIES, p=[0.2, 0.2, 0.15, 0.15, 0.15, 0.15]))
    five = topology in FIVE_AXIS
    instrument = instrument or str(rng.choice(
        INSTRUMENTS, p=[0.65, 0.0, 0.35, 0.0] if five else [0.0, 0.5, 0.0, 0.5]))
    given = five or bool(rng.random() < 0.5)
    m = build_machine(topology, rng, given)
    rows = make_rows(m, instrument, rng, n_rows)
    set_linear_strokes(m, rows)
    with_dir = instrument == "r_test" and bool(rng.random() < 0.35)
    effects = draw_effects(m, rng, null)
    for e in effects:
        judge_identifiable(m, rows, e, with_dir)
    pos, dirs = located_errors(m, errs_from_effects(effects), rows)
    n = len(rows["q"])
    sigma = float(rng.uniform(0.2e-6, 1e-6))
    t = {"name": name, "topology": topology, "instrument": instrument, "machine": m,
         "rows": rows, "effects": effects, "with_dir": with_dir, "machine_given": given,
         "tool_offset_given": (not given) and bool(rng.random() < 0.5),
         "sigma_m": sigma, "sigma_dir": sigma / DIR_LEVER,
         "uncertainty_m": math.ceil(2 * sigma * 1e8) / 1e8,
         "errors_m": pos + rng.normal(0.0, sigma, (n, 3)),
         "dir_errors": dirs + rng.normal(0.0, sigma / DIR_LEVER, (n, 3)),
         "time_s": np.concatenate([[0.0], np.cumsum(rng.uniform(1.0, 4.0, n - 1))])}
    zero_q = {a["name"]: 0.0 for a in m["work"] + m["tool"]}
    t["tool_offset_m"] = None if five else float(nominal_relative(m, zero_q, np.zeros(3))[2])
    t["units"] = draw_units(rng)
    t["columns"] = column_names(rng, [a["name"] for a in m["work"] + m["tool"]], t["units"])
    t["machine_setup_deg"] = _machine_setup(m, rng)
    t["error_convention"], t["error_convention_written"] = dict(DEFAULT_ERROR_CONVENTION), False
    return t


def _machine_setup(machine, rng):
    """Setup pose for machine.yaml [deg]: same as the map's, omitted, or stale."""
    if not machine["setup"]:
        return None
    deg = {n: round(math.degrees(v), 9) for n, v in machine["setup"].items()}
    choice = str(rng.choice(["same", "omit", "stale"], p=[0.45, 0.4, 0.15]))
    if choice == "stale":  # the map's setup pose wins: this one must be ignored
        first = next(iter(deg))
        deg[first] = deg[first] + (90.0 if deg[first] <= 0 else -90.0)
    return None if choice == "omit" else deg


def build_truth(trial):
    """The ``truth.json`` content: everything drawn, with the reasons."""
    m, rows = trial["machine"], trial["rows"]
    setup_deg = {n: round(math.degrees(v), 9) for n, v in m["setup"].items()}
    conv = dict(CONVENTION_TEXT, **{
        "target_kind": TARGET_KIND[trial["instrument"]],
        "located_rows": {str(g): int(i) for g, i in rows["setup"].items()},
        "tool_setup_row": rows["tool_setup"],
        "tool_located": any(a["rotary"] for a in m["tool"]),
        "signs": {a["name"]: a["sign"] for a in m["work"] + m["tool"]},
        "pivots_m": {k: v.tolist() for k, v in m["pivots"].items()},
        "setup_pose_deg": setup_deg, "machine_yaml_setup_pose_deg": trial["machine_setup_deg"],
        "machine_yaml_setup_pose_differs": trial["machine_setup_deg"] not in (None, setup_deg),
        "panel": rows["panel"], "units": trial["units"], "columns": trial["columns"],
        "machine_given": trial["machine_given"], "tool_offset_given": trial["tool_offset_given"],
        "tool_offset_m": trial["tool_offset_m"], "direction_errors": trial["with_dir"],
        "noise_sigma_m": trial["sigma_m"], "noise_sigma_dir_rad": trial["sigma_dir"],
        "uncertainty_k2_m": trial["uncertainty_m"], "tool_vector_m": m["tool_vec"].tolist(),
        "workpiece_m": m["work_vec"].tolist(), "n_targets": len(rows["setup"]),
        "error_convention": dict(trial["error_convention"]),
        "error_convention_in_map": trial["error_convention_written"]})
    return {"trial": trial["name"], "topology": trial["topology"],
            "instrument": trial["instrument"], "chain": m["chain"], "rows": len(rows["q"]),
            "null": not trial["effects"], "conventions": conv, "effects": trial["effects"]}


def write_trial(trial, folder, rng):
    """Write survey.csv, map.yaml, machine.yaml and truth.json into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    cols = survey_columns(trial)
    order = rng.permutation(len(cols))
    cols = [cols[i] for i in order]
    with open(folder / "survey.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow([c for c, _ in cols])
        for i in range(len(cols[0][1])):
            w.writerow([repr(float(v[i])) for _, v in cols])
    dump = lambda obj: yaml.safe_dump(obj, sort_keys=False, default_flow_style=None)  # noqa
    (folder / "map.yaml").write_text(dump(build_map(trial)))
    (folder / "machine.yaml").write_text(dump(build_machine_yaml(trial, rng)))
    (folder / "truth.json").write_text(json.dumps(build_truth(trial), indent=1))


def generate(out, trials, seed, topology=None, instrument=None, n_rows=None,
             error_conventions=True):
    """Generate ``trials`` trials into ``out``; one independent stream per trial.

    With ``error_conventions`` each trial's error columns take a convention drawn from
    a stream of its own (``[seed, trial, 7]``), so every other draw is the same as
    without it; without, every survey is in the default convention with no key.
    """
    out = Path(out)
    index = []
    for i, ss in enumerate(np.random.SeedSequence(seed).spawn(trials)):
        rng = np.random.default_rng(ss)
        name = f"trial_{i:03d}"
        t = draw_trial(rng, name, topology, instrument, n_rows)
        if error_conventions:
            t["error_convention"], t["error_convention_written"] = draw_error_convention(
                np.random.default_rng([seed, i, 7]))
        write_trial(t, out / name, rng)
        index.append({"name": name, "folder": name, "topology": t["topology"],
                      "instrument": t["instrument"], "rows": len(t["rows"]["q"]),
                      "null": not t["effects"],
                      "effects": [e["iso_name"] for e in t["effects"]]})
        print(f"{name} {t['topology']:16s} {t['instrument']:15s} rows={index[-1]['rows']:4d} "
              f"null={index[-1]['null']!s:5s} effects={','.join(index[-1]['effects']) or '-'}")
    (out / "index.json").write_text(json.dumps(
        {"generator": "studies.convention_surveys", "seed": seed, "trials": index}, indent=1))
    return index


def main(argv=None):
    """Command line: ``--out DIR --trials N --seed S [--topology T] [--instrument I]
    [--no-error-conventions]``."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", required=True)
    p.add_argument("--trials", type=int, default=12)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--topology", choices=TOPOLOGIES)
    p.add_argument("--instrument", choices=INSTRUMENTS)
    p.add_argument("--no-error-conventions", action="store_true",
                   help="write every survey's errors in the default convention (no key)")
    a = p.parse_args(argv)
    generate(a.out, a.trials, a.seed, a.topology, a.instrument,
             error_conventions=not a.no_error_conventions)


if __name__ == "__main__":
    main()
