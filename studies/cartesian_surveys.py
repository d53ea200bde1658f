"""Surveys of three Cartesian machines that exist only here: an independent generator.

Issue 28's proof must not lean on the package: this module shares **no code** with
``mt_accuracy_ros`` (not its chain, not its machines, not its simulator, not its
effect bases). Each machine is a layout written out below - which axes carry the
workpiece, which the tool, their travel, the tool's length - and the TCP error is
computed with exact 4x4 homogeneous transforms built here (Rodrigues rotations, ISO
230-1 error motions placed after each axis' nominal motion). Errors are drawn in
shapes outside the catalogue's exact forms (issue 39): cubic splines through random
knots, periodic splines for a screw's pitch, an off-centre catenary sag for a bow, a
backlash that changes along a worn screw, a following error that grows faster
than the feed, a thermal growth that bends away from a line in the rise - none of them
the workbench's Legendre, Fourier, step, velocity or exact-lag regressors. A
squareness stays a slope: that is what ISO 230-1 calls one.

A survey is written as a data logger would: positions in mm, deviations in um, a
time column in s, feeds in mm/min, directions, four thermocouples in degC, and a
column map YAML (with the tool offset, a fact a metrologist knows).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml
from scipy.interpolate import CubicSpline

from studies.shapes import worn_backlash


@dataclass(frozen=True)
class Layout:
    """A Cartesian machine: ``work`` axes from the bed to the table, ``tool`` axes from
    the bed to the spindle; travel [m]; the tool tip's z from the spindle [m]."""

    name: str
    work: tuple[str, ...]
    tool: tuple[str, ...]
    travel: dict
    tool_z_m: float


#: Three machines of different travel and layout (none of them bundled).
LAYOUTS = {
    # Bed-type vertical mill: the table rides X on a Y saddle; the head moves in Z (down).
    "vmc_500": Layout("vmc_500", ("Y", "X"), ("Z",),
                      {"X": (0.0, 0.5), "Y": (0.0, 0.4), "Z": (-0.35, 0.0)}, -0.12),
    # Gantry: every axis on the tool side, two metres of X.
    "gantry_2000": Layout("gantry_2000", (), ("X", "Y", "Z"),
                          {"X": (0.0, 2.0), "Y": (0.0, 1.5), "Z": (0.0, 0.8)}, -0.2),
    # Horizontal machine: the table moves in Z, the column in X, the head in Y.
    "hmc_600": Layout("hmc_600", ("Z",), ("X", "Y"),
                      {"X": (-0.3, 0.3), "Y": (0.0, 0.6), "Z": (0.0, 0.45)}, 0.1),
}

UNIT = {"X": np.array([1.0, 0.0, 0.0]), "Y": np.array([0.0, 1.0, 0.0]),
        "Z": np.array([0.0, 0.0, 1.0])}
SENSORS = ("column", "bed", "spindle", "ambient")


