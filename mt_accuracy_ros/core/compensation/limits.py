"""What a controller will take: correction limits, and the gate a model version passes first.

A compensation is only as safe as its worst value. A model version fitted on
90 s of data can hold a term that is harmless at the readings and absurd one
kelvin or 100 mm away from them (a 5 mm/K lag gain fitted to millikelvin of
sensor noise). So before a version goes live its corrections are bounded
over the machine's **whole travel and temperature range**, not only where the
data lay, and refused when they exceed what the controller is configured to
take:

* ``max_correction_m`` - the largest correction per TCP component [m];
* ``max_correction_rate_m_per_s`` - the largest change of the correction per
  second [m/s], from the correction's slope along each axis at the fastest
  feed plus its temperature sensitivity at the fastest temperature change.

Both come from the machine description's ``cnc:`` section (defaults below).
The envelope is evaluated on dense lines along each axis (1 mm or finer, so
a screw pitch's slope is resolved) with the other axes at their stroke ends
and middle; temperatures enter through each sensor's sensitivity
(the model at +1 K on that sensor minus the model at its reference) times
the configured range, summed in absolute value - the worst case for a model
linear in its rises, which every thermal family is (Zhu eqs. 3.12-3.13).
Heat sources are bounded by their gain times the fastest driver.
"""
from __future__ import annotations

import copy
import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..kinematics.machine import MachineDescription

#: Defaults of the ``cnc:`` section (SI units). 1 mm matches the virtual CNC's
#: unit-mistake limit; 10 mm/s is 10 um per 1 ms interpolation cycle.
DEFAULT_LIMITS = {
    "max_correction_m": 1.0e-3,
    "max_correction_rate_m_per_s": 1.0e-2,
    "max_feed_m_per_s": 0.5,
    "temperature_range_k": 15.0,
    "max_temperature_rate_k_per_s": 0.01,
    "max_spindle_speed_rpm": 20000.0,
}

_LINE_STEP_M = 1.0e-3          # dense line spacing along a linear axis [m] ...
_PER_PERIOD = 32               # ... or finer: this many points per shortest period
_LINE_MAX_POINTS = 4001
_ROTARY_STEP_RAD = np.radians(1.0)


@dataclass(frozen=True)
class CorrectionLimits:
    """The controller's limits (see the module docstring); per TCP component X, Y, Z.

    Parameters
    ----------
    max_correction_m : tuple of float, (x, y, z)
        Largest correction per TCP component [m].
    max_correction_rate_m_per_s : float
        Largest change of the correction [m/s].
    max_feed_m_per_s : float
        Fastest feed of a linear axis [m/s].
    temperature_range_k : float
        Temperatures the model must stay bounded over: +- this about each reference [K].
    max_temperature_rate_k_per_s : float
        Fastest temperature change of a structure [K/s].
    max_spindle_speed_rpm : float
        Fastest spindle speed [rpm].
    """

    max_correction_m: tuple[float, float, float]
    max_correction_rate_m_per_s: float
    max_feed_m_per_s: float
    temperature_range_k: float
    max_temperature_rate_k_per_s: float
    max_spindle_speed_rpm: float

    @classmethod
    def of(cls, machine: MachineDescription) -> "CorrectionLimits":
        """The limits of ``machine``: its ``cnc:`` section over :data:`DEFAULT_LIMITS`.

        Parameters
        ----------
        machine : MachineDescription
            The machine (its validated ``cnc`` mapping).

        Returns
        -------
        CorrectionLimits
            The limits, a scalar ``max_correction_m`` repeated for x, y, z.
        """
        spec = {**DEFAULT_LIMITS, **(machine.cnc or {})}
        per_axis = spec["max_correction_m"]
        if isinstance(per_axis, dict):
            default = DEFAULT_LIMITS["max_correction_m"]
            per_axis = tuple(float(per_axis.get(a, default)) for a in "XYZ")
        else:
            per_axis = (float(per_axis),) * 3
        return cls(per_axis, float(spec["max_correction_rate_m_per_s"]),
                   float(spec["max_feed_m_per_s"]), float(spec["temperature_range_k"]),
                   float(spec["max_temperature_rate_k_per_s"]),
                   float(spec["max_spindle_speed_rpm"]))


