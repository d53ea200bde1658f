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
    """A sensor's rise, or for ``a-b`` the difference of two rises [K].

    Parameters
    ----------
    ctx : Context
        The readings.
    name : str
        A sensor name, or ``a-b`` for a difference.

    Returns
    -------
    ndarray, shape (N,)
        Rise over the reference [K].
    """
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
        """The structure sensors that change.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            Sensor names.
        """
        return ctx.structure_sensors()

    def parameter_names(self, variant, setting):
        """A gain per TCP direction.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``bx, by, bz`` [m/K].
        """
        return ["bx", "by", "bz"]

    def design(self, ctx, variant, setting):
        """The sensor's rise on x, y and z (Zhu eq. 3.12).

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
            (N, 3, 3) [K]: TCP error [m] per gain [m/K].
        """
        return per_component(ctx.variables.rise(variant))

    def parameter_limits(self, ctx, variant, setting):
        """Free expansion of the structure per kelvin.

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
        dict of str to tuple of (float, str)
            Parameter name -> (bound, reason): free expansion of the structure [m/K].
        """
        return _free_expansion_limits(ctx, ["bx", "by", "bz"])

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
        """The structure sensors that change, when the readings have times.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            Sensor names.
        """
        return ctx.structure_sensors() if ctx.variables.time_s is not None else []

    def parameter_names(self, variant, setting):
        """A gain per TCP direction.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``bx, by, bz`` [m/K].
        """
        return ["bx", "by", "bz"]

    def design(self, ctx, variant, setting):
        """The sensor's rise through a first-order lag of ``setting["tau_s"]`` [s], on x, y and z.

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
            (N, 3, 3) [K].
        """
        lagged = ctx.variables.lag(f"T_{variant}", ctx.variables.rise(variant), setting["tau_s"])
        return per_component(lagged)

    def parameter_limits(self, ctx, variant, setting):
        """Free expansion of the structure per kelvin.

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
        dict of str to tuple of (float, str)
            Parameter name -> (bound, reason): free expansion of the structure [m/K].
        """
        return _free_expansion_limits(ctx, ["bx", "by", "bz"])

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
        return (f"the residual follows the {variant} temperature {setting['tau_s'] / 60:.0f} min "
                "late - the structure's thermal time constant (Zhu eqs. 3.9-3.10)")


