"""Motion programs of the virtual machine tool, evaluated vectorised.

A program is a list of waypoints (axis positions) joined by straight moves at a
feed, with optional dwells; it repeats until the scenario ends. Evaluating it
at N sample times is one ``searchsorted`` plus linear interpolation - no
per-sample Python - which keeps the simulator above 10^6 samples/s.

Programs (Kidani chapters 3-4):

* ``back_and_forth`` - full-stroke runs of one or more axes, the warm-up of
  section 3.3.3;
* ``cutting_passes`` - repeated passes at 1,000 mm/min over the stroke with a
  rapid return (Fig. 4.4, five passes);
* ``stop_and_measure`` - steps of 40 mm with a dwell at each position for the
  laser (Fig. 3.15, y_0 = -440 mm ... y_11 = 0 mm);
* ``diagonal`` - body or face diagonals of the work volume (ISO 230-6);
* ``circle`` - a circle for the ball bar (ISO 230-4), evaluated in closed form.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.errors import ScenarioError
from ..core.kinematics.machine import MachineDescription

MM_PER_MIN = 1e-3 / 60.0  # [m/s] per mm/min


@dataclass
class Program:
    """Waypoints, the segment times between them, and the axes they move.

    ``knots_s`` (K,) are the times at which the machine is at ``waypoints`` (K, A)
    (A = len(axes)); between knots it moves linearly. The program repeats with
    period ``knots_s[-1]`` unless ``repeat`` is False (then it holds the end).
    """

    axes: tuple[str, ...]
    knots_s: NDArray[np.float64]
    waypoints: NDArray[np.float64]
    repeat: bool = True
    dwell_points: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 0)))
    dwell_windows_s: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))

    @property
    def period_s(self) -> float:
        return float(self.knots_s[-1])

    def command(self, time_s: ArrayLike) -> dict[str, NDArray[np.float64]]:
        """Commanded position of every program axis at ``time_s`` [m]."""
        t = np.asarray(time_s, dtype=np.float64)
        if self.repeat and self.period_s > 0:
            t = np.mod(t, self.period_s)
        else:
            t = np.clip(t, 0.0, self.period_s)
        return {axis: np.interp(t, self.knots_s, self.waypoints[:, i])
                for i, axis in enumerate(self.axes)}

    def dwell_mask(self, time_s: ArrayLike, settle_s: float = 0.0) -> NDArray[np.int64]:
        """Index of the dwell each sample lies in (after ``settle_s``), or -1."""
        t = np.asarray(time_s, dtype=np.float64)
        if self.repeat and self.period_s > 0:
            t = np.mod(t, self.period_s)
        out = np.full(t.shape, -1, dtype=np.int64)
        for i, (start, end) in enumerate(self.dwell_windows_s):
            out[(t >= start + settle_s) & (t < end)] = i
        return out


def _build(axes, points: list[list[float]], feeds: list[float], dwells: list[float],
           repeat: bool = True) -> Program:
    """Waypoints joined at ``feeds[i]`` (move i -> i+1), then ``dwells[i+1]`` at the target."""
    knots = [0.0]
    waypoints = [points[0]]
    dwell_windows = []
    if dwells[0] > 0:
        dwell_windows.append((0.0, dwells[0]))
        knots.append(dwells[0])
        waypoints.append(points[0])
    for i in range(1, len(points)):
        distance = float(np.linalg.norm(np.subtract(points[i], points[i - 1])))
        knots.append(knots[-1] + max(distance / feeds[i - 1], 1e-6))
        waypoints.append(points[i])
        if dwells[i] > 0:
            dwell_windows.append((knots[-1], knots[-1] + dwells[i]))
            knots.append(knots[-1] + dwells[i])
            waypoints.append(points[i])
    return Program(tuple(axes), np.array(knots), np.array(waypoints, dtype=np.float64),
                   repeat=repeat, dwell_points=np.array(points),
                   dwell_windows_s=np.array(dwell_windows).reshape(-1, 2))


def _independent_back_and_forth(machine: MachineDescription, axes, feed_m_per_min: float,
                                axis_feeds: dict) -> Program:
    from fractions import Fraction
    from math import gcd, lcm

    unknown = set(axis_feeds) - set(axes)
    if unknown:
        raise ScenarioError(f"axis_feeds_m_per_min names {sorted(unknown)[0]!r}, not one of "
                            f"the program's axes {list(axes)}")
    strokes = {a: _stroke(machine, a) for a in axes}
    periods = {a: 2.0 * (strokes[a][1] - strokes[a][0]) /
               _feed(float(axis_feeds.get(a, feed_m_per_min))) for a in axes}
    base = periods[axes[0]]
    ratios = {a: Fraction(periods[a] / base).limit_denominator(16) for a in axes}
    # The program period: the shortest time holding a whole number of every axis'
    # (slightly adjusted) cycles - base x lcm(numerators) / gcd(denominators).
    period = float(base * lcm(*(r.numerator for r in ratios.values())) /
                   gcd(*(r.denominator for r in ratios.values())))
    cycles = {a: max(1, int(round(period / periods[a]))) for a in axes}
    knots = sorted({round(k * period / (2 * cycles[a]), 12) for a in axes
                    for k in range(2 * cycles[a] + 1)})
    knots = np.array(knots)
    waypoints = np.empty((knots.size, len(axes)))
    for j, axis in enumerate(axes):
        low, high = strokes[axis]
        phase = np.mod(knots * cycles[axis] / period, 1.0)
        phase[-1] = 0.0 if knots[-1] >= period - 1e-12 else phase[-1]
        waypoints[:, j] = low + (high - low) * (1.0 - np.abs(2.0 * phase - 1.0))
    return Program(axes, knots, waypoints, repeat=True,
                   dwell_points=np.zeros((0, len(axes))), dwell_windows_s=np.zeros((0, 2)))


def _stroke(machine: MachineDescription, axis: str) -> tuple[float, float]:
    if axis not in machine.axes:
        raise ScenarioError(f"axis {axis!r} is not an axis of machine {machine.name} "
                            f"({', '.join(machine.axis_order)})")
    low, high = machine.axes[axis].stroke
    return float(low), float(high)


def _check_inside(machine: MachineDescription, axis: str, value: float, what: str) -> None:
    low, high = _stroke(machine, axis)
    if not low - 1e-9 <= value <= high + 1e-9:
        raise ScenarioError(f"{what} = {value:g} m is outside the {axis} stroke "
                            f"[{low:g}, {high:g}] m")


def back_and_forth(machine: MachineDescription, axes=("X",), feed_m_per_min: float = 30.0,
                   start_m: float | None = None, end_m: float | None = None,
                   dwell_s: float = 0.0, axis_feeds_m_per_min: dict | None = None) -> Program:
    """Full-stroke (or ``start_m``..``end_m``) back-and-forth runs of ``axes`` together.

    With ``axis_feeds_m_per_min`` ({axis: feed}) each axis runs its own full-stroke
    back-and-forth at its own feed, so that the axes' positions do not move in lock
    step (a reference survey on the fly then sees every axis' errors apart). Each
    feed is adjusted by at most 1/16 of a cycle so that every axis closes a whole
    number of cycles within the program period.
    """
    axes = tuple(axes)
    if axis_feeds_m_per_min:
        return _independent_back_and_forth(machine, axes, feed_m_per_min, axis_feeds_m_per_min)
    lows, highs = [], []
    for axis in axes:
        low, high = _stroke(machine, axis)
        a = low if start_m is None else float(start_m)
        b = high if end_m is None else float(end_m)
        _check_inside(machine, axis, a, "start_m")
        _check_inside(machine, axis, b, "end_m")
        lows.append(a)
        highs.append(b)
    feed = _feed(feed_m_per_min)
    return _build(axes, [lows, highs, lows], [feed, feed], [dwell_s, dwell_s, 0.0])


def cutting_passes(machine: MachineDescription, axis: str = "X",
                   feed_mm_per_min: float = 1000.0, rapid_m_per_min: float = 30.0,
                   start_m: float | None = None, end_m: float | None = None,
                   passes: int = 5) -> Program:
    """``passes`` cutting passes at ``feed_mm_per_min`` with rapid returns (Kidani Fig. 4.4).

    Does not repeat: after the last pass the axis holds at the start.
    """
    low, high = _stroke(machine, axis)
    a = low if start_m is None else float(start_m)
    b = high if end_m is None else float(end_m)
    _check_inside(machine, axis, a, "start_m")
    _check_inside(machine, axis, b, "end_m")
    if int(passes) < 1:
        raise ScenarioError(f"passes must be >= 1, got {passes}")
    feed = feed_mm_per_min * MM_PER_MIN
    if not feed > 0:
        raise ScenarioError(f"feed_mm_per_min must be > 0, got {feed_mm_per_min}")
    rapid = _feed(rapid_m_per_min)
    points, feeds = [[a]], []
    for _ in range(int(passes)):
        points += [[b], [a]]
        feeds += [feed, rapid]
    return _build((axis,), points, feeds + [feed], [0.0] * len(points), repeat=False)


def stop_and_measure(machine: MachineDescription, axis: str = "Y", step_m: float = 0.04,
                     start_m: float | None = None, end_m: float | None = None,
                     dwell_s: float = 2.0, feed_m_per_min: float = 5.0,
                     both_directions: bool = False) -> Program:
    """Steps of ``step_m`` with a ``dwell_s`` stop at each (Kidani Fig. 3.15).

    Default for Y of the HMC: y_0 = -440 mm ... y_11 = 0 mm (12 positions).
    """
    low, high = _stroke(machine, axis)
    a = low if start_m is None else float(start_m)
    b = high if end_m is None else float(end_m)
    _check_inside(machine, axis, a, "start_m")
    _check_inside(machine, axis, b, "end_m")
    if not step_m > 0:
        raise ScenarioError(f"step_m must be > 0, got {step_m}")
    direction = 1.0 if b >= a else -1.0
    count = int(np.floor(abs(b - a) / step_m + 1e-9)) + 1
    stops = [a + direction * i * step_m for i in range(count)]
    if both_directions:
        stops = stops + stops[-2::-1]
    feed = _feed(feed_m_per_min)
    points = [[s] for s in stops] + [[stops[0]]]
    return _build((axis,), points, [feed] * len(points), [dwell_s] * len(stops) + [0.0])


def diagonal(machine: MachineDescription, kind: str = "body", feed_m_per_min: float = 5.0,
             dwell_s: float = 1.0, steps: int = 10, corner: int = 0) -> Program:
    """A body diagonal (all linear axes) or a face diagonal (first two) with stops."""
    linear = [a for a in machine.axis_order if not machine.axes[a].is_rotary]
    if kind not in ("body", "face"):
        raise ScenarioError(f"diagonal kind must be 'body' or 'face', got {kind!r}")
    axes = tuple(linear if kind == "body" else linear[:2])
    lows = np.array([_stroke(machine, a)[0] for a in axes])
    highs = np.array([_stroke(machine, a)[1] for a in axes])
    flip = np.array([(corner >> i) & 1 for i in range(len(axes))], dtype=bool)
    start = np.where(flip, highs, lows)
    end = np.where(flip, lows, highs)
    stops = [list(start + (end - start) * i / steps) for i in range(steps + 1)]
    points = stops + stops[-2::-1]
    feed = _feed(feed_m_per_min)
    return _build(axes, points, [feed] * len(points), [dwell_s] * len(points))


def random_points(machine: MachineDescription, axes=None, points: int = 30, seed: int = 0,
                  dwell_s: float = 1.0, feed_m_per_min: float = 10.0,
                  margin: float = 0.02, limits: dict | None = None) -> Program:
    """Stops at ``points`` random positions of the work volume (a volumetric survey,
    e.g. with a laser tracker); every axis moves independently, so position-dependent
    effects (squareness) are separable from one another.

    ``limits``: axis -> [low, high] inside its stroke (e.g. the tilt range a
    five-axis job uses, in rad); the feed is the speed along the path in the
    axes' own units (m, rad) per minute.
    """
    axes = tuple(axes or [a for a in machine.axis_order if not machine.axes[a].is_rotary])
    rng = np.random.default_rng(seed)
    limits = dict(limits or {})
    for axis, span in limits.items():
        if axis not in axes or not isinstance(span, (list, tuple)) or len(span) != 2:
            raise ScenarioError(f"limits: {axis!r} -> [low, high] for one of the moving axes "
                                f"({', '.join(axes)})")
        for value, label in zip(span, ("low", "high")):
            _check_inside(machine, axis, float(value), f"limits {axis} {label}")
        if not float(span[0]) < float(span[1]):
            raise ScenarioError(f"limits {axis}: low must be below high, got {span}")
    lows = np.array([float(limits[a][0]) if a in limits else _stroke(machine, a)[0]
                     for a in axes])
    highs = np.array([float(limits[a][1]) if a in limits else _stroke(machine, a)[1]
                      for a in axes])
    span = highs - lows
    stops = lows + span * margin + rng.random((int(points), len(axes))) * span * (1 - 2 * margin)
    feed = _feed(feed_m_per_min)
    path = [list(p) for p in stops] + [list(stops[0])]
    return _build(axes, path, [feed] * len(path), [dwell_s] * len(stops) + [0.0])


@dataclass
class CircleProgram:
    """A circle in the plane of two linear axes at constant feed (ball bar, ISO 230-4)."""

    axes: tuple[str, str]
    center_m: tuple[float, float]
    radius_m: float
    feed_m_per_s: float
    counter_clockwise: bool = True
    dwell_points: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 0)))
    dwell_windows_s: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))

    @property
    def period_s(self) -> float:
        return 2.0 * np.pi * self.radius_m / self.feed_m_per_s

    def angle(self, time_s: ArrayLike) -> NDArray[np.float64]:
        sign = 1.0 if self.counter_clockwise else -1.0
        return sign * 2.0 * np.pi * np.asarray(time_s, dtype=np.float64) / self.period_s

    def command(self, time_s: ArrayLike) -> dict[str, NDArray[np.float64]]:
        phi = self.angle(time_s)
        return {self.axes[0]: self.center_m[0] + self.radius_m * np.cos(phi),
                self.axes[1]: self.center_m[1] + self.radius_m * np.sin(phi)}

    def dwell_mask(self, time_s: ArrayLike, settle_s: float = 0.0) -> NDArray[np.int64]:
        return np.full(np.shape(time_s), -1, dtype=np.int64)


def circle(machine: MachineDescription, axes=("X", "Y"), radius_m: float = 0.1,
           center_m=None, feed_m_per_min: float = 1.0, counter_clockwise: bool = True
           ) -> CircleProgram:
    """Circle of ``radius_m`` about ``center_m`` (default: middle of the strokes)."""
    axes = tuple(axes)
    if len(axes) != 2:
        raise ScenarioError("circle needs exactly two axes")
    mids = [0.5 * sum(_stroke(machine, a)) for a in axes]
    center = tuple(float(c) for c in (center_m if center_m is not None else mids))
    for axis, c in zip(axes, center):
        _check_inside(machine, axis, c - radius_m, f"circle {axis} minimum")
        _check_inside(machine, axis, c + radius_m, f"circle {axis} maximum")
    if not radius_m > 0:
        raise ScenarioError(f"radius_m must be > 0, got {radius_m}")
    return CircleProgram(axes, center, float(radius_m), _feed(feed_m_per_min), counter_clockwise)


def _feed(feed_m_per_min: float) -> float:
    feed = float(feed_m_per_min) / 60.0
    if not np.isfinite(feed) or feed <= 0:
        raise ScenarioError(f"feed must be finite and > 0 m/min, got {feed_m_per_min}")
    if feed > 1.0 + 1e-12:
        raise ScenarioError(f"feed {feed_m_per_min} m/min exceeds the machine's 60 m/min "
                            "(Kidani Table 3.1)")
    return feed


PROGRAMS = {"back_and_forth": back_and_forth, "cutting_passes": cutting_passes,
            "stop_and_measure": stop_and_measure, "diagonal": diagonal, "circle": circle,
            "random_points": random_points}
