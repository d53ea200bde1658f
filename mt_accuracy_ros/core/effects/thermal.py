"""Thermal effect families: structures that grow, lag, bend and heat up.

Temperatures enter as rises dT over each sensor's reference (its first
reading unless the model says otherwise).

* ``structural_thermal_drift`` - a TCP offset proportional to one sensor's
  rise, e = beta dT, per direction (Zhu eq. 3.12, the "sensor term").
* ``thermal_lag`` - the same through a first-order lag of time constant tau:
  the structure follows its sensor late (Zhu's modal time constants,
  Zhu eqs. 3.9-3.10 and the fit of Zhu eq. 3.17); tau searched 5 min - 2.7 h.
* ``thermal_gradient`` - the difference of two sensors: a gradient bends a
  link (deflection and slope, Zhu Table 4.2).
* ``heat_source`` - growth driven by an operating input through a lag: spindle
  power ~ speed, an axis' drive and guideway heat ~ |feed| (Zhu eqs. 3.9-3.10
  with the heat input as the driver); starts from a cold machine.
* ``position_dependent_thermal`` - expansion along an axis relative to its
  scale, alpha q dT on the axis' positioning (Zhu eq. 3.13 with P(x) = x).
* ``thermal_squareness`` - a squareness that changes with a temperature or a
  temperature difference (a column tilting as its front and back warm apart).
"""
from __future__ import annotations

import numpy as np

from .base import Context, EffectFamily, per_component
from .physics import (BENDING_LEVER, GENEROUS_CTE_PER_K, MAX_RISE_K, structure_length_m,
                      thermal_gain_limit_m_per_k)

#: Searched time constants: 5 min to 5.3 h, half an octave apart.
TIME_CONSTANTS_S = tuple(float(300.0 * 2.0 ** (k / 2)) for k in range(13))


#: The longest time constant searched, in multiples of the data's time span: a lag
#: is supported by a record that sees it at least once.
MAX_TAU_PER_SPAN = 1.0


def _free_expansion_limits(ctx, names, lever: float = 1.0, per: str = "K"):
    bound = thermal_gain_limit_m_per_k(ctx.machine) * lever
    why = (f"free expansion of {structure_length_m(ctx.machine):.2g} m of structure at "
           f"{GENEROUS_CTE_PER_K * 1e6:.0f} um/m/K" + (f" x a bending lever of {lever:g}"
                                                        if lever != 1.0 else "") + f" per {per}")
    return {name: (bound, why) for name in names}


class _SearchedTimeConstant:
    """Families whose time constant is searched (in-fold) over TIME_CONSTANTS_S.

    Only time constants up to MAX_TAU_PER_SPAN x the data's span, and none at
    all on a record shorter than the shortest: a lag longer than the record is
    a ramp to the data, its gain (m/K of a signal of millikelvin) is arbitrary,
    and evaluated later - in a broadcaster whose lag has run longer - it
    extrapolates to millimetres.
    """

    continuous_setting = "tau_s"

    def settings(self, ctx, variant):
        time_s = ctx.variables.time_s
        if time_s is None or np.size(time_s) < 2:
            return []
        span = ctx.variables.span_s()     # of the longest run: lags restart each run
        return [{"tau_s": tau} for tau in TIME_CONSTANTS_S if tau <= MAX_TAU_PER_SPAN * span]

    def describe_setting(self, setting):
        return f"tau {setting['tau_s'] / 60:.0f} min"


def _gradient_names(ctx: Context) -> list[str]:
    sensors = ctx.structure_sensors()
    return [f"{a}-{b}" for i, a in enumerate(sensors) for b in sensors[i + 1:]]


def temperature_variable(ctx: Context, name: str):
    """A sensor's rise, or for ``a-b`` the difference of two rises [K]."""
    if "-" in name and name not in ctx.variables.temperatures:
        a, b = name.split("-", 1)
        return ctx.variables.rise(a) - ctx.variables.rise(b)
    return ctx.variables.rise(name)