class ThermalGradient(EffectFamily):
    name = "thermal_gradient"
    group = "thermal"
    complexity = 2
    summary = "a temperature difference across a structure bends it"
    reference = "Zhu Table 4.2 (deflection and slope of a link)"

    def variants(self, ctx):
        """Every pair of changing structure sensors.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            ``a-b`` names.
        """
        return _gradient_names(ctx)

    def parameter_names(self, variant, setting):
        """A gain per TCP direction.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``bx, by, bz`` [m/K of difference].
        """
        return ["bx", "by", "bz"]

    def design(self, ctx, variant, setting):
        """The difference of the two rises on x, y and z.

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
            (N, 3, 3) [K].
        """
        return per_component(temperature_variable(ctx, variant))

    def parameter_limits(self, ctx, variant, setting):
        """Free expansion times a bending lever, per kelvin of difference.

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
        dict of str to tuple of (float, str)
            Parameter name -> (bound, reason): free expansion of the structure [m/K].
        """
        return _free_expansion_limits(ctx, ["bx", "by", "bz"], BENDING_LEVER,
                                      "K of difference")

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
        """``spindle_speed`` and ``feed_<axis>`` for inputs that changed, when the readings have
        times.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            Variant names.
        """
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
        """A gain per TCP direction.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``gx, gy, gz`` [m/krpm] (spindle) or [m/(m/min)] (feed).
        """
        return ["gx", "gy", "gz"]

    def driver(self, ctx, variant):
        """The operating input that heats: spindle speed [krpm] or |feed| of the axis [m/min].

        Parameters
        ----------
        ctx : Context
            The readings.
        variant : str
            ``spindle_speed`` or ``feed_<axis>``.

        Returns
        -------
        ndarray, shape (N,)
            The driver [krpm] or [m/min].
        """
        if variant == "spindle_speed":
            return ctx.variables.spindle_speed() * 60.0 / (2.0 * np.pi) / 1000.0  # krpm
        return np.abs(ctx.variables.velocity(variant[-1])) * 60.0                  # m/min

    def design(self, ctx, variant, setting):
        """The driver through a lag of ``setting["tau_s"]`` [s] from a cold machine, on x, y and z.

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
            (N, 3, 3) [krpm] or [m/min].
        """
        lagged = ctx.variables.lag(f"heat_{variant}", self.driver(ctx, variant),
                                   setting["tau_s"], from_rest=True)
        return per_component(lagged)

    def parameter_limits(self, ctx, variant, setting):
        """A rise of at most MAX_RISE_K of the structure at the fastest driver seen.

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
        dict of str to tuple of (float, str)
            Parameter name -> (bound [m per driver unit], reason); empty when the driver never ran.
        """
        fastest = float(np.max(np.abs(self.driver(ctx, variant)), initial=0.0))
        if fastest <= 0:
            return {}
        unit = "krpm" if variant == "spindle_speed" else "m/min"
        bound = thermal_gain_limit_m_per_k(ctx.machine) * MAX_RISE_K / fastest
        why = (f"at the fastest {fastest:.3g} {unit} seen, a rise of at most {MAX_RISE_K:g} K "
               f"of {structure_length_m(ctx.machine):.2g} m of structure")
        return {name: (bound, why) for name in ("gx", "gy", "gz")}

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
        """Every moving linear axis with every changing structure sensor.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            ``<axis>:<sensor>`` names.
        """
        return [f"{a}:{s}" for a in ctx.linear_axes(moving=True) for s in ctx.structure_sensors()]

    def parameter_names(self, variant, setting):
        """The expansion coefficient.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``["alpha_per_k"]`` [1/K].
        """
        return ["alpha_per_k"]

    def design(self, ctx, variant, setting):
        """Position times rise along the axis' positioning sensitivity (Zhu eq. 3.13).

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
            (N, 3, 1) [m K].
        """
        axis, sensor = variant.split(":", 1)
        column = ctx.variables.positions[axis] * ctx.variables.rise(sensor)
        return (ctx.jacobian(f"E{axis}{axis}") * column[:, None])[:, :, None]

    def parameter_limits(self, ctx, variant, setting):
        """A generous CTE relative to the scale.

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
        dict of str to tuple of (float, str)
            ``{"alpha_per_k": (bound [1/K], reason)}``.
        """
        return {"alpha_per_k": (GENEROUS_CTE_PER_K, "no structure expands faster than "
                                f"{GENEROUS_CTE_PER_K * 1e6:.0f} um/m/K relative to its scale")}

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
        """Location-error squareness forms with every changing sensor and sensor pair.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            ``<EC0Y|EB0Z|EA0Z>:<sensor or a-b>`` names.
        """
        from .geometric import Squareness

        temperatures = ctx.structure_sensors() + _gradient_names(ctx)
        # The location-error forms only (EC0Y, EB0Z, EA0Z): the other-reference slopes
        # would double the candidates for a distinction the thermal data cannot make.
        squares = [v for v in Squareness().variants(ctx) if v not in Squareness.OTHER_REFERENCE]
        return [f"{s}:{t}" for s in squares for t in temperatures]

    def parameter_names(self, variant, setting):
        """The squareness per kelvin.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``["rad_per_k"]`` [rad/K].
        """
        return ["rad_per_k"]

    def design(self, ctx, variant, setting):
        """The squareness' sensitivity times the temperature variable.

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
            (N, 3, 1) [m K per rad].
        """
        square, temperature = variant.split(":", 1)
        column = temperature_variable(ctx, temperature)
        return (ctx.jacobian(square) * column[:, None])[:, :, None]

    def orientation_design(self, ctx, variant, setting):
        """The squareness' turn times the temperature variable.

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
            (N, 3, 1) [K] ([rad] per [rad/K]).
        """
        square, temperature = variant.split(":", 1)
        column = temperature_variable(ctx, temperature)
        return (ctx.orientation_jacobian(square) * column[:, None])[:, :, None]

    def parameter_limits(self, ctx, variant, setting):
        """A link's tilt per kelvin at a generous CTE and slenderness.

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
        dict of str to tuple of (float, str)
            ``{"rad_per_k": (bound [rad/K], reason)}``.
        """
        bound = GENEROUS_CTE_PER_K * BENDING_LEVER
        return {"rad_per_k": (bound, f"a link tilts at most {GENEROUS_CTE_PER_K * 1e6:.0f} "
                                     f"urad/K x a slenderness of {BENDING_LEVER:g}")}

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
    """Parameters of a set of sensors ``a+b+...``: one gain per sensor and direction.

    Parameters
    ----------
    variant : str
        Sensor names joined by ``+``.

    Returns
    -------
    list of str
        ``b<x|y|z>_<sensor>`` [m/K], 3 per sensor.
    """
    return [f"b{c}_{sensor}" for sensor in variant.split("+") for c in "xyz"]