@dataclass
class Envelope:
    """The largest correction and correction rate of a model over travel x temperature.

    ``max_abs_m`` (3,) [m] and ``max_rate_m_per_s`` (3,) [m/s], per TCP
    component; ``where`` names the command position of each maximum.

    Parameters
    ----------
    max_abs_m : ndarray, shape (3,)
        Largest |correction| per TCP component [m].
    max_rate_m_per_s : ndarray, shape (3,)
        Largest |d correction / dt| per component [m/s].
    where : list of str
        Per component, where the maximum lies (positions, temperature range).
    points : int
        Command positions evaluated.
    """

    max_abs_m: NDArray[np.float64]
    max_rate_m_per_s: NDArray[np.float64]
    where: list[str]
    points: int

    def problems(self, limits: CorrectionLimits) -> list[str]:
        """Why the envelope exceeds ``limits``: one sentence per component and kind.

        Parameters
        ----------
        limits : CorrectionLimits
            The controller's limits.

        Returns
        -------
        list of str
            Empty when within; a non-finite value is a problem.
        """
        out = []
        for c, component in enumerate("xyz"):
            if not np.isfinite(self.max_abs_m[c]) or \
                    self.max_abs_m[c] > limits.max_correction_m[c]:
                out.append(f"its {component} correction reaches "
                           f"{self.max_abs_m[c] * 1e6:.4g} um ({self.where[c]}), beyond the "
                           f"controller's {limits.max_correction_m[c] * 1e6:.4g} um")
            if not np.isfinite(self.max_rate_m_per_s[c]) or \
                    self.max_rate_m_per_s[c] > limits.max_correction_rate_m_per_s:
                out.append(f"its {component} correction changes by up to "
                           f"{self.max_rate_m_per_s[c] * 1e3:.4g} mm/s, beyond the controller's "
                           f"{limits.max_correction_rate_m_per_s * 1e3:.4g} mm/s")
        return out


def _shortest_period_m(model) -> float:
    """The shortest period of the model's periodic effects [m] (inf if none)."""
    periods = [float(entry["setting"]["period_m"]) for entry in model.effects.values()
               if isinstance(entry, dict) and isinstance(entry.get("setting"), dict)
               and isinstance(entry["setting"].get("period_m"), (int, float))]
    return min(periods, default=float("inf"))


def _axis_grid(machine: MachineDescription, axis: str, dense: bool,
               step_m: float = _LINE_STEP_M) -> NDArray[np.float64]:
    low, high = machine.axes[axis].stroke
    if not dense:
        return np.array([low, 0.5 * (low + high), high])
    step = _ROTARY_STEP_RAD if machine.axes[axis].is_rotary else step_m
    count = int(min(_LINE_MAX_POINTS, max(3, np.ceil((high - low) / step) + 1)))
    return np.linspace(low, high, count)


def _sensors(model) -> list[str]:
    """The sensors the model's effects read (perturbed one at a time for the envelope)."""
    import re

    names = set()
    for entry in model.effects.values():
        if not isinstance(entry, dict):
            continue
        sensor = entry.get("sensor")
        if isinstance(sensor, str):
            names.add(sensor)
        if "expression" in entry:
            names.update(re.findall(r"\bT_(\w+)", str(entry["expression"])))
        family, variant = str(entry.get("family", "")), str(entry.get("variant", ""))
        if family in ("structural_thermal_drift", "thermal_lag"):
            names.add(variant)
        elif family == "thermal_gradient":
            names.update(variant.split("-", 1))
        elif family in ("position_dependent_thermal", "thermal_squareness"):
            names.update(variant.split(":", 1)[1].split("-", 1))
    return sorted(n for n in names if n)


def _heat_source_bound(model, limits: CorrectionLimits) -> NDArray[np.float64]:
    """(3,) [m] the heat sources can add at steady state with the fastest driver."""
    out = np.zeros(3)
    for entry in model.effects.values():
        if isinstance(entry, dict) and entry.get("family") == "heat_source":
            driver = limits.max_spindle_speed_rpm / 1000.0 \
                if entry.get("variant") == "spindle_speed" else limits.max_feed_m_per_s * 60.0
            gains = entry.get("coefficients", {})
            out += np.abs([gains.get(g, 0.0) for g in ("gx", "gy", "gz")]) * driver
    return out


def _moves_with_direction(model) -> bool:
    """Whether the model's corrections depend on the direction or sign of motion (backlash,
    servo lag, acceleration, a user's expression of anything): only then is the travel
    evaluated in both directions - a five-axis model's geometry needs it once."""
    from ..effects import family_named

    for name, entry in model.effects.items():
        if name in ("reversal", "servo_lag") or not isinstance(entry, dict):
            return True
        if "expression" in entry:
            return True
        if "family" in entry:
            try:
                if family_named(entry["family"]).group not in ("geometric", "rotary",
                                                               "thermal"):
                    return True
            except ValueError:
                return True
    return False


