"""A machine the workbench has never seen: hidden effects made outside the package.

This generator shares **no code** with the workbench, the error model or the
kinematic chain of ``mt_accuracy_ros``: it reads a bundled machine
description as plain YAML, builds the rigid-body chain with its own 4x4
matrices (exact rotations from scipy's rotation vectors, errors placed as
ISO 230-1 and Khan & Chen eq. 8 place them: a linear axis' location error
before its motion, a rotary body turned about its actual line (ISO 230-7), error
motions after the motion), integrates thermal lags with
scipy's ODE solver on a dense grid, and draws errors as splines through
random knots or sinusoids - none of them in the workbench's Legendre,
Fourier or exact-lag bases. A mistake in a workbench regressor therefore
cannot cancel out against the same mistake here.

A survey is ``readings`` reference measurements of the TCP error (a laser
tracker or probe: x, y, z with Gaussian noise ``noise_m``) spread over a
few hours of work: random positions, half of them on the fly (feed,
acceleration) and half at a standstill (last direction known), the machine
following a program of spindle speeds and feeds that heats it, four
temperature sensors (column, bed, spindle, ambient) read with 0.02 K noise.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import yaml
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

from studies.shapes import worn_backlash

MACHINES = Path(__file__).resolve().parents[1] / "mt_accuracy_ros" / "machines"
LETTERS = "XYZABC"


# ----------------------------------------------------------------- geometry
@dataclass
class Geometry:
    name: str
    tool_axes: list[str]          # bed outwards
    work_axes: list[str]          # bed outwards
    offsets: dict[str, np.ndarray]
    strokes: dict[str, tuple[float, float]]
    tool: np.ndarray
    workpiece: np.ndarray

    @property
    def axes(self) -> list[str]:
        return self.work_axes + self.tool_axes


def read_geometry(name: str) -> Geometry:
    data = yaml.safe_load((MACHINES / f"{name}.yaml").read_text())
    letters = data["chain"].strip("[]").split()
    bed = letters.index("b")
    work = [c for c in letters[1:bed]][::-1]
    tool = [c for c in letters[bed + 1:-1]]
    axes = data["axes"]
    return Geometry(data["name"], tool, work,
                    {a: np.array(axes[a].get("offset", [0, 0, 0]), float) for a in work + tool},
                    {a: tuple(axes[a]["stroke"]) for a in work + tool},
                    np.array(data["tool"], float), np.array(data["workpiece"], float))


def _homogeneous(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    n = rotation.shape[0]
    out = np.zeros((n, 4, 4))
    out[:, :3, :3] = rotation
    out[:, :3, 3] = translation
    out[:, 3, 3] = 1.0
    return out


def _error_transform(twist: np.ndarray) -> np.ndarray:
    """(N, 6) small displacement (dx, dy, dz, ea, eb, ec) -> (N, 4, 4), exact rotation."""
    return _homogeneous(Rotation.from_rotvec(twist[:, 3:]).as_matrix(), twist[:, :3])


def _motion(letter: str, value: np.ndarray) -> np.ndarray:
    n = value.size
    if letter in "XYZ":
        shift = np.zeros((n, 3))
        shift[:, "XYZ".index(letter)] = value
        return _homogeneous(np.broadcast_to(np.eye(3), (n, 3, 3)), shift)
    vector = np.zeros((n, 3))
    vector[:, "ABC".index(letter)] = value
    return _homogeneous(Rotation.from_rotvec(vector).as_matrix(), np.zeros((n, 3)))


def tcp_point(geometry: Geometry, q: dict[str, np.ndarray], errors: "ErrorSet | None",
              work_point: np.ndarray | None = None) -> np.ndarray:
    """Tool point minus the workpiece point under the tool, bed frame (N, 3).

    The point under the tool is the material the nominal machine puts the tool on: the
    nominal tool point expressed in the nominal workpiece frame (Kidani's w, "the
    machining point"), carried by the actual workpiece frame. ``work_point`` (3,) [m]
    is a target fixed on the workpiece side instead (a probed sphere), in the frame of
    the last workpiece axis after its offset.
    """
    n = next(iter(q.values())).size

    def frames(axes, with_errors):
        frame = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
        parent = np.zeros(3)
        for axis in axes:
            frame = frame @ _homogeneous(np.broadcast_to(np.eye(3), (n, 3, 3)),
                                         np.broadcast_to(parent, (n, 3)))
            located = _error_transform(errors.location(axis, n)) if with_errors else None
            if located is not None and axis in "ABC":
                # ISO 230-7: the body turns about the actual line (set up at 0): the
                # motion conjugated by the line's displacement, zero effect at q = 0.
                frame = frame @ located @ _motion(axis, q[axis]) @ np.linalg.inv(located)
            elif located is not None:
                frame = frame @ located @ _motion(axis, q[axis])
            else:
                frame = frame @ _motion(axis, q[axis])
            if with_errors:
                frame = frame @ _error_transform(errors.motion(axis, q))
            parent = geometry.offsets[axis]
        return frame @ _homogeneous(np.broadcast_to(np.eye(3), (n, 3, 3)),
                                    np.broadcast_to(parent, (n, 3)))

    tip = np.append(np.asarray(geometry.tool, float), 1.0)
    nominal_tool = frames(geometry.tool_axes, False) @ tip
    if work_point is None:
        under_tool = np.einsum("nij,nj->ni", np.linalg.inv(frames(geometry.work_axes, False)),
                               nominal_tool)
    else:
        under_tool = np.broadcast_to(np.append(np.asarray(work_point, float), 1.0), (n, 4))
    with_errors = errors is not None
    tool = frames(geometry.tool_axes, with_errors) @ tip
    work = np.einsum("nij,nj->ni", frames(geometry.work_axes, with_errors), under_tool)
    return tool[:, :3] - work[:, :3]


@dataclass
class ErrorSet:
    """Errors injected into the chain: functions of the state, per axis (N, 6)."""

    motion_fns: dict[str, list[Callable]] = field(default_factory=dict)
    location_fns: dict[str, list[Callable]] = field(default_factory=dict)
    state: dict = field(default_factory=dict)

    def motion(self, axis: str, q: dict) -> np.ndarray:
        n = next(iter(q.values())).size
        out = np.zeros((n, 6))
        for fn in self.motion_fns.get(axis, []):
            out += fn(q, self.state)
        return out

    def location(self, axis: str, n: int) -> np.ndarray:
        out = np.zeros((n, 6))
        for fn in self.location_fns.get(axis, []):
            out += np.broadcast_to(fn(self.state), (n, 6))
        return out


# ----------------------------------------------------------------- the machine's day
@dataclass
class Survey:
    machine: str
    time_s: np.ndarray
    positions: dict[str, np.ndarray]
    velocities: dict[str, np.ndarray]
    accelerations: dict[str, np.ndarray]
    directions: dict[str, np.ndarray]
    temperatures: dict[str, np.ndarray]     # measured, degC
    spindle_speed_rad_s: np.ndarray
    program_feed: dict[str, np.ndarray]     # |feed| the program ran at [m/s]
    true_temperatures: dict[str, np.ndarray]
    dense_time_s: np.ndarray
    dense_rpm: np.ndarray
    dense_feed: dict[str, np.ndarray]
    dense_temperatures: dict[str, np.ndarray]


def _lag_ode(time_s: np.ndarray, signal: np.ndarray, tau_s: float, y0: float) -> np.ndarray:
    """tau y' = u - y with u linear between the dense samples, by scipy's RK45."""
    solution = solve_ivp(lambda t, y: (np.interp(t, time_s, signal) - y) / tau_s,
                         (time_s[0], time_s[-1]), [y0], t_eval=time_s, rtol=1e-8, atol=1e-10,
                         max_step=max(30.0, tau_s / 50.0))
    return solution.y[0]


def machine_day(machine: str, seed: int, readings: int = 720, hours: float = 3.0) -> Survey:
    """Positions, motion, spindle program and temperatures of one survey."""
    geometry = read_geometry(machine)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0xF0E1]))
    duration = hours * 3600.0
    dense = np.arange(0.0, duration + 5.0, 5.0)
    # The program: segments of 8-30 min, each with a spindle speed and feeds.
    bounds = [0.0]
    while bounds[-1] < duration:
        bounds.append(bounds[-1] + rng.uniform(480, 1800))
    segment = np.searchsorted(bounds, dense, side="right") - 1
    rpm_levels = rng.choice([0.0, 3000.0, 6000.0, 9000.0, 12000.0], len(bounds))
    rpm = rpm_levels[segment]
    linear = [a for a in geometry.axes if a in "XYZ"]
    feed_levels = {a: rng.uniform(0.0, 0.33, len(bounds)) for a in geometry.axes}
    feed = {a: feed_levels[a][segment] for a in geometry.axes}
    # Temperatures: an ambient swing plus heat from the spindle and the axes.
    ambient = 20.0 + 0.8 * np.sin(2 * np.pi * dense / (6 * 3600) + rng.uniform(0, 6.3)) + \
        np.cumsum(rng.normal(0, 0.003, dense.size))
    spindle_heat = rpm / 12000.0
    axis_heat = sum(feed[a] for a in linear) / 0.33
    temperatures = {
        "ambient": ambient,
        "spindle": _lag_ode(dense, ambient + 6.0 * spindle_heat, rng.uniform(500, 900),
                            ambient[0]),
        "column": _lag_ode(dense, ambient + 2.5 * spindle_heat + 0.8 * axis_heat,
                           rng.uniform(2000, 3500), ambient[0]),
        "bed": _lag_ode(dense, ambient + 1.5 * axis_heat, rng.uniform(3000, 5000), ambient[0]),
    }
    # Readings: random stops and on-the-fly readings, in time order.
    t = np.sort(rng.uniform(60.0, duration, readings))
    positions, velocities, accelerations, directions = {}, {}, {}, {}
    moving = rng.random(readings) < 0.5
    for axis in geometry.axes:
        low, high = geometry.strokes[axis]
        margin = 0.05 * (high - low)
        positions[axis] = rng.uniform(low + margin, high - margin, readings)
        program = np.interp(t, dense, feed[axis])
        sign = rng.choice([-1.0, 1.0], readings)
        velocities[axis] = np.where(moving, sign * program * rng.uniform(0.6, 1.0, readings),
                                    0.0)
        accelerations[axis] = np.where(moving, rng.uniform(-2.0, 2.0, readings), 0.0)
        directions[axis] = sign
    true = {k: np.interp(t, dense, v) for k, v in temperatures.items()}
    measured = {k: v + rng.normal(0, 0.02, readings) for k, v in true.items()}
    return Survey(machine, t, positions, velocities, accelerations, directions, measured,
                  np.interp(t, dense, rpm) * 2 * np.pi / 60.0,
                  {a: np.interp(t, dense, feed[a]) for a in geometry.axes}, true, dense, rpm,
                  feed, temperatures)


# ----------------------------------------------------------------- hidden effects
def _smooth(rng, low, high, knots=6):
    """A smooth random curve over [low, high] (cubic spline, unit RMS, no line in it)."""
    x = np.linspace(low, high, knots)
    spline = CubicSpline(x, rng.normal(0, 1, knots))
    grid = np.linspace(low, high, 400)
    values = spline(grid)
    line = np.polyfit(grid, values, 1)
    rms = np.sqrt(np.mean((values - np.polyval(line, grid)) ** 2)) or 1.0
    return lambda q: (spline(q) - np.polyval(line, q)) / rms


def _periodic(rng, period: float, knots: int = 6):
    """A measured-looking periodic error: a periodic cubic spline through random knots
    over one period (zero mean, unit RMS) - a shape no one- or two-harmonic sine is."""
    x = np.linspace(0.0, period, knots + 1)
    y = rng.normal(0, 1, knots + 1)
    y[-1] = y[0]
    spline = CubicSpline(x, y, bc_type="periodic")
    grid = np.linspace(0.0, period, 400, endpoint=False)
    mean, rms = float(np.mean(spline(grid))), float(np.std(spline(grid))) or 1.0
    return lambda q: (spline(np.mod(q, period)) - mean) / rms


def _component(letter: str) -> int:
    return "XYZABC".index(letter)


@dataclass
class Hidden:
    """One hidden effect: what it is called, the names the workbench may give it, the
    variables it lives in, and how it acts (errors in the chain and/or a TCP offset)."""

    kind: str
    accepted: set[str]
    variables: set[str]
    errors: ErrorSet = field(default_factory=ErrorSet)
    offset: Callable | None = None          # (survey) -> (N, 3) TCP error [m]


def _twist(index: int, values: np.ndarray) -> np.ndarray:
    out = np.zeros((values.size, 6))
    out[:, index] = values
    return out


def make_hidden(kind: str, survey: Survey, rng: np.random.Generator) -> Hidden:
    """A hidden effect of ``kind`` at unit magnitude (scaled later)."""
    geometry = read_geometry(survey.machine)
    linear = [a for a in geometry.axes if a in "XYZ"]
    rotary = [a for a in geometry.axes if a in "ABC"]
    axis = str(rng.choice(linear))
    dense = survey.dense_time_s

    def lag_at_readings(signal, tau, from_rest=False):
        y0 = 0.0 if from_rest else signal[0]
        return np.interp(survey.time_s, dense, _lag_ode(dense, signal, tau, y0))

    def rise(name):
        values = survey.dense_temperatures[name]
        return values - values[0]

    # Where an effect may fairly be said to live: its sensor, that sensor against the
    # ambient it rises from, or the sensor's lag.
    def thermal_names(sensor):
        return {f"T_{sensor}", f"T_ambient-{sensor}"} | {f"T_{sensor}@{m}min"
                                                         for m in (10, 20, 40)}

    # On a 5-axis machine a rotary axis turns the lever of every error behind it; an
    # angle acting through an Abbe arm lives in the product of two positions.
    positions_all = {a.lower() for a in linear} | {a.lower() for a in rotary} | \
        {f"{a.lower()}*{b.lower()}" for i, a in enumerate(sorted(linear))
         for b in sorted(linear)[i + 1:]}

    # Where a geometric error of one axis pair lives: either position, or their product
    # (an angle acting through the other axis' arm).
    def pair_variables(a: str, b: str) -> set[str]:
        a, b = sorted((a.lower(), b.lower()))
        return {a, b, f"{a}*{b}"}

    def squared_pair(name: str) -> set[str]:
        """The variables of the pair a squareness (e.g. EC0Y: X and Y) joins."""
        turned = name[1].translate(ROTATION_AXIS)
        return pair_variables(*(c for c in "XYZ" if c != turned))

    if kind == "ballscrew_pitch":
        pitch = rng.uniform(0.004, 0.02)
        shape = _periodic(rng, pitch)
        e = ErrorSet({axis: [lambda q, s: _twist(_component(axis), shape(q[axis]))]})
        return Hidden(kind, {f"positioning_periodic:E{axis}{axis}"}, {axis.lower()}, e)
    if kind == "positioning":
        curve = _smooth(rng, *geometry.strokes[axis])
        e = ErrorSet({axis: [lambda q, s: _twist(_component(axis), curve(q[axis]))]})
        return Hidden(kind, {f"positioning:E{axis}{axis}"}, {axis.lower()}, e)
    if kind == "straightness":
        direction = str(rng.choice([c for c in "XYZ" if c != axis]))
        curve = _smooth(rng, *geometry.strokes[axis])
        e = ErrorSet({axis: [lambda q, s: _twist(_component(direction), curve(q[axis]))]})
        return Hidden(kind, {f"straightness:E{direction}{axis}"}, {axis.lower()}, e)
    if kind == "angular":
        rotation = str(rng.choice(list("ABC")))
        curve = _smooth(rng, *geometry.strokes[axis])
        # ~1 urad per um at a 0.3 m arm: scaled to the TCP later.
        e = ErrorSet({axis: [lambda q, s: _twist(_component(rotation), curve(q[axis]))]})
        # Strict: the axis' own position, or its product with another axis (the arm).
        return Hidden(kind, {f"angular:E{rotation}{axis}"},
                      {axis.lower()} | {v for v in positions_all
                                        if "*" in v and axis.lower() in v.split("*")}, e)
    if kind == "squareness":
        name = str(rng.choice(["EC0Y", "EB0Z", "EA0Z"]))
        e = ErrorSet(location_fns={name[-1]: [lambda s: _twist(_component(name[1]),
                                                               np.ones(1))[0]]})
        # The right pair, either axis the reference: where the error is taken (the
        # machining point) a turned table and a tilted travel of the same pair differ by
        # a constant, which no zeroed instrument sees.
        return Hidden(kind, {f"squareness:{other}" for other in SAME_PAIR[name]},
                      squared_pair(name), e)
    if kind == "thermal_squareness":
        name = str(rng.choice(["EC0Y", "EB0Z", "EA0Z"]))
        difference = np.interp(survey.time_s, dense, rise("column") - rise("bed"))
        e = ErrorSet(location_fns={name[-1]: [lambda s: _twist(_component(name[1]),
                                                               s["difference"])]},
                     state={"difference": difference})
        return Hidden(kind, {f"thermal_squareness:{name}:bed-column",
                             f"thermal_squareness:{name}:column-bed"},
                      thermal_names("bed") | thermal_names("column") | {"T_bed-column"} |
                      squared_pair(name), e)
    if kind == "structural_drift":
        beta = rng.normal(0, 1, 3)
        values = np.interp(survey.time_s, dense, rise("column"))
        # A structure that stiffens as it warms: the growth bends away from a straight
        # line in the rise (not the catalogue's beta x rise).
        values = values - 0.12 * values ** 2 / max(np.max(np.abs(values)), 1e-9)
        return Hidden(kind, {"structural_thermal_drift:column"}, thermal_names("column"),
                      offset=lambda s: np.outer(values, beta))
    if kind == "lagged_growth":
        tau = rng.uniform(900, 1800)
        values = lag_at_readings(rise("spindle"), tau)
        beta = np.array([0.1, 0.2, 1.0]) * rng.choice([-1, 1])
        return Hidden(kind, {"thermal_lag:spindle"}, thermal_names("spindle"),
                      offset=lambda s: np.outer(values, beta))
    if kind == "gradient_bending":
        values = np.interp(survey.time_s, dense, rise("spindle") - rise("column"))
        beta = rng.normal(0, 1, 3)
        return Hidden(kind, {"thermal_gradient:column-spindle"},
                      {"T_column-spindle", "T_spindle", "T_column"},
                      offset=lambda s: np.outer(values, beta))
    if kind == "spindle_heat":
        tau = rng.uniform(600, 1500)
        values = lag_at_readings(survey.dense_rpm / 1000.0, tau, from_rest=True)
        beta = np.array([0.0, 0.3, 1.0])
        # The spindle sensor reads the same heat through its own lag: naming it (alone, or
        # against the ambient it rises from) identifies the spindle as the source too.
        return Hidden(kind, {"heat_source:spindle_speed", "thermal_lag:spindle",
                             "structural_thermal_drift:spindle",
                             "thermal_gradient:ambient-spindle"},
                      {"spindle_speed"} | thermal_names("spindle") |
                      {f"spindle_speed@{m}min" for m in (10, 20, 40)},
                      offset=lambda s: np.outer(values, beta))
    if kind == "axis_heat":
        tau = rng.uniform(900, 2400)
        values = lag_at_readings(survey.dense_feed[axis] * 60.0, tau, from_rest=True)
        direction = np.zeros(3)
        direction[_component(axis)] = 1.0
        # The generator's bed and column warm from the axes' motion: their sensors
        # (against the ambient they rise from) are where this heat shows.
        return Hidden(kind, {f"heat_source:feed_{axis}"}, {f"v_{axis.lower()}"} |
                      {f"|v_{axis.lower()}|@{m}min" for m in (10, 20, 40)} |
                      thermal_names("bed") | thermal_names("column"),
                      offset=lambda s: np.outer(values, direction))
    if kind == "position_thermal":
        sensor = str(rng.choice(["bed", "column"]))
        values = np.interp(survey.time_s, dense, rise(sensor))
        e = ErrorSet({axis: [lambda q, s: _twist(_component(axis), q[axis] * s["rise"])]},
                     state={"rise": values})
        return Hidden(kind, {f"position_dependent_thermal:{axis}:{sensor}"},
                      {axis.lower()} | thermal_names(sensor), e)
    if kind == "backlash":
        lost = -0.5 * worn_backlash(survey.positions[axis], survey.directions[axis],
                                    *geometry.strokes[axis], rng)
        e = ErrorSet({axis: [lambda q, s: _twist(_component(axis), lost)]})
        return Hidden(kind, {f"reversal:{axis}"}, {f"dir_{axis.lower()}",
                                                   f"v_{axis.lower()}"}, e)
    if kind == "servo_lag":
        velocity = survey.velocities[axis]
        fastest = max(np.max(np.abs(velocity)), 1e-12)
        # A lag of another order: the following error grows faster than the feed (a
        # velocity-dependent gain), not the catalogue's constant-gain -v.
        lag = -(velocity + 0.6 * velocity * np.abs(velocity) / fastest)
        e = ErrorSet({axis: [lambda q, s: _twist(_component(axis), lag)]})
        return Hidden(kind, {f"servo_lag:{axis}"}, {f"v_{axis.lower()}"}, e)
    if kind == "acceleration":
        acceleration = survey.accelerations[axis]
        direction = rng.normal(0, 1, 3)
        return Hidden(kind, {f"acceleration:{axis}"}, {f"acc_{axis.lower()}"},
                      offset=lambda s: np.outer(acceleration, direction))
    if kind == "twist":
        a, b = sorted(rng.choice(linear, 2, replace=False))
        centre = {k: np.mean(geometry.strokes[k]) for k in (a, b)}
        component = str(rng.choice(list("xyz")))
        pa, pb = survey.positions[a] - centre[a], survey.positions[b] - centre[b]

        half = 0.5 * (geometry.strokes[a][1] - geometry.strokes[a][0])

        def offset(s):
            # A twisted way: the product of the two positions, its rate changing along a's
            # travel (not the catalogue's plain p_a p_b).
            out = np.zeros((pa.size, 3))
            out[:, "xyz".index(component)] = pa * pb * (1.0 + 0.4 * np.tanh(2.0 * pa / half))
            return out
        return Hidden(kind, {f"cross_axis:{a}{b}"}, {f"{a.lower()}*{b.lower()}"}, offset=offset)
    if kind == "rotary_offset":
        if not rotary:
            raise ValueError("rotary_offset needs a rotary axis")
        r_axis = str(rng.choice(rotary))
        along = "XYZ"["ABC".index(r_axis)]
        options = [f"E{c}0{r_axis}" for c in "XYZ" if c != along] + \
            [f"E{c}0{r_axis}" for c in "ABC" if c != r_axis]

        def seen(name):
            # A location error whose whole effect is a constant shift (e.g. an offset of
            # the chain's last axis) cannot be seen by any instrument: not drawn.
            errors = ErrorSet(location_fns={r_axis: [lambda s: _twist(_component(name[1]),
                                                                      1e-6 * np.ones(1))[0]]})
            moved = tcp_point(geometry, survey.positions, errors) - \
                tcp_point(geometry, survey.positions, None)
            return _rms(moved) > 1e-9
        which = str(rng.choice([name for name in options if seen(name)]))
        e = ErrorSet(location_fns={r_axis: [lambda s: _twist(_component(which[1]),
                                                             np.ones(1))[0]]})
        return Hidden(kind, {f"rotary_location:{r_axis}"}, {r_axis.lower()} |
                      {a.lower() for a in linear}, e)
    if kind == "rotary_runout":
        if not rotary:
            raise ValueError("rotary_runout needs a rotary axis")
        r_axis = str(rng.choice(rotary))
        component = str(rng.choice([c for c in "XYZ"]))
        phase = rng.uniform(0, 2 * np.pi)
        e = ErrorSet({r_axis: [lambda q, s: _twist(_component(component),
                                                   np.cos(2 * q[r_axis] + phase))]})
        return Hidden(kind, {f"rotary_error:E{component}{r_axis}"}, {r_axis.lower()}, e)
    raise ValueError(f"unknown hidden effect kind {kind!r}")


#: The linear axis a rotation letter turns about (A about X, ...).
ROTATION_AXIS = str.maketrans("ABC", "XYZ")

#: The squareness names of one axis pair (the location error and the two travel slopes).
SAME_PAIR = {"EC0Y": ("EC0Y", "EYX", "EXY"), "EB0Z": ("EB0Z", "EZX", "EXZ"),
             "EA0Z": ("EA0Z", "EZY", "EYZ")}


KINDS_3AXIS = ("ballscrew_pitch", "positioning", "straightness", "angular", "squareness",
               "thermal_squareness", "structural_drift", "lagged_growth", "gradient_bending",
               "spindle_heat", "axis_heat", "position_thermal", "backlash", "servo_lag",
               "acceleration", "twist")
KINDS_ROTARY = ("rotary_offset", "rotary_runout")


def effect_error(geometry: Geometry, survey: Survey, hidden: Hidden, scale: float
                 ) -> np.ndarray:
    """(N, 3) TCP error of one hidden effect at ``scale`` (chain errors and offsets)."""
    errors = ErrorSet({k: [(lambda f: (lambda q, s: scale * f(q, s)))(f) for f in v]
                       for k, v in hidden.errors.motion_fns.items()},
                      {k: [(lambda f: (lambda s: scale * f(s)))(f) for f in v]
                       for k, v in hidden.errors.location_fns.items()}, hidden.errors.state)
    out = tcp_point(geometry, survey.positions, errors) - tcp_point(geometry, survey.positions,
                                                                    None)
    if hidden.offset is not None:
        out = out + scale * hidden.offset(hidden.errors.state)
    return out


def _rms(error: np.ndarray) -> float:
    centred = error - error.mean(axis=0)
    return float(np.sqrt(np.mean(np.sum(centred ** 2, axis=1))))


@dataclass
class Trial:
    survey: Survey
    hidden: list[Hidden]
    truth_m: np.ndarray        # (N, 3) noise-free TCP error of the hidden effects
    measured_m: np.ndarray     # (N, 3)
    magnitudes_m: list[float]  # RMS at the TCP of each hidden effect
    noise_m: float


def make_trial(machine: str, kinds: tuple[str, ...], seed: int, *, noise_m: float = 0.7e-6,
               readings: int = 720, magnitudes_m: tuple[float, ...] | None = None) -> Trial:
    """A survey of ``machine`` with the hidden effects ``kinds`` (2-20 um RMS each)."""
    survey = machine_day(machine, seed, readings)
    geometry = read_geometry(machine)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0xE77EC7, len(kinds)]))
    hidden, truth, sizes = [], np.zeros((readings, 3)), []
    for i, kind in enumerate(kinds):
        effect = make_hidden(kind, survey, rng)
        target = magnitudes_m[i] if magnitudes_m else float(np.exp(rng.uniform(np.log(2e-6),
                                                                              np.log(20e-6))))
        unit = _rms(effect_error(geometry, survey, effect, 1e-6))
        scale = 1e-6 * target / unit
        truth += effect_error(geometry, survey, effect, scale)
        hidden.append(effect)
        sizes.append(target)
    noise = np.random.default_rng(np.random.SeedSequence([seed, 0x0715E])).normal(
        0.0, noise_m, truth.shape)
    return Trial(survey, hidden, truth, truth + noise, sizes, noise_m)