class StructuralDrift(EffectFamily):
    name = "structural_thermal_drift"
    group = "thermal"
    complexity = 1
    summary = "a structure grows with one sensor's temperature, at every position alike"
    reference = "Zhu eq. 3.12"

    def variants(self, ctx):
        return ctx.structure_sensors()

    def parameter_names(self, variant, setting):
        return ["bx", "by", "bz"]

    def design(self, ctx, variant, setting):
        return per_component(ctx.variables.rise(variant))

    def parameter_limits(self, ctx, variant, setting):
        return _free_expansion_limits(ctx, ["bx", "by", "bz"])

    def explanation(self, variant, setting):
        return (f"the residual follows the temperature of the {variant} sensor in every "
                "direction at once, independent of position - the structure grows as it warms "
                "(Zhu eq. 3.12)")


class ThermalLag(_SearchedTimeConstant, EffectFamily):
    name = "thermal_lag"
    group = "thermal"
    complexity = 2
    summary = "a structure grows with a sensor's temperature, but late (a thermal time constant)"
    reference = "Zhu eqs. 3.9-3.10, 3.17 (modal time constants)"

    def variants(self, ctx):
        return ctx.structure_sensors() if ctx.variables.time_s is not None else []

    def parameter_names(self, variant, setting):
        return ["bx", "by", "bz"]

    def design(self, ctx, variant, setting):
        lagged = ctx.variables.lag(f"T_{variant}", ctx.variables.rise(variant), setting["tau_s"])
        return per_component(lagged)

    def parameter_limits(self, ctx, variant, setting):
        return _free_expansion_limits(ctx, ["bx", "by", "bz"])

    def explanation(self, variant, setting):
        return (f"the residual follows the {variant} temperature {setting['tau_s'] / 60:.0f} min "
                "late - the structure's thermal time constant (Zhu eqs. 3.9-3.10)")


class ThermalGradient(EffectFamily):
    name = "thermal_gradient"
    group = "thermal"
    complexity = 2
    summary = "a temperature difference across a structure bends it"
    reference = "Zhu Table 4.2 (deflection and slope of a link)"

    def variants(self, ctx):
        return _gradient_names(ctx)

    def parameter_names(self, variant, setting):
        return ["bx", "by", "bz"]

    def design(self, ctx, variant, setting):
        return per_component(temperature_variable(ctx, variant))

    def parameter_limits(self, ctx, variant, setting):
        return _free_expansion_limits(ctx, ["bx", "by", "bz"], BENDING_LEVER,
                                      "K of difference")

    def explanation(self, variant, setting):
        a, b = variant.split("-", 1)
        return (f"the residual follows the difference {a} - {b}: a temperature gradient that "
                "bends a link (deflection and slope, Zhu Table 4.2)")


class HeatSource(_SearchedTimeConstant, EffectFamily):
    name = "heat_source"
    group = "thermal"
    complexity = 2
    summary = "growth driven by an operating input (spindle speed, an axis' feed) through a lag"
    reference = "Zhu eqs. 3.9-3.10 (heat input -> thermal mode)"

    def variants(self, ctx):
        if ctx.variables.time_s is None:
            return []
        out = []
        if ctx.variables.spindle_speed_rad_s is not None and \
                np.ptp(ctx.variables.spindle_speed_rad_s) > 0:
            out.append("spindle_speed")
        out += [f"feed_{a}" for a in ctx.linear_axes() if a in ctx.variables.velocities and
                np.ptp(np.abs(ctx.variables.velocities[a])) > 0]
        return out

    def parameter_names(self, variant, setting):
        return ["gx", "gy", "gz"]

    def driver(self, ctx, variant):
        if variant == "spindle_speed":
            return ctx.variables.spindle_speed() * 60.0 / (2.0 * np.pi) / 1000.0  # krpm
        return np.abs(ctx.variables.velocity(variant[-1])) * 60.0                  # m/min

    def design(self, ctx, variant, setting):
        lagged = ctx.variables.lag(f"heat_{variant}", self.driver(ctx, variant),
                                   setting["tau_s"], from_rest=True)
        return per_component(lagged)

    def parameter_limits(self, ctx, variant, setting):
        fastest = float(np.max(np.abs(self.driver(ctx, variant)), initial=0.0))
        if fastest <= 0:
            return {}
        unit = "krpm" if variant == "spindle_speed" else "m/min"
        bound = thermal_gain_limit_m_per_k(ctx.machine) * MAX_RISE_K / fastest
        why = (f"at the fastest {fastest:.3g} {unit} seen, a rise of at most {MAX_RISE_K:g} K "
               f"of {structure_length_m(ctx.machine):.2g} m of structure")
        return {name: (bound, why) for name in ("gx", "gy", "gz")}

    def explanation(self, variant, setting):
        what = "the spindle speed (spindle power heats the head)" if variant == "spindle_speed" \
            else f"the {variant[-1]} feed (drive and guideway heat)"
        return (f"the residual follows {what} through a {setting['tau_s'] / 60:.0f} min lag - "
                "a heat source warming the structure (Zhu eqs. 3.9-3.10)")