def sensor_set_design(ctx: Context, variant: str) -> np.ndarray:
    """(N, 3, 3S) design of a set of sensors ``a+b+...``: each rise on x, y and z.

    Parameters
    ----------
    ctx : Context
        The readings.
    variant : str
        S sensor names joined by ``+``.

    Returns
    -------
    ndarray, shape (N, 3, 3S)
        Rises [K].
    """
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
        """All changing structure sensors as one variant, when there are at least MIN_RIDGE_SENSORS.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            ``["a+b+..."]`` or empty.
        """
        sensors = ctx.structure_sensors()
        return ["+".join(sensors)] if len(sensors) >= MIN_RIDGE_SENSORS else []

    def settings(self, ctx, variant):
        """The ridge strengths searched.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).

        Returns
        -------
        list of dict
            ``{"ridge": lambda}`` (relative to each column's sum of squares).
        """
        return [{"ridge": value} for value in RIDGE_STRENGTHS]

    def parameter_names(self, variant, setting):
        """One gain per sensor and direction.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``b<x|y|z>_<sensor>`` [m/K].
        """
        return sensor_set_parameters(variant)

    def design(self, ctx, variant, setting):
        """Every sensor's rise on x, y and z.

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
            (N, 3, 3S) [K].
        """
        return sensor_set_design(ctx, variant)

    def parameter_limits(self, ctx, variant, setting):
        """Free expansion of the structure per kelvin.

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
        dict of str to tuple of (float, str)
            Parameter name -> (bound, reason): free expansion of the structure [m/K].
        """
        return _free_expansion_limits(ctx, self.parameter_names(variant, setting))

    def describe_setting(self, setting):
        """The setting in words, e.g. ``"ridge 0.1"``.

        Parameters
        ----------
        setting : dict
            The setting.

        Returns
        -------
        str
            The words.
        """
        return f"ridge {setting['ridge']:g}"

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
        sensors = variant.split("+")
        return (f"the residual follows the {len(sensors)} structure sensors together (ridge "
                f"strength {setting.get('ridge', float('nan')):g}, chosen inside each fold) - "
                "heat spread through the structure that no one sensor carries alone "
                "(Zhu eq. 3.12 with every sensor)")


def sensor_weights(parameters: dict[str, float], temperatures: dict[str, np.ndarray]
                   ) -> list[tuple[str, float]]:
    """Which sensors carry an all-sensor model: (sensor, share of the model's spread), the
    largest first - each sensor's |coefficient| x its temperature range, all components.

    Parameters
    ----------
    parameters : dict of str to float
        ``b<c>_<sensor>`` -> gain [m/K].
    temperatures : dict of str to ndarray, shape (N,)
        Sensor -> temperatures [degC] (only the range counts).

    Returns
    -------
    list of tuple of (str, float)
        (sensor, dimensionless share summing to 1), largest first.
    """
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
