"""Fitted parameters in the units their physics is read in, rounded to their uncertainty.

The model and the JSON keep SI (m, rad, s, m/K); a metrologist reads a drift gain in
um/K, a tilt in urad, a time constant in min, a pitch in mm. :func:`parameter_unit`
says which unit a catalogue parameter is read in, :func:`format_measured` writes
``value ± U`` with U (k = 2) to two significant digits and the value to the same
decimal place (GUM 7.2.6).
"""
from __future__ import annotations

import math

#: (unit, factor from SI) by kind of quantity.
UNITS = {"length": ("µm", 1e6), "angle": ("µrad", 1e6), "gain_k": ("µm/K", 1e6),
         "angle_k": ("µrad/K", 1e6), "expansion": ("µm/m/K", 1e6), "time": ("ms", 1e3),
         "per_acceleration": ("µm/(m/s²)", 1e6),
         "lever": ("mm", 1e3), "spindle_gain": ("µm/krpm", 1e6),
         "feed_gain": ("µm/(m/min)", 1e6), "per_score": ("µm per unit score", 1e6)}

_LENGTH_FAMILIES = {"positioning", "straightness", "positioning_periodic",
                    "straightness_periodic"}
_THERMAL_GAIN_FAMILIES = {"structural_thermal_drift", "thermal_lag", "thermal_gradient",
                          "all_sensors_ridge", "spindle_thermal_growth",
                          "sensor_least_squares"}


#: The kind of quantity each family's parameters are, where one kind fits them all.
_KIND_OF_FAMILY = {**{f: "length" for f in _LENGTH_FAMILIES},
                   **{f: "gain_k" for f in _THERMAL_GAIN_FAMILIES},
                   "angular": "angle", "angular_periodic": "angle", "squareness": "angle",
                   "position_dependent_thermal": "expansion", "thermal_squareness": "angle_k",
                   "reversal": "length", "setup_location": "length", "servo_lag": "time",
                   "acceleration": "per_acceleration",
                   # a twist's coefficient multiplies normalised positions: a length
                   "cross_axis": "length", "abbe_offset": "lever",
                   # a principal component's score is standardised: its gain is a length
                   "temperature_components": "per_score"}


def parameter_unit(family: str, variant: str, name: str) -> tuple[str, float]:
    """(unit, factor) a parameter ``name`` of ``family:variant`` is read in; ("", 1.0) for
    one without a physical reading (a user expression's own constants stay as declared).

    Parameters
    ----------
    family : str
        The family's name, e.g. ``structural_thermal_drift``.
    variant : str
        The variant, e.g. ``EXB`` for a rotary error.
    name : str
        The parameter's name.

    Returns
    -------
    tuple of (str, float)
        The unit read in (e.g. ``"µm/K"``) and the factor from the SI value to it.
    """
    if family == "rotary_error":        # E<component><axis>: a translation or a rotation
        kind = "length" if variant[1:2] in ("X", "Y", "Z") else "angle"
    elif family == "rotary_location":   # each parameter its own ISO location error
        kind = "length" if name[1:2] in ("X", "Y", "Z") else "angle"
    elif family in ("angular", "angular_arm") and name.startswith("lever_"):
        kind = "length"                 # a located tilt's lever: the carriage's move -P0 x p
    elif family == "heat_source":
        kind = "spindle_gain" if variant == "spindle_speed" else "feed_gain"
    else:
        kind = _KIND_OF_FAMILY.get(family)
    return UNITS[kind] if kind else ("", 1.0)


def format_measured(value: float, uncertainty: float | None, unit: str = "") -> str:
    """``1.47 ± 0.42 µm/K``: U to two significant digits, the value to its decimal place
    (no uncertainty: four significant digits).

    Parameters
    ----------
    value : float
        The value, in ``unit``.
    uncertainty : float or None
        Expanded uncertainty U (k = 2), in ``unit``; None or <= 0 for none.
    unit : str, optional
        Unit written after the numbers.

    Returns
    -------
    str
        ``value ± U unit``.
    """
    suffix = f" {unit}" if unit else ""
    if not math.isfinite(value):
        return f"{value}{suffix}"
    if uncertainty is None or not math.isfinite(uncertainty) or uncertainty <= 0:
        return f"{value:.4g}{suffix}"
    decimals = 1 - int(math.floor(math.log10(uncertainty)))
    if decimals > 0:
        return f"{value:.{decimals}f} ± {uncertainty:.{decimals}f}{suffix}"
    step = 10.0 ** (-decimals)

    def half_up(x: float) -> float:   # 12345 to tens is 12350, as a reader rounds
        return math.copysign(math.floor(abs(x) / step + 0.5) * step, x)

    return f"{half_up(value):.0f} ± {half_up(uncertainty):.0f}{suffix}"


def display_parameters(family: str, variant: str, parameters: dict[str, float],
                       standard_uncertainties: dict[str, float] | None = None
                       ) -> dict[str, str]:
    """Every parameter as ``value ± U (k = 2)`` in its physical unit.

    Parameters
    ----------
    family : str
        The family's name.
    variant : str
        The variant.
    parameters : dict of str to float
        Parameter name -> fitted value in SI (the family's parameter units).
    standard_uncertainties : dict of str to float, optional
        Parameter name -> standard uncertainty u (k = 1), SI; U = 2 u is shown.

    Returns
    -------
    dict of str to str
        Parameter name -> text in its reading unit (see :func:`format_measured`); a
        parameter with value and u both 0 (not measured) is left out.
    """
    out = {}
    for name, value in parameters.items():
        unit, factor = parameter_unit(family, variant, name)
        u = (standard_uncertainties or {}).get(name)
        if value == 0 and u == 0:
            continue   # a component these data did not measure: nothing was fitted

        out[name] = format_measured(float(value) * factor,
                                    None if u is None else 2.0 * float(u) * factor, unit)
    return out


def display_setting(setting: dict) -> str:
    """A searched setting as read: a period in mm, a time constant in min.

    Parameters
    ----------
    setting : dict
        The setting, SI (``period_m`` [m], ``tau_s`` [s], ...).

    Returns
    -------
    str
        Its parts joined by commas, e.g. ``"period 10 mm, tau 30 min"``.
    """
    parts = []
    for key, value in setting.items():
        if key in ("period_m", "period"):
            parts.append(f"period {float(value) * 1e3:.4g} mm")
        elif key in ("centre", "scale"):
            continue     # a principal-component setting's standardisation
        elif key == "loadings":
            parts.append(f"{len(value)} component(s)")
        elif key == "sensors":
            parts.append(f"of {str(value).count('+') + 1} sensors")
        elif key == "tau_s":
            parts.append(f"tau {float(value) / 60.0:.3g} min")
        elif isinstance(value, float):
            parts.append(f"{key} {value:.4g}")
        else:
            parts.append(f"{key} {value}")
    return ", ".join(parts)