class PositionDependentThermal(EffectFamily):
    name = "position_dependent_thermal"
    group = "thermal"
    complexity = 2
    summary = "an axis' structure expands relative to its scale: error ~ position x temperature"
    reference = "Zhu eq. 3.13 (P(x) = x)"

    def variants(self, ctx):
        return [f"{a}:{s}" for a in ctx.linear_axes(moving=True) for s in ctx.structure_sensors()]

    def parameter_names(self, variant, setting):
        return ["alpha_per_k"]

    def design(self, ctx, variant, setting):
        axis, sensor = variant.split(":", 1)
        column = ctx.variables.positions[axis] * ctx.variables.rise(sensor)
        return (ctx.jacobian(f"E{axis}{axis}") * column[:, None])[:, :, None]

    def parameter_limits(self, ctx, variant, setting):
        return {"alpha_per_k": (GENEROUS_CTE_PER_K, "no structure expands faster than "
                                f"{GENEROUS_CTE_PER_K * 1e6:.0f} um/m/K relative to its scale")}

    def explanation(self, variant, setting):
        axis, sensor = variant.split(":", 1)
        return (f"the {axis} error grows with the {axis} position times the {sensor} "
                "temperature - a structure expanding along the axis relative to its scale "
                "(Zhu eq. 3.13)")


class ThermalSquareness(EffectFamily):
    name = "thermal_squareness"
    group = "thermal"
    complexity = 3
    summary = "a squareness that changes with a temperature or a temperature difference"
    reference = "Zhu eq. 4.2 (ch. 4, thermal link HTMs): a link's slope as a location error"

    def variants(self, ctx):
        from .geometric import Squareness

        temperatures = ctx.structure_sensors() + _gradient_names(ctx)
        # The location-error forms only (EC0Y, EB0Z, EA0Z): the other-reference slopes
        # would double the candidates for a distinction the thermal data cannot make.
        squares = [v for v in Squareness().variants(ctx) if v not in Squareness.OTHER_REFERENCE]
        return [f"{s}:{t}" for s in squares for t in temperatures]

    def parameter_names(self, variant, setting):
        return ["rad_per_k"]

    def design(self, ctx, variant, setting):
        square, temperature = variant.split(":", 1)
        column = temperature_variable(ctx, temperature)
        return (ctx.jacobian(square) * column[:, None])[:, :, None]

    def orientation_design(self, ctx, variant, setting):
        square, temperature = variant.split(":", 1)
        column = temperature_variable(ctx, temperature)
        return (ctx.orientation_jacobian(square) * column[:, None])[:, :, None]

    def parameter_limits(self, ctx, variant, setting):
        bound = GENEROUS_CTE_PER_K * BENDING_LEVER
        return {"rad_per_k": (bound, f"a link tilts at most {GENEROUS_CTE_PER_K * 1e6:.0f} "
                                     f"urad/K x a slenderness of {BENDING_LEVER:g}")}

    def explanation(self, variant, setting):
        square, temperature = variant.split(":", 1)
        what = f"the difference {temperature.replace('-', ' - ')}" if "-" in temperature else \
            f"the {temperature} temperature"
        return (f"the squareness {square} changes with {what} - a structure tilting as it "
                "warms unevenly (a thermal link's slope, Zhu eq. 4.2)")


