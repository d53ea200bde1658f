"""The virtual machine tool: scales, thermocouples and the true TCP error of a scenario.

:func:`simulate` turns a :class:`~.scenario.Scenario` into a
:class:`SimulationResult`, vectorised over all samples (no per-sample Python),
deterministic for the scenario's seed. What it models, per linear axis with a
scale pair (distance D, Kidani Table 3.1):

* commanded motion from the program; actual position after ``reversal`` and
  ``servo_lag``;
* the pair's true yaw E (``geometric`` profile + ``guideway_deterioration``);
* readings (Kidani eq. 2.13 inverted, scale zero at the low stroke end,
  travel u = q - q_low):

      x1 = q - D/2 E + g1(u) - dL1(u, t) + n1
      x2 = q + D/2 E + g2(u) - dL2(u, t) + u (1/cos delta - 1) + v dt + n2

  with g_i each scale's graduation error (a fraction of the SQ57 accuracy
  (1.5 + 1.5 L) um, Table 3.2), dL_i the thermal expansion (Kidani eq. 3.17),
  delta the parallelism (Kidani eq. 3.5), dt the head timing skew (Kidani eq. 2.20), n_i
  white noise; then quantised to the 10 nm resolution;
* thermocouples every 110 mm on each scale and on the structure, with noise
  and 0.01 K resolution;
* the TCP error relative to the workpiece point under the tool against the
  command, from the simulator's own rigid-body poses (:mod:`.rigid_body`, no
  code of the kinematic model it judges) with every enabled effect, on demand
  at chosen samples (:meth:`tcp_error`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..core.kinematics.machine import COMPONENTS
from ..core.scales.dual_scale import YAW_COMPONENT
from .effects import SineProfile, deterioration_bump, random_profiles
from .programs import PROGRAMS
from .rigid_body import BodyErrors, tool_against_work
from ..core.errors import ScenarioError
from .scenario import MAX_WINDOW_SAMPLES, THERMAL_MOTION_RATE_HZ, Scenario
from .thermal_state import ScaleTemperatureField, first_order_response, thermocouple_positions

#: Default distance between the scales of a pair when the machine file has none [m].
DEFAULT_SCALE_DISTANCE_M = 0.5
#: Rotary encoders: white noise [rad] and resolution (27 bits per turn) [rad].
ENCODER_NOISE_RAD = 0.1e-6
ENCODER_RESOLUTION_RAD = 2.0 * np.pi / 2 ** 27
#: Fastest feed of the test machine [m/s] (60 m/min, Kidani Table 3.1).
MAX_FEED_M_PER_S = 1.0


@dataclass
class SimulationResult:
    """Everything one scenario produced. Arrays are per sample (N,) unless noted."""

    scenario: Scenario
    time_s: NDArray[np.float64]
    command: dict[str, NDArray[np.float64]]
    actual: dict[str, NDArray[np.float64]]
    velocity: dict[str, NDArray[np.float64]]
    scale_axes: list[str]
    scale_channels: list[str]
    scale_readings: NDArray[np.float64]          # (N, 2 * len(scale_axes)) [m]
    scale_distance_m: dict[str, float]
    yaw_truth: dict[str, NDArray[np.float64]]    # true yaw each pair measures [rad]
    temperature_time_s: NDArray[np.float64]      # (M,)
    temperature_names: list[str]
    temperatures_c: NDArray[np.float64]          # (M, S) measured [degC]
    temperatures_true_c: NDArray[np.float64]     # (M, S) [degC]
    thermocouple_positions_m: dict[str, NDArray[np.float64]]
    spindle_speed_rpm: NDArray[np.float64]       # (M,)
    program: object
    first_index: int = 0                         # index of time_s[0] in the whole run
    encoder_axes: list[str] = field(default_factory=list)   # rotary axes with an angle encoder
    encoder_readings: NDArray[np.float64] = field(             # (N, len(encoder_axes)) [rad]
        default_factory=lambda: np.zeros((0, 0)))
    _masks: dict[str, NDArray[np.float64]] = field(repr=False, default_factory=dict)
    _profiles: dict = field(repr=False, default_factory=dict)
    _thermal: dict[str, NDArray[np.float64]] = field(repr=False, default_factory=dict)

    @property
    def sample_rate_hz(self) -> float:
        return self.scenario.sample_rate_hz

    def channel(self, name: str) -> NDArray[np.float64]:
        """Readings of one scale head, e.g. ``"y1"`` [m]."""
        return self.scale_readings[:, self.scale_channels.index(name)]

    def mask(self, effect: str, indices=slice(None)) -> NDArray[np.float64]:
        """1 where ``effect`` is on, per sample."""
        if effect not in self._masks:
            return np.zeros(self.time_s.size)[indices]
        return self._masks[effect][indices]

    def thermal_at(self, key: str, indices) -> NDArray[np.float64]:
        """A thermal response (``column``, ``bed``, ``spindle``, ...) at sample indices."""
        return np.interp(self.time_s[indices], self.temperature_time_s, self._thermal[key])

    def temperature_rise(self, sensor: str) -> NDArray[np.float64]:
        """Measured rise of a thermocouple since the first reading [K], per temperature step."""
        column = self.temperatures_c[:, self.temperature_names.index(sensor)]
        return column - column[0]

    def dwell_groups(self, settle_s: float = 0.5) -> list[NDArray[np.int64]]:
        """Sample indices of each program dwell (after ``settle_s``), in time order."""
        labels = self.program.dwell_mask(self.time_s, settle_s)
        # A repeating program dwells at the same label again; split at gaps.
        index = np.flatnonzero(labels >= 0)
        if index.size == 0:
            return []
        breaks = np.flatnonzero((np.diff(index) > 1) | (np.diff(labels[index]) != 0)) + 1
        return np.split(index, breaks)

    # ------------------------------------------------------------- TCP truth
    def body_errors(self, indices, positions: dict | None = None) -> BodyErrors:
        """The error twists of every body, from every enabled effect, at ``indices``
        (the axes where they were, or at ``positions``: axis -> (N,), the same
        instants), the description's own error functions included."""
        positions = positions or {a: self.actual[a][indices] for a in self.actual}
        scenario = self.scenario
        machine = scenario.machine
        n = int(np.size(self.time_s[indices]))
        errors = BodyErrors()
        c = COMPONENTS.index
        for axis in machine.axis_order:
            spec = machine.axes[axis]
            q = np.broadcast_to(np.asarray(positions[axis], float), (n,))
            for component, function in spec.motion_errors.items():
                value = function(q)
                if np.any(value):
                    errors.add("motion", axis, c(component), value, n)
            for component, value in spec.location_errors.items():
                if value:
                    errors.add("location", axis, c(component), value, n)
        geometric = self.mask("geometric", indices)
        for axis, components in self._profiles.items():
            q = positions[axis]
            for component, profile in components.items():
                errors.add("motion", axis, c(component), profile(q) * geometric, n)
        if scenario.ever_enabled("guideway_deterioration"):
            axis = scenario.parameters("guideway_deterioration")["axis"]
            errors.add("motion", axis, c(YAW_COMPONENT[axis]),
                       self._deterioration_yaw(axis, indices, positions[axis]), n)
        if scenario.ever_enabled("position_dependent_thermal"):
            params = scenario.parameters("position_dependent_thermal")
            axis = params["axis"]
            growth = (float(params["alpha_per_k"])
                      * (positions[axis] - float(params["reference_m"]))
                      * self.thermal_at("bed", indices)
                      * self.mask("position_dependent_thermal", indices))
            errors.add("motion", axis, c(axis), growth, n)
        if scenario.ever_enabled("ballscrew_pitch"):
            params = scenario.parameters("ballscrew_pitch")
            axis = params["axis"]
            amplitude = float(params["amplitude_m"]) * (
                1.0 + float(params["growth_per_k"]) * self.thermal_at("column", indices))
            pitch = amplitude * np.sin(2.0 * np.pi * positions[axis] / float(params["pitch_m"]) +
                                       float(params["phase_rad"]))
            errors.add("motion", axis, c(axis), pitch * self.mask("ballscrew_pitch", indices), n)
        if scenario.ever_enabled("squareness"):
            on = self.mask("squareness", indices)
            for name, value in scenario.parameters("squareness")["errors_rad"].items():
                if name[-1] in machine.axes:
                    # a declared squareness replaces the description's value
                    twist = errors.location.setdefault(name[-1], np.zeros((n, 6)))
                    twist[:, c(name[1])] = float(value) * on
        if scenario.ever_enabled("rotary_location"):
            on = self.mask("rotary_location", indices)
            for name, value in scenario.parameters("rotary_location")["errors"].items():
                errors.add("location", name[-1], c(name[1]), float(value) * on, n)
        if scenario.ever_enabled("rotary_runout"):
            params = scenario.parameters("rotary_runout")
            axis = params["axis"]
            on = self.mask("rotary_runout", indices)
            angle = positions[axis] + float(params["phase_rad"])
            # The two directions across the axis, in cyclic order after its own (A: Y, Z).
            along = "XYZ"["ABC".index(axis)]
            first, second = "XYZ"[("XYZ".index(along) + 1) % 3], "XYZ"[("XYZ".index(along) + 2) % 3]
            radius = float(params["radial_m"]) * on
            for component, value in ((first, radius * np.cos(angle)),
                                     (second, radius * np.sin(angle)),
                                     (axis, float(params["positioning_rad"]) * np.sin(angle) * on)):
                errors.add("motion", axis, c(component), value, n)
        drift = np.zeros((n, 6))
        if scenario.ever_enabled("structural_thermal_drift"):
            beta = np.asarray(scenario.parameters("structural_thermal_drift")["beta_m_per_k"])
            drift[:, :3] += np.outer(self.thermal_at("column", indices)
                                     * self.mask("structural_thermal_drift", indices), beta)
        if scenario.ever_enabled("spindle_thermal_growth"):
            params = scenario.parameters("spindle_thermal_growth")
            direction = np.asarray(params["direction"], dtype=np.float64)
            direction = direction / np.linalg.norm(direction)
            growth = (float(params["growth_m"]) * self.thermal_at("spindle", indices)
                      * self.mask("spindle_thermal_growth", indices))
            drift[:, :3] += np.outer(growth, direction)
        if scenario.ever_enabled("table_tilt"):
            params = scenario.parameters("table_tilt")
            on = self.mask("table_tilt", indices) * (
                1.0 + float(params.get("growth_per_k", 0.0)) * self.thermal_at("bed", indices))
            for name, value in params["errors_rad"].items():
                # A workpiece-side axis' angular error motion that turns from -amplitude
                # to +amplitude over its stroke: a bowed way (a circular-arc straightness)
                # pitches linearly along it; ``bow`` > 0 adds a cubic (a worn middle).
                axis = name[-1]
                low, high = machine.axes[axis].stroke
                u = (2.0 * positions[axis] - (low + high)) / (high - low)
                bow = float(params.get("bow", 0.0))
                errors.add("motion", axis, c(name[1]),
                           float(value) * ((1.0 - bow) * u + bow * u ** 3) * on, n)
        if np.any(drift):
            errors.thermal["bed_tool"] = drift
        return errors

    def _deterioration_yaw(self, axis: str, indices, q=None) -> NDArray[np.float64]:
        params = self.scenario.parameters("guideway_deterioration")
        if axis != params["axis"] or not self.scenario.ever_enabled("guideway_deterioration"):
            return np.zeros(np.size(self.time_s[indices]))
        q = self.actual[axis][indices] if q is None else q
        peak = deterioration_peak_rad(self.scenario)
        return peak * deterioration_bump(q, float(params["start_m"]), float(params["end_m"])) \
            * self.mask("guideway_deterioration", indices)

    def tcp_error(self, indices=None, *, with_orientation: bool = False,
                  work_point: NDArray | None = None):
        """True TCP error against the command (N, 3) [m] (and the tool's orientation
        error (N, 3) [rad] with ``with_orientation``).

        The tool point against the workpiece point under it (the one the command
        puts the tool on), from the simulator's own rigid-body poses
        (:func:`.rigid_body.tool_against_work`) at the actual axis positions
        (reversal, servo lag) with every enabled effect, plus the Abbe term
        eps x offset. ``work_point`` ((3,) [m], workpiece frame) is a fixed
        target instead (an R-test sphere).
        """
        indices = np.arange(self.time_s.size)[slice(None) if indices is None else indices]
        machine = self.scenario.machine
        actual = {a: self.actual[a][indices] for a in machine.axis_order}
        command = {a: self.command[a][indices] for a in machine.axis_order}
        position, orientation = self._pose_error(indices, actual, command, work_point)
        if with_orientation:
            return position, orientation
        return position

    def _pose_error(self, indices, actual: dict, command: dict, work_point=None):
        """(position (N, 3) [m], orientation (N, 3) [rad]) truth at ``actual`` against
        ``command`` in the machine's state at ``indices``, the Abbe term included."""
        machine = self.scenario.machine
        position, orientation = tool_against_work(
            machine, actual, command, self.body_errors(indices, actual), work_point)
        if self.scenario.ever_enabled("abbe_offset"):
            offset = np.asarray(self.scenario.parameters("abbe_offset")["offset_m"], float)
            position = position + np.cross(orientation, offset) \
                * self.mask("abbe_offset", indices)[:, None]
        return position, orientation

    def error_at(self, pose: dict[str, float], index: int) -> NDArray[np.float64]:
        """(3,) the machine's true TCP error [m] at ``pose`` (axis -> command, at rest) in
        the state it was in at sample ``index``: where an instrument zeroed there reads 0."""
        machine = self.scenario.machine
        q = {a: np.array([float(pose[a])]) for a in machine.axis_order}
        return self._pose_error(np.array([index]), q, q)[0][0]

    def rotary_turn(self, indices, turn_rad: NDArray[np.float64]
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """How the tool's pose relative to the workpiece changes when the CNC turns the
        rotary axes by ``turn_rad`` (N, R) beyond the command (a compensation).

        Exact (nominal rigid-body poses at both commands, no linearisation): the
        tool point's shift against the material that was under it (N, 3) [m] and
        the rotation vector (N, 3) [rad], bed frame.
        """
        indices = np.arange(self.time_s.size)[indices]
        machine = self.scenario.machine
        command = {a: self.command[a][indices] for a in machine.axis_order}
        turned = dict(command)
        for k, axis in enumerate(self.encoder_axes):
            turned[axis] = command[axis] + turn_rad[:, k]
        return tool_against_work(machine, turned, command, None)


def yaw_lever_m(machine, axis: str) -> float:
    """|d e_TCP / d E_yaw| of ``axis`` from the simulator's rigid bodies, mid stroke [m].

    The Abbe lever d through which the pair's yaw moves the TCP (Kidani
    eq. 3.14: e_y = E_CY d).
    """
    positions = {a: np.array([0.5 * sum(machine.axes[a].stroke)]) for a in machine.axis_order}
    unit = 1e-6
    errors = BodyErrors()
    errors.add("motion", axis, COMPONENTS.index(YAW_COMPONENT[axis]), unit, 1)
    moved, _ = tool_against_work(machine, positions, positions, errors)
    return float(np.linalg.norm(moved[0]) / unit)


def deterioration_peak_rad(scenario: Scenario) -> float:
    """Peak yaw change of ``guideway_deterioration`` that moves the TCP by ``tcp_change_m``."""
    params = scenario.parameters("guideway_deterioration")
    lever = float(params["lever_m"]) or yaw_lever_m(scenario.machine, params["axis"])
    return float(params["tcp_change_m"]) / lever


def _effect_masks(scenario: Scenario, time_s: NDArray[np.float64]) -> dict[str, NDArray]:
    from .effects import EFFECTS

    masks = {}
    for name in EFFECTS:
        if not scenario.ever_enabled(name):
            continue  # read as zeros by SimulationResult.mask
        on = np.full(time_s.shape, 1.0 if name in scenario.enabled else 0.0)
        for event_time, effect, enable in scenario.events:
            if effect == name:
                on[time_s >= event_time] = 1.0 if enable else 0.0
        masks[name] = on
    return masks


def direction_held(velocity: NDArray[np.float64]) -> NDArray[np.float64]:
    """sign(v), holding the last direction of motion while the axis stands still."""
    moving = np.abs(velocity) > 1e-9
    index = np.where(moving, np.arange(velocity.size), 0)
    np.maximum.accumulate(index, out=index)
    sign = np.sign(velocity[index])
    sign[sign == 0] = 1.0
    return sign


#: Noise is drawn in blocks of this many samples, each from its own seed, so that
#: any window of a run (a live node's chunk) holds exactly the whole run's values.
NOISE_BLOCK = 65536
#: Rate at which the program is sampled to drive the thermal model [Hz].


def _axis_motion(scenario: Scenario, program, time_s: NDArray, masks: dict) -> tuple[dict, dict,
                                                                                     dict]:
    machine = scenario.machine
    moved = program.command(time_s)
    rate = scenario.sample_rate_hz
    n = time_s.size
    command, actual, velocity = {}, {}, {}
    for axis in machine.axis_order:
        low, high = machine.axes[axis].stroke
        home = 0.0 if machine.axes[axis].is_rotary else (low if low <= 0 <= high and low == 0
                                                         else 0.5 * (low + high))
        c = moved.get(axis, np.full(n, home))
        v = np.gradient(c, 1.0 / rate) if n > 1 else np.zeros(n)
        q = c.copy()
        if not machine.axes[axis].is_rotary:
            reversal = scenario.parameters("reversal")
            if axis in reversal["axes"] and scenario.ever_enabled("reversal"):
                q -= direction_held(v) * 0.5 * float(reversal["backlash_m"]) * masks["reversal"]
            lag = scenario.parameters("servo_lag")
            if axis in lag["axes"] and scenario.ever_enabled("servo_lag"):
                q -= v * float(lag["lag_s"]) * masks["servo_lag"]
        command[axis], actual[axis], velocity[axis] = c, q, v
    return command, actual, velocity


def _block_noise(entropy: int, first: int, stop: int, channels: int, sigma: float,
                 stream: int = 0x5CA1E) -> NDArray:
    """White noise (stop - first, channels) identical for any window of the same run."""
    out = np.empty((stop - first, channels))
    for block in range(first // NOISE_BLOCK, (stop - 1) // NOISE_BLOCK + 1 if stop > first else 0):
        rng = np.random.default_rng(np.random.SeedSequence([entropy, stream, block]))
        values = rng.normal(0.0, sigma, (NOISE_BLOCK, channels))
        lo, hi = max(first, block * NOISE_BLOCK), min(stop, (block + 1) * NOISE_BLOCK)
        out[lo - first:hi - first] = values[lo - block * NOISE_BLOCK:hi - block * NOISE_BLOCK]
    return out


def simulate(scenario: Scenario, *, start_index: int = 0, stop_index: int | None = None,
             progress: bool = False) -> SimulationResult:
    """Run ``scenario``: every signal of the virtual machine tool, vectorised.

    ``start_index`` / ``stop_index`` select a window of samples (a live node
    streams a long run chunk by chunk); every value in a window equals the
    whole run's value at the same index. Temperatures always cover the whole run.
    """
    machine = scenario.machine
    seeds = np.random.SeedSequence(scenario.seed).spawn(5)
    noise_entropy = scenario.seed if scenario.noise_seed is None else scenario.noise_seed
    noise_seeds = np.random.SeedSequence(noise_entropy).spawn(5)
    rng_geometry, rng_graduation = (np.random.default_rng(seeds[0]),
                                    np.random.default_rng(seeds[3]))
    rng_thermo = np.random.default_rng(noise_seeds[2])
    total = scenario.n_samples
    rate = scenario.sample_rate_hz
    stop = total if stop_index is None else int(min(max(stop_index, 0), total))
    start = int(min(max(start_index, 0), stop))
    if stop - start > MAX_WINDOW_SAMPLES:
        raise ScenarioError(
            f"{scenario.source}: {stop - start:,} samples at once (duration_s x sample_rate_hz "
            f"= {scenario.duration_s:g} s x {rate:g} Hz) exceed the {MAX_WINDOW_SAMPLES:,} the "
            "simulator holds in memory: simulate it in windows (start_index/stop_index, as "
            "the nodes stream it), or shorten the run or lower the rate")
    program_args = {k: v for k, v in scenario.program.items() if k != "type"}
    program = PROGRAMS[scenario.program["type"]](machine, **program_args)
    # One sample of margin keeps np.gradient central at the window's edges; with
    # reversal on, one program period more finds the last direction of motion.
    lookback = 1
    if scenario.ever_enabled("reversal"):
        lookback += int(np.ceil(program.period_s * rate)) + 1
    lo, hi = max(0, start - lookback), min(total, stop + 1)
    wide_time = np.arange(lo, hi, dtype=np.float64) / rate
    wide_masks = _effect_masks(scenario, wide_time)
    wide = _axis_motion(scenario, program, wide_time, wide_masks)
    keep = slice(start - lo, stop - lo)
    command, actual, velocity = ({a: v[keep] for a, v in part.items()} for part in wide)
    time_s = wide_time[keep]
    masks = {name: mask[keep] for name, mask in wide_masks.items()}
    n = time_s.size

    linear = [a for a in machine.axis_order if not machine.axes[a].is_rotary]
    geometric = scenario.parameters("geometric")
    profiles = random_profiles(linear, rng_geometry, float(geometric["linear_m"]),
                               float(geometric["angular_rad"]))

    # ---- thermal state at the temperature rate
    temperature_rate = scenario.temperature_rate_hz
    m = max(2, int(np.floor(scenario.duration_s * temperature_rate)) + 1)
    temperature_time = np.arange(m) / temperature_rate
    # Heat from motion: the program's speed sampled at a fixed rate over the whole
    # run, averaged per temperature step (independent of the scale sample rate).
    motion_time = np.arange(0.0, scenario.duration_s, 1.0 / THERMAL_MOTION_RATE_HZ)
    motion_velocity = _axis_motion(scenario, program, motion_time,
                                   _effect_masks(scenario, motion_time))[2]
    bins = np.minimum((motion_time * temperature_rate).astype(np.int64), m - 1)
    counts = np.maximum(np.bincount(bins, minlength=m), 1)
    motion_input = {a: np.bincount(bins, np.abs(motion_velocity[a]), minlength=m) / counts
                    / MAX_FEED_M_PER_S for a in linear}
    spindle = scenario.spindle
    speed = np.zeros(m)
    for start, end in spindle.get("intervals_s") or []:
        speed[(temperature_time >= float(start)) & (temperature_time < float(end))] = \
            float(spindle["speed_rpm"])
    spindle_input = speed / max(float(spindle["max_rpm"]), 1.0)
    dt_thermal = 1.0 / temperature_rate
    mean_motion = np.mean([motion_input[a] for a in linear], axis=0)
    ambient_cfg = scenario.ambient
    ambient = float(ambient_cfg["amplitude_k"]) * np.sin(
        2 * np.pi * temperature_time / float(ambient_cfg["period_s"]))
    expansion = scenario.parameters("scale_thermal_expansion")
    drift = scenario.parameters("structural_thermal_drift")
    bed = scenario.parameters("position_dependent_thermal")
    growth = scenario.parameters("spindle_thermal_growth")
    # Normalised to a steady 1 at full, continuous input; the rise parameters scale them.
    thermal = {
        "column": float(drift["rise_k"]) * first_order_response(
            0.6 * np.minimum(mean_motion * 10, 1) + 0.4 * spindle_input, dt_thermal,
            float(drift["time_constant_s"]), 1.0),
        "bed": float(bed["rise_k"]) * first_order_response(
            np.minimum(motion_input.get(bed["axis"], mean_motion) * 10, 1), dt_thermal,
            float(bed["time_constant_s"]), 1.0),
        "spindle": first_order_response(spindle_input, dt_thermal,
                                        float(growth["time_constant_s"]), 1.0),
        "ambient": ambient,
    }

    # ---- scales
    scale_axes = [a for a in linear if a in machine.scale_distance_m] or linear[:3]
    distances = {a: float(machine.scale_distance_m.get(a, DEFAULT_SCALE_DISTANCE_M))
                 for a in scale_axes}
    noise = scenario.noise
    readings = np.empty((n, 2 * len(scale_axes)))
    channels: list[str] = []
    yaw_truth: dict[str, NDArray] = {}
    temperature_names: list[str] = []
    temperature_columns: list[NDArray] = []
    tc_positions: dict[str, NDArray] = {}
    skew = float(scenario.parameters("timing_skew")["skew_s"])
    head_noise = _block_noise(noise_entropy, start, stop, 2 * len(scale_axes),
                              float(noise["scale_m"])) if float(noise["scale_m"]) > 0 else None
    delta = float(scenario.parameters("scale_parallelism")["delta_rad"])
    for k, axis in enumerate(scale_axes):
        low, high = machine.axes[axis].stroke
        length = high - low
        q = actual[axis]
        travel = q - low
        distance = distances[axis]
        yaw = profiles[axis][YAW_COMPONENT[axis]].tabulated(low, high)(q)
        if "geometric" not in masks:
            yaw = np.zeros(n)
        elif not np.all(masks["geometric"]):
            yaw = yaw * masks["geometric"]
        if scenario.ever_enabled("guideway_deterioration"):
            params = scenario.parameters("guideway_deterioration")
            if params["axis"] == axis:
                yaw = yaw + deterioration_peak_rad(scenario) * \
                    deterioration_bump(q, float(params["start_m"]), float(params["end_m"])) * \
                    masks["guideway_deterioration"]
        yaw_truth[axis] = yaw
        # Motion heat of this axis warms its scales: FE field of each scale body.
        heat = np.minimum(motion_input[axis] * 10, 1)
        accuracy = float(noise["scale_accuracy_fraction"]) * (1.5e-6 + 1.5e-6 * length)
        for i in (1, 2):
            field = ScaleTemperatureField(length, heat, dt_thermal,
                                          float(expansion["time_constant_s"]),
                                          float(expansion[f"rise_scale_{i}_k"]))
            name = f"{axis.lower()}{i}"
            positions = thermocouple_positions(length)
            tc_positions[name] = positions
            sensor_rises = field.at_sensors(positions)
            for j in range(positions.size):
                temperature_names.append(f"{name}_s{j}")
                temperature_columns.append(sensor_rises[:, j] + ambient)
            graduation = SineProfile(
                tuple(accuracy * rng_graduation.uniform(0.3, 1.0) / (1 + r) for r in range(3)),
                tuple(float(w) for w in rng_graduation.uniform([0.5, 0.15, 0.05],
                                                               [1.0, 0.3, 0.1])),
                tuple(float(p) for p in rng_graduation.uniform(0, 2 * np.pi, 3)))
            reading = q + (-0.5 if i == 1 else 0.5) * distance * yaw
            reading = reading + graduation.tabulated(0.0, length)(travel) - graduation(np.zeros(1))
            if scenario.ever_enabled("scale_thermal_expansion"):
                uniform = np.interp(time_s, temperature_time, ambient - ambient[0])
                expansion_m = float(expansion["expansion_per_k"]) * (
                    field.expansion_integral(time_s, travel) + uniform * travel)
                reading = reading - expansion_m * masks["scale_thermal_expansion"]
            if i == 2 and scenario.ever_enabled("scale_parallelism"):
                reading = reading + travel * (1.0 / np.cos(delta) - 1.0) * \
                    masks["scale_parallelism"]
            if i == 2 and scenario.ever_enabled("timing_skew"):
                reading = reading + velocity[axis] * skew * masks["timing_skew"]
            if float(noise["scale_m"]) > 0:
                reading = reading + head_noise[:, 2 * k + i - 1]
            resolution = float(noise["resolution_m"])
            if resolution > 0:
                reading = np.round(reading / resolution) * resolution
            readings[:, 2 * k + i - 1] = reading
            channels.append(name)

    # Rotary encoders (one angle encoder per rotary axis, read by the same trigger as the
    # scales): the CNC closes its loop on them, so they read the commanded angle; how far
    # the table really is from it (rotary_runout's positioning error, the location
    # errors) is what only a reference instrument sees.
    encoder_axes = [a for a in machine.axis_order if machine.axes[a].is_rotary]
    encoder_readings = np.column_stack([actual[a] for a in encoder_axes]) if encoder_axes \
        else np.zeros((n, 0))
    if encoder_axes:
        encoder_readings = encoder_readings + _block_noise(
            noise_entropy, start, stop, len(encoder_axes), ENCODER_NOISE_RAD, stream=0xE4C)
        encoder_readings = np.round(encoder_readings / ENCODER_RESOLUTION_RAD) \
            * ENCODER_RESOLUTION_RAD

    mean_c = float(ambient_cfg["mean_c"])
    for name, key, scale in (("column", "column", 1.0), ("bed", "bed", 1.0),
                             ("spindle", "spindle", 8.0)):
        temperature_names.append(name)
        temperature_columns.append(scale * thermal[key] + ambient)
    temperature_names.append("ambient")
    temperature_columns.append(ambient)
    true_c = mean_c + np.column_stack(temperature_columns)
    measured = true_c + rng_thermo.normal(0.0, float(noise["thermocouple_k"]), true_c.shape)
    step = float(noise["thermocouple_resolution_k"])
    if step > 0:
        measured = np.round(measured / step) * step

    return SimulationResult(
        scenario=scenario, time_s=time_s, command=command, actual=actual, velocity=velocity,
        scale_axes=scale_axes, scale_channels=channels, scale_readings=readings,
        scale_distance_m=distances, yaw_truth=yaw_truth, temperature_time_s=temperature_time,
        temperature_names=temperature_names, temperatures_c=measured,
        temperatures_true_c=true_c, thermocouple_positions_m=tc_positions,
        spindle_speed_rpm=speed, program=program, first_index=start,
        encoder_axes=encoder_axes, encoder_readings=encoder_readings, _masks=masks,
        _profiles=profiles,
        _thermal=thermal)