def correction_envelope(model, limits: CorrectionLimits) -> Envelope:
    """The model's largest |correction| and |d correction / dt| per component (see the
    module docstring). Heat-source lags count at their steady state.

    Parameters
    ----------
    model : ErrorModel
        The model version to bound (not changed: a copy is evaluated).
    limits : CorrectionLimits
        Feed [m/s], temperature range [K] and rate [K/s], spindle speed [rpm] bounding
        the variables.

    Returns
    -------
    Envelope
        Bounds [m] and [m/s] per TCP component.
    """
    machine = model.machine
    axes = list(machine.axis_order)
    state = copy.copy(model)
    state.reference_temperatures_c = dict(model.reference_temperatures_c)
    sensors = _sensors(model)
    for sensor in sensors:
        state.reference_temperatures_c.setdefault(sensor, 20.0)
    reference = dict(state.reference_temperatures_c)
    # Fine enough that a screw pitch's slope is resolved, not aliased to zero.
    step_m = min(_LINE_STEP_M, _shortest_period_m(model) / _PER_PERIOD)
    max_abs, max_rate = np.zeros(3), np.zeros(3)
    where = ["nowhere"] * 3
    points = 0
    thermal_rate = np.zeros(3)
    for dense_axis in axes:
        others = [a for a in axes if a != dense_axis]
        corners = list(itertools.product(*[_axis_grid(machine, a, False) for a in others]))
        line = _axis_grid(machine, dense_axis, True, step_m)
        positions = {dense_axis: np.tile(line, len(corners))}
        for k, a in enumerate(others):
            positions[a] = np.repeat([c[k] for c in corners], line.size)
        n = positions[dense_axis].size
        points += n
        worst = np.zeros((n, 3))
        sensitivity = np.zeros((n, 3))
        axis_rate = np.zeros(3)
        for sign in (1.0, -1.0) if _moves_with_direction(model) else (1.0,):
            velocity = {a: np.full(n, sign * limits.max_feed_m_per_s)
                        for a in axes if not machine.axes[a].is_rotary}
            direction = {a: np.full(n, sign) for a in axes}

            def evaluate(temperatures):
                state._lag_states = {}
                return state.tcp_error(positions, temperatures, velocity, direction,
                                       time_s=np.zeros(n), accelerations={a: np.zeros(n)
                                                                          for a in axes},
                                       spindle_speed_rad_s=np.zeros(n), fresh=True)[0]

            base = evaluate({s: np.full(n, t) for s, t in reference.items()})
            total_sensitivity = np.zeros((n, 3))
            for sensor in sensors:
                warmed = {s: np.full(n, t + (1.0 if s == sensor else 0.0))
                          for s, t in reference.items()}
                total_sensitivity += np.abs(evaluate(warmed) - base)
            bound = np.abs(base) + total_sensitivity * limits.temperature_range_k
            worst = np.maximum(worst, bound)
            sensitivity = np.maximum(sensitivity, total_sensitivity)
            # The slope along the dense axis at the fastest feed (per degree for rotary
            # axes at one revolution per second would be arbitrary: linear axes only).
            if not machine.axes[dense_axis].is_rotary and line.size > 1:
                per_line = base.reshape(len(corners), line.size, 3)
                slope = np.abs(np.diff(per_line, axis=1)) / np.diff(line)[None, :, None]
                axis_rate = np.maximum(axis_rate, slope.max(axis=(0, 1)) *
                                       limits.max_feed_m_per_s)
        max_rate += axis_rate
        worst += _heat_source_bound(model, limits)
        thermal_rate = np.maximum(thermal_rate, sensitivity.max(axis=0) *
                                  limits.max_temperature_rate_k_per_s)
        for c in range(3):
            i = int(np.argmax(worst[:, c]))
            if worst[i, c] > max_abs[c] or not np.isfinite(worst[i, c]):
                max_abs[c] = worst[i, c]
                where[c] = "at " + ", ".join(f"{a} {positions[a][i]:.4g}" for a in axes) + \
                    (f", temperatures +-{limits.temperature_range_k:g} K" if sensors else "")
    # Along several axes at once the slopes add (a diagonal move at full feed per axis).
    return Envelope(max_abs, max_rate + thermal_rate, where, points)


def gate_problem(model, limits: CorrectionLimits | None = None) -> str:
    """Why ``model`` must not go live on this controller ("" if it may).

    Parameters
    ----------
    model : ErrorModel
        The model version.
    limits : CorrectionLimits, optional
        Default: those of ``model.machine``.

    Returns
    -------
    str
        "" or the problems joined by "; " (including a model that cannot be evaluated).
    """
    limits = limits or CorrectionLimits.of(model.machine)
    try:
        envelope = correction_envelope(model, limits)
    except (ArithmeticError, ValueError) as exc:
        return f"its corrections cannot be evaluated over the travel ({exc})"
    problems = envelope.problems(limits)
    return "; ".join(problems)