#: Ridge strengths searched, relative to each column's own sum of squares (so the
#: choice does not depend on units): from nearly least squares to heavy shrinkage.
RIDGE_STRENGTHS = (1e-3, 1e-2, 1e-1, 1.0, 10.0)

#: Fewest structure sensors for which an all-sensor model is a candidate: "many weak
#: sensors". With a handful, single sensors, their differences and lags span what the
#: structure can do and name it; a shrunk blend of four would out-fit two named
#: physical effects at once (a drift and a thermal squareness of the catalogue trials).
MIN_RIDGE_SENSORS = 6


def sensor_set_parameters(variant: str) -> list[str]:
    """Parameters of a set of sensors ``a+b+...``: one gain per sensor and direction."""
    return [f"b{c}_{sensor}" for sensor in variant.split("+") for c in "xyz"]


def sensor_set_design(ctx: Context, variant: str) -> np.ndarray:
    """(N, 3, 3S) design of a set of sensors ``a+b+...``: each rise on x, y and z."""
    return np.concatenate([per_component(ctx.variables.rise(sensor))
                           for sensor in variant.split("+")], axis=2)


class AllSensorsRidge(EffectFamily):
    """Every structure sensor at once, shrunk by ridge regression (Zhu eq. 3.12 with all
    sensors as regressors; Tikhonov regularisation against their collinearity).

    Many weak sensors can carry a thermal drift together that none carries alone (the
    heat spreads through the structure). Least squares on all of them overfits their
    collinearity; ridge shrinks it with a strength lambda that the workbench chooses
    **inside each fold** by validation on the training blocks alone
    (:attr:`penalty_setting`), so the held-out test stays honest. The variant lists the
    sensors (``t1_C+t2_C+...``): the model evaluates the same columns later.
    """

    name = "all_sensors_ridge"
    group = "thermal"
    complexity = 3
    summary = "many structure sensors together, shrunk by ridge regression"
    reference = "Zhu eq. 3.12 (sensor terms), all sensors with a ridge penalty"
    #: The setting that is a penalty, not a different design: the workbench adds
    #: setting["ridge"] x each column's own sum of squares to its normal equations.
    penalty_setting = "ridge"

    def variants(self, ctx):
        sensors = ctx.structure_sensors()
        return ["+".join(sensors)] if len(sensors) >= MIN_RIDGE_SENSORS else []

    def settings(self, ctx, variant):
        return [{"ridge": value} for value in RIDGE_STRENGTHS]

    def parameter_names(self, variant, setting):
        return sensor_set_parameters(variant)

    def design(self, ctx, variant, setting):
        return sensor_set_design(ctx, variant)

    def parameter_limits(self, ctx, variant, setting):
        return _free_expansion_limits(ctx, self.parameter_names(variant, setting))

    def describe_setting(self, setting):
        return f"ridge {setting['ridge']:g}"

    def explanation(self, variant, setting):
        sensors = variant.split("+")
        return (f"the residual follows the {len(sensors)} structure sensors together (ridge "
                f"strength {setting.get('ridge', float('nan')):g}, chosen inside each fold) - "
                "heat spread through the structure that no one sensor carries alone "
                "(Zhu eq. 3.12 with every sensor)")


def sensor_weights(parameters: dict[str, float], temperatures: dict[str, np.ndarray]
                   ) -> list[tuple[str, float]]:
    """Which sensors carry an all-sensor model: (sensor, share of the model's spread), the
    largest first - each sensor's |coefficient| x its temperature range, all components."""
    contribution: dict[str, float] = {}
    for name, value in parameters.items():
        sensor = name[3:]
        values = temperatures.get(sensor)
        if values is None or not np.isfinite(value):
            continue
        contribution[sensor] = contribution.get(sensor, 0.0) + abs(value) * float(np.ptp(values))
    total = sum(contribution.values()) or 1.0
    return sorted(((s, v / total) for s, v in contribution.items()), key=lambda p: -p[1])


def families() -> list[EffectFamily]:
    return [StructuralDrift(), ThermalLag(), ThermalGradient(), HeatSource(),
            PositionDependentThermal(), ThermalSquareness(), AllSensorsRidge()]