def rotation(vector: np.ndarray) -> np.ndarray:
    """(N, 3) rotation vectors -> (N, 3, 3) matrices (Rodrigues, exact)."""
    angle = np.linalg.norm(vector, axis=1)
    axis = np.divide(vector, angle[:, None], out=np.zeros_like(vector),
                     where=angle[:, None] > 0)
    k = np.zeros((vector.shape[0], 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    k[:, 1, 0], k[:, 2, 0], k[:, 2, 1] = axis[:, 2], -axis[:, 1], axis[:, 0]
    s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    return np.eye(3) + s * k + (1 - c) * (k @ k)


def transform(rotation_: np.ndarray, translation: np.ndarray) -> np.ndarray:
    out = np.zeros((rotation_.shape[0], 4, 4))
    out[:, :3, :3] = rotation_
    out[:, :3, 3] = translation
    out[:, 3, 3] = 1.0
    return out


@dataclass
class Errors:
    """Error motions per axis [m, rad] as functions of that axis' position, plus terms
    of the whole reading (thermal, motion) added at the TCP."""

    linear: dict = field(default_factory=dict)    # (axis, component) -> f(q) [m]
    angular: dict = field(default_factory=dict)   # (axis, component) -> f(q) [rad]
    tcp: list = field(default_factory=list)       # f(survey) -> (N, 3) [m]


def tcp_error(layout: Layout, q: dict, errors: Errors) -> np.ndarray:
    """(N, 3) actual minus nominal tool tip, in the workpiece's frame [m]."""
    n = next(iter(q.values())).size

    def chain(axes, sign):
        total = transform(np.repeat(np.eye(3)[None], n, 0), np.zeros((n, 3)))
        for axis in axes:
            nominal = transform(np.repeat(np.eye(3)[None], n, 0),
                                sign * q[axis][:, None] * UNIT[axis])
            delta, theta = np.zeros((n, 3)), np.zeros((n, 3))
            for c in range(3):
                if (axis, c) in errors.linear:
                    delta[:, c] = errors.linear[(axis, c)](q[axis])
                if (axis, c) in errors.angular:
                    theta[:, c] = errors.angular[(axis, c)](q[axis])
            total = total @ nominal @ transform(rotation(theta), delta)
        return total

    tip = np.array([0.0, 0.0, layout.tool_z_m, 1.0])
    # A survey's positions are the tool relative to the work, like a CNC's: a table moves
    # against its command.
    tool = chain(layout.tool, 1.0) @ tip
    work = chain(layout.work, -1.0)
    actual = np.einsum("nij,nj->ni", np.linalg.inv(work), tool)[:, :3]
    nominal = np.zeros((n, 3))
    for axis in layout.tool + layout.work:
        nominal += q[axis][:, None] * UNIT[axis]
    nominal[:, 2] += layout.tool_z_m
    error = actual - nominal
    for term in errors.tcp:
        error = error + term
    return error


@dataclass
class Survey:
    layout: Layout
    time_s: np.ndarray
    q: dict
    feed: dict          # axis -> (N,) [m/s] at the reading (0 at a standstill)
    direction: dict     # axis -> (N,) +-1, the last motion
    temperatures: dict  # sensor -> (N,) [degC]


def first_order(time_s: np.ndarray, drive: np.ndarray, tau_s: float) -> np.ndarray:
    """tau y' = u - y from rest, by explicit Euler sub-steps of at most tau/50 (not the
    workbench's exact piecewise-linear solution)."""
    out = np.zeros_like(drive)
    y = 0.0
    for k in range(1, time_s.size):
        dt = time_s[k] - time_s[k - 1]
        steps = max(1, int(np.ceil(dt / (tau_s / 50.0))))
        h = dt / steps
        for j in range(steps):
            u = drive[k - 1] + (drive[k] - drive[k - 1]) * (j + 0.5) / steps
            y += h * (u - y) / tau_s
        out[k] = y
    return out


def make_survey(layout: Layout, rng: np.random.Generator, readings: int = 500,
                hours: float = 3.0) -> Survey:
    """Random positions over the travel, half on the fly; a warm-up and a cooling of the
    structure that four thermocouples see, each with its own time constant."""
    t = np.sort(rng.uniform(0.0, hours * 3600.0, readings))
    q = {a: rng.uniform(*layout.travel[a], readings) for a in "XYZ"}
    moving = rng.random(readings) < 0.5
    feed = {a: np.where(moving, rng.uniform(-4000, 4000, readings), 0.0) / 60e3 for a in "XYZ"}
    direction = {a: np.where(feed[a] != 0, np.sign(feed[a]),
                             rng.choice([-1.0, 1.0], readings)) for a in "XYZ"}
    heat = (t < 0.6 * t[-1]).astype(float)          # the spindle works, then stops
    temperatures = {
        "column": 20.0 + 2.5 * first_order(t, heat, 2400.0),
        "bed": 20.0 + 1.0 * first_order(t, heat, 7000.0),
        "spindle": 20.0 + 6.0 * first_order(t, heat, 900.0),
        "ambient": 20.0 + 0.4 * np.sin(2 * np.pi * t / (5 * 3600.0) + rng.uniform(0, 6.3)),
    }
    temperatures = {k: v + rng.normal(0, 0.02, readings) for k, v in temperatures.items()}
    return Survey(layout, t, q, feed, direction, temperatures)


def spline(rng, low, high, amplitude, knots=5):
    """A smooth function over [low, high]: a cubic spline through random knots, with zero
    mean over the travel (a constant tilt is a squareness by ISO 230-1, not an error
    motion; a constant offset, the instrument's zero)."""
    x = np.linspace(low, high, knots)
    y = rng.normal(0.0, 1.0, knots)
    y -= y.mean()
    y *= amplitude / max(np.max(np.abs(y)), 1e-12)
    curve = CubicSpline(x, y, bc_type="natural")
    mean = float(np.mean(curve(np.linspace(low, high, 2001))))
    return lambda q: curve(q) - mean


def periodic_spline(rng, period: float, knots: int = 6):
    """A screw's measured-looking periodic error: a periodic cubic spline through random
    knots over one period, zero mean, unit RMS (not one or two sines)."""
    x = np.linspace(0.0, period, knots + 1)
    y = rng.normal(0.0, 1.0, knots + 1)
    y[-1] = y[0]
    curve = CubicSpline(x, y, bc_type="periodic")
    grid = curve(np.linspace(0.0, period, 400, endpoint=False))
    mean, rms = float(np.mean(grid)), float(np.std(grid)) or 1.0
    return lambda q: (curve(np.mod(q, period)) - mean) / rms


def sag(rng, low, high, amplitude):
    """A way that sags: a catenary whose lowest point lies off the travel's centre, zero
    mean and its line removed (a bow, not the Legendre P2 the catalogue fits)."""
    lowest = rng.uniform(low + 0.3 * (high - low), low + 0.7 * (high - low))
    stiffness = 2.5 / (high - low)
    grid = np.linspace(low, high, 2001)

    def raw(q):
        return np.cosh(stiffness * (np.asarray(q) - lowest))
    line = np.polyfit(grid, raw(grid), 1)
    peak = float(np.max(np.abs(raw(grid) - np.polyval(line, grid)))) or 1.0
    return lambda q: amplitude * (raw(q) - np.polyval(line, q)) / peak


#: ISO 230-1's names for the squareness of each axis pair: the later axis' location
#: error, and the slope of either travel against the other (a fact, not package code).
SQUARENESS_OF_PAIR = {"XY": ("EC0Y", "EYX", "EXY"), "XZ": ("EB0Z", "EZX", "EXZ"),
                      "YZ": ("EA0Z", "EZY", "EYZ")}


#: Single hidden effects: (kind, what it is named by, fairly) per machine, filled in by
#: :func:`hidden`. Kinds: pitch, scale, bow, square, angular (a tool-side tilt),
#: angular_table (a tilt of an axis that carries the workpiece), angular_tables (tilts of
#: two such axes at once: both must be named), drift, backlash, lag.
KINDS = ("pitch", "scale", "bow", "square", "angular", "angular_table", "angular_tables",
         "drift", "backlash", "lag")


def hidden(kind: str, layout: Layout, survey: Survey, rng: np.random.Generator,
           magnitude_m: float) -> tuple[Errors, set[str]]:
    """One hidden effect of ``kind`` on a random axis of ``layout``, about
    ``magnitude_m`` at the TCP; returns the errors and the names it may fairly be given
    (catalogue names, or ``family:*`` for any variant of a family)."""
    errors = Errors()
    axis = str(rng.choice(list("XYZ")))
    low, high = layout.travel[axis]
    c = "XYZ".index(axis)
    if kind == "pitch":
        period = float(rng.choice([0.008, 0.010, 0.016, 0.020]))
        shape = periodic_spline(rng, period)
        errors.linear[(axis, c)] = lambda x: 1.4 * magnitude_m * shape(x)
        return errors, {f"positioning_periodic:E{axis}{axis}"}
    if kind == "scale":
        errors.linear[(axis, c)] = spline(rng, low, high, 1.5 * magnitude_m)
        return errors, {f"positioning:E{axis}{axis}"}
    if kind == "bow":
        other = str(rng.choice([a for a in "XYZ" if a != axis]))
        errors.linear[(axis, "XYZ".index(other))] = sag(rng, low, high, 1.5 * magnitude_m)
        return errors, {f"straightness:E{other}{axis}"}
    if kind == "square":
        a, b = rng.choice(list("XYZ"), 2, replace=False)
        span = layout.travel[b][1] - layout.travel[b][0]
        slope = 1.7 * magnitude_m / span
        errors.linear[(str(b), "XYZ".index(str(a)))] = lambda x: slope * x
        # Strict (issue 39): a squareness of this pair, whichever axis is the reference -
        # never one of another pair.
        return errors, {f"squareness:{name}" for name in SQUARENESS_OF_PAIR[
            "".join(sorted((str(a), str(b))))]}
    if kind == "angular":
        # A tilt of a tool-side axis, smooth along its travel, acting through the machine's
        # real arms. Only one the data can tell from a straightness: its effect must change
        # with another axis' position (the yaw of a table axis about z acts through its
        # own position alone - a straightness by any measurement - and is not drawn).
        return _tilt(layout, layout.tool, rng, magnitude_m, "tool-side")
    if kind == "angular_table":
        # A tilt of an axis that carries the workpiece, the error read where it matters:
        # at the workpiece point under the tool (Kidani eqs. 2.9-2.10, Khan & Chen eq. 17:
        # w the machining point). Its arm runs from the table to the tool, so it changes
        # with the other axes' positions.
        return _tilt(layout, layout.work, rng, magnitude_m, "workpiece-side")
    if kind == "angular_tables":
        # Both axes that carry the workpiece tilt at once (a worn saddle and a worn table).
        if len(layout.work) < 2:
            raise NotDrawn(f"{layout.name}: fewer than two axes carry the workpiece")
        errors, fair = Errors(), set()
        for axis in layout.work[:2]:
            one, names = _tilt(layout, (axis,), rng, magnitude_m, f"{axis} table")
            errors.angular.update(one.angular)
            fair |= names
        return errors, fair
    if kind == "drift":
        sensor = str(rng.choice(["column", "spindle"]))
        rise = survey.temperatures[sensor] - survey.temperatures[sensor][0]
        # A structure that stiffens as it warms: the growth bends away from a straight
        # line in the rise (the catalogue's drift is beta x rise).
        rise = rise - 0.12 * rise ** 2 / max(np.max(np.abs(rise)), 1e-9)
        gain = magnitude_m / max(np.std(rise), 1e-9)
        direction = rng.normal(0, 1, 3)
        direction /= np.linalg.norm(direction)
        errors.tcp.append(gain * rise[:, None] * direction[None, :])
        return errors, {f"structural_thermal_drift:{sensor}", f"thermal_lag:{sensor}"}
    if kind == "backlash":
        step = 2.0 * magnitude_m
        column = np.zeros((survey.time_s.size, 3))
        column[:, c] = 0.5 * step * worn_backlash(survey.q[axis], survey.direction[axis],
                                                  low, high, rng)
        errors.tcp.append(column)
        return errors, {f"reversal:{axis}"}
    if kind == "lag":
        fastest = max(np.max(np.abs(survey.feed[axis])), 1e-9)
        column = np.zeros((survey.time_s.size, 3))
        # A following error that grows faster than the feed (a velocity-dependent gain).
        ratio = survey.feed[axis] / fastest
        column[:, c] = -1.4 * magnitude_m * (ratio + 0.6 * ratio * np.abs(ratio))
        errors.tcp.append(column)
        return errors, {f"servo_lag:{axis}"}
    raise ValueError(f"unknown kind {kind!r}")


def _tilt(layout: Layout, axes: tuple[str, ...], rng: np.random.Generator, magnitude_m: float,
          side: str) -> tuple[Errors, set[str]]:
    """A smooth tilt of one of ``axes`` about a random direction whose effect at the tool
    changes with another axis' position, about ``magnitude_m`` through the longest arm."""
    arm = 0.5 * max(hi - lo for lo, hi in layout.travel.values()) + abs(layout.tool_z_m)
    pairs = [(a, r) for a in axes for r in "XYZ"]
    for k in (rng.permutation(len(pairs)) if pairs else []):
        axis, turn = pairs[k]
        low, high = layout.travel[axis]
        trial = Errors(angular={(axis, "XYZ".index(turn)):
                                spline(rng, low, high, 1.5 * magnitude_m / arm)})
        if _depends_on_other_axes(layout, trial, axis, rng):
            return trial, {f"angular:E{'ABC'['XYZ'.index(turn)]}{axis}"}
    raise NotDrawn(f"{layout.name}: no {side} axis whose tilt acts through another axis' "
                   "position")


class NotDrawn(ValueError):
    """This machine's layout has no such effect to hide (e.g. no tool-side tilt)."""


def _depends_on_other_axes(layout: Layout, errors: Errors, axis: str,
                           rng: np.random.Generator) -> bool:
    """Does the TCP error of ``errors`` change with an axis other than ``axis``? (the part
    no polynomial of ``axis``' position explains is above a tenth)"""
    q = {a: rng.uniform(*layout.travel[a], 400) for a in "XYZ"}
    error = tcp_error(layout, q, errors)
    low, high = layout.travel[axis]
    u = (2 * q[axis] - low - high) / (high - low)
    basis = np.polynomial.legendre.legvander(u, 10)
    rest = error - basis @ np.linalg.lstsq(basis, error, rcond=None)[0]
    return bool(np.linalg.norm(rest) > 0.1 * np.linalg.norm(error - error.mean(axis=0)))


def accepted(name: str, fair: set[str]) -> bool:
    return name in fair or any(f.endswith(":*") and name.startswith(f[:-1]) for f in fair)


def write_survey(survey: Survey, error_m: np.ndarray, noise_m: float,
                 rng: np.random.Generator, directory: Path, give_tool_offset: bool = True
                 ) -> tuple[Path, Path]:
    """The logger's CSV (mm, um, mm/min, degC) and its column map; returns both paths.
    ``give_tool_offset=False``: the map does not say how long the tool is."""
    directory.mkdir(parents=True, exist_ok=True)
    measured = error_m + rng.normal(0.0, noise_m, error_m.shape)
    header = ["time_s"] + [f"{a}_mm" for a in "XYZ"] + [f"d{c}_um" for c in "xyz"] + \
        [f"F{a}_mm_min" for a in "XYZ"] + [f"dir_{a}" for a in "XYZ"] + \
        [f"T_{s}" for s in SENSORS]
    columns = [survey.time_s] + [survey.q[a] * 1e3 for a in "XYZ"] + \
        [measured[:, c] * 1e6 for c in range(3)] + \
        [survey.feed[a] * 60e3 for a in "XYZ"] + [survey.direction[a] for a in "XYZ"] + \
        [survey.temperatures[s] for s in SENSORS]
    rows = np.column_stack(columns)
    csv = directory / "survey.csv"
    csv.write_text(",".join(header) + "\n" + "\n".join(
        ",".join(f"{v:.6f}" for v in row) for row in rows) + "\n")
    column_map = {
        "time": {"column": "time_s", "unit": "s"},
        "positions": {a: {"column": f"{a}_mm", "unit": "mm"} for a in "XYZ"},
        "errors": {c: {"column": f"d{c}_um", "unit": "um"} for c in "xyz"},
        "velocities": {a: {"column": f"F{a}_mm_min", "unit": "mm/min"} for a in "XYZ"},
        "directions": {a: {"column": f"dir_{a}"} for a in "XYZ"},
        "temperatures": {s: {"column": f"T_{s}", "unit": "degC"} for s in SENSORS},
        "uncertainty": {"value": float(2e6 * noise_m), "unit": "um"},
        "tool_offset": {"value": float(survey.layout.tool_z_m * 1e3), "unit": "mm"},
        "work_axes": list(survey.layout.work),
    }
    if not give_tool_offset:
        del column_map["tool_offset"]
    path = directory / "map.yaml"
    path.write_text(yaml.safe_dump(column_map, sort_keys=False))
    return csv, path


def single_effect_trial(machine: str, kind: str | None, seed: int, directory: Path,
                        magnitude_m: float | None = None, noise_m: float = 0.3e-6,
                        readings: int = 500, give_tool_offset: bool = True
                        ) -> tuple[Path, Path, set[str]]:
    """A survey of ``machine`` with one hidden effect (``None``: nothing hidden).

    ``give_tool_offset=False`` leaves the tool's length out of the column map: a tilt
    is then fairly named only with the arm the data identify (``angular_arm``)."""
    rng = np.random.default_rng(seed)
    layout = LAYOUTS[machine]
    survey = make_survey(layout, rng, readings)
    fair: set[str] = set()
    errors = Errors()
    if kind is not None:
        size = magnitude_m if magnitude_m is not None else rng.uniform(2e-6, 5e-6)
        errors, fair = hidden(kind, layout, survey, rng, size)
    error = tcp_error(layout, survey.q, errors)
    csv, column_map = write_survey(survey, error, noise_m, rng, directory, give_tool_offset)
    if not give_tool_offset:
        # A tilt acts through an arm along the tool (z) unless it turns about z (a yaw).
        fair = {name.replace("angular:", "angular_arm:") if name[9] != "C" else name
                for name in fair}
    return csv, column_map, fair


def judged(kind: str | None, named: list[str], fair: set[str]) -> tuple[bool, list[str]]:
    """(right, spurious): the right effect named first (for two tilts at once: both named
    as the first two), and every name beyond the fair ones; nothing hidden: right when
    nothing is named."""
    if kind is None:
        return not named, list(named)
    if kind == "angular_tables":
        right = set(named[:2]) == fair
        return right, [n for n in named if n not in fair]
    right = bool(named) and accepted(named[0], fair)
    return right, [n for n in named[1:] if not accepted(n, fair)]


def weak_bow_trial(sigmas: float, seed: int, directory: Path, readings: int = 300,
                   noise_m: float = 0.5e-6) -> tuple[Path, Path, set[str]]:
    """A straightness bow of X in z alone, its least-squares coefficient ``sigmas``
    standard errors large (noise ``noise_m`` on every component)."""
    rng = np.random.default_rng(seed)
    layout = LAYOUTS["vmc_500"]
    survey = make_survey(layout, rng, readings)
    low, high = layout.travel["X"]
    u = (2 * survey.q["X"] - low - high) / (high - low)
    shape = u ** 2 - np.mean(u ** 2)
    # The coefficient of `shape` has standard error noise / |shape|.
    amplitude = sigmas * noise_m / np.linalg.norm(shape)
    errors = Errors()
    errors.tcp.append(np.column_stack([np.zeros(readings), np.zeros(readings),
                                       amplitude * shape]))
    error = tcp_error(layout, survey.q, errors)
    csv, column_map = write_survey(survey, error, noise_m, rng, directory)
    return csv, column_map, {"straightness:EZX"}


def log_leaving_range(seed: int, path: Path, rows: int = 600) -> Path:
    """A thermal log whose second half leaves the first half's temperature range: the
    growth follows t1 while it warms to 22 degC, then saturates while t1 goes on to
    27 degC; t2 and t3 wander (a heat source elsewhere, the room)."""
    rng = np.random.default_rng(seed)
    time_s = np.arange(rows) * 30.0
    t1 = 20.0 + 7.0 * (time_s / time_s[-1]) ** 1.5 + rng.normal(0, 0.01, rows)
    t2 = 21.0 + 0.5 * np.sin(time_s / 3000.0) + rng.normal(0, 0.01, rows)
    t3 = 20.5 + 0.3 * np.cos(time_s / 5000.0) + rng.normal(0, 0.01, rows)
    growth = 3.0 * np.tanh((t1 - 20.0) / 1.5) + rng.normal(0, 0.05, rows)
    path.write_text("time_s,t1_C,t2_C,t3_C,growth_um\n" + "\n".join(
        f"{a:.1f},{b:.4f},{c:.4f},{d:.4f},{e:.4f}"
        for a, b, c, d, e in zip(time_s, t1, t2, t3, growth)) + "\n")
    return path
