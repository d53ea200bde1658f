"""Units of measured quantities, and whether values read in a declared unit are plausible.

A value in a wrong unit is the commonest slip in a measurement file: errors in µm
declared as m (a 2.3 m RMS error), positions in mm declared as m (a 400 m travel that
the spectral search then grinds through), temperatures in kelvin declared as °C (a
reference temperature of 293 °C). Each reader converts with :data:`UNITS` /
:data:`TEMPERATURE` and then asks :func:`check_plausible`, which refuses values outside
the quantity's bounds in ONE line naming where they came from, the range found, and the
unit that would make them plausible (:func:`likely_unit`)::

    column dev_x (err.x): values 3.2 … 48.1 declared m look like um (plausible: |error|
    ≤ 5 mm); declare the unit (dev_x:um)

The check runs when a file is read, before any search: no computation sees an
implausible input.

Bounds (:data:`BOUNDS`), in SI (temperatures in degC), the one table every reader uses:

==================  ==========  =====================  ===============================
quantity            measure     plausible              why
==================  ==========  =====================  ===============================
position            max |x|     ≤ 10 m                 a machine tool's axis travel
travel              max - min   1 mm … 10 m            a laser run's sweep (10 mm … 10 m
                                                       typical; below 1 mm is no axis)
error               max |x|     ≤ 5 mm                 a machine's TCP / positioning error
deviation_spread    max - min   ≥ 10 nm                an axis's deviations over a real
                                                       travel (a laser resolves 1 nm; the
                                                       best axes spread ≥ 0.1 µm)
uncertainty         value       1 nm … 1 mm            an instrument's k = 2 figure
bar_length          value       10 mm … 2 m            a ball bar (50 … 1500 mm made)
tool_offset         max |x|     ≤ 2 m                  a tool's length (Abbe arm)
angle               max |x|     ≤ 40 pi rad            a rotary axis (20 turns)
angle_error         max |x|     ≤ 0.01 rad             a tool direction's change
temperature         min, max    -30 … +80 degC         structure, ambient, coolant
temperature_hot     min, max    -30 … +150 degC        spindle, motor, bearing, drive
velocity            max |x|     ≤ 5 m/s                a linear axis' feed (300 m/min)
angular_velocity    max |x|     ≤ 200 rad/s            a rotary axis (≈ 1900 rpm)
acceleration        max |x|     ≤ 100 m/s^2            10 g: beyond any linear motor
spindle_speed       max |x|     ≤ 10,500 rad/s         100,000 rpm
duration            max - min   ≤ 366 days             a survey's time span
==================  ==========  =====================  ===============================

Temperatures: kelvin declared as °C (290 … 310) is refused naming K; °F declared as °C
is refused only when it falls outside the range (a workshop's 60 … 100 °F reads as a
plausible 60 … 100 °C on a hot spindle and 15.6 … 37.8 °C are plausible too: the two
cannot be told apart by the values, only by the declaration).

Pure numpy, no ROS: the numerical core, the CLI readers and the thermal logs use it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError

LENGTH = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "micron": 1e-6, "nm": 1e-9,
          "in": 0.0254, "inch": 0.0254}
ANGLE = {"rad": 1.0, "mrad": 1e-3, "urad": 1e-6, "µrad": 1e-6, "deg": math.pi / 180.0,
         "arcsec": math.pi / 648000.0}
#: quantity -> unit -> the factor to SI.
UNITS = {
    "length": LENGTH, "angle": ANGLE,
    "time": {"s": 1.0, "ms": 1e-3, "min": 60.0, "h": 3600.0},
    "velocity": {"m/s": 1.0, "mm/s": 1e-3, "mm/min": 1e-3 / 60.0, "m/min": 1.0 / 60.0,
                 "rad/s": 1.0, "deg/s": math.pi / 180.0},
    "acceleration": {"m/s^2": 1.0, "mm/s^2": 1e-3, "rad/s^2": 1.0},
    "speed": {"rad/s": 1.0, "rpm": 2.0 * math.pi / 60.0, "1/min": 2.0 * math.pi / 60.0,
              "Hz": 2.0 * math.pi},
    "unitless": {"1": 1.0, "": 1.0},
}
#: Temperatures in degC (as sensor_msgs/Temperature): unit -> (scale, offset) to degC.
TEMPERATURE = {"degC": (1.0, 0.0), "C": (1.0, 0.0), "K": (1.0, -273.15),
               "degF": (5.0 / 9.0, -32.0 * 5.0 / 9.0)}


@dataclass(frozen=True)
class Bound:
    """What is plausible for a quantity, in SI (temperatures in degC).

    ``measure``: ``"magnitude"`` (max |x| ≤ high), ``"span"`` (low ≤ max - min ≤ high)
    or ``"value"`` (low ≤ every x ≤ high). ``typical``: a central value of the measure,
    which decides between units that would all be plausible. ``family``: the unit table
    (a key of :data:`UNITS`, or ``"temperature"``). ``label``: how a message names it.

    Attributes
    ----------
    measure : str
        ``"magnitude"``, ``"span"`` or ``"value"``.
    low, high : float
        The plausible range of the measure, SI ([degC] for temperatures).
    typical : float
        A central value of the measure, SI.
    family : str
        The unit table.
    label : str
        How a message names the quantity.
    shown : str
        How the bound reads in a message.
    """

    measure: str
    low: float
    high: float
    typical: float
    family: str
    label: str
    #: How the bound reads in a message (the SI figure in a user's unit).
    shown: str


#: The one table of bounds (the module docstring explains each).
BOUNDS: dict[str, Bound] = {
    "position": Bound("magnitude", 0.0, 10.0, 0.3, "length", "position", "|x| ≤ 10 m"),
    "travel": Bound("span", 1e-3, 10.0, 0.5, "length", "travel", "1 mm … 10 m"),
    "error": Bound("magnitude", 0.0, 5e-3, 1e-5, "length", "error", "|error| ≤ 5 mm"),
    "deviation_spread": Bound("span", 1e-8, 5e-3, 1e-5, "length", "spread of deviations",
                              "10 nm … 5 mm"),
    "uncertainty": Bound("value", 1e-9, 1e-3, 1e-6, "length", "uncertainty", "1 nm … 1 mm"),
    "bar_length": Bound("value", 1e-2, 2.0, 0.15, "length", "ball-bar length",
                        "10 mm … 2 m"),
    "tool_offset": Bound("magnitude", 0.0, 2.0, 0.15, "length", "tool offset", "|x| ≤ 2 m"),
    "angle": Bound("magnitude", 0.0, 40.0 * math.pi, math.pi, "angle", "rotary position",
                   "|angle| ≤ 20 turns"),
    "angle_error": Bound("magnitude", 0.0, 1e-2, 1e-5, "angle", "direction error",
                         "|angle| ≤ 0.01 rad"),
    "temperature": Bound("value", -30.0, 80.0, 22.0, "temperature", "temperature",
                         "-30 … +80 °C"),
    "temperature_hot": Bound("value", -30.0, 150.0, 35.0, "temperature", "temperature",
                             "-30 … +150 °C"),
    "velocity": Bound("magnitude", 0.0, 5.0, 0.05, "velocity", "velocity", "|v| ≤ 5 m/s"),
    "angular_velocity": Bound("magnitude", 0.0, 200.0, 1.0, "velocity", "angular velocity",
                              "|v| ≤ 200 rad/s"),
    "acceleration": Bound("magnitude", 0.0, 100.0, 2.0, "acceleration", "acceleration",
                          "|a| ≤ 100 m/s^2"),
    "spindle_speed": Bound("magnitude", 0.0, 10500.0, 1000.0, "speed", "spindle speed",
                           "≤ 100,000 rpm"),
    "duration": Bound("span", 0.0, 366 * 86400.0, 3600.0, "time", "time span",
                      "≤ 366 days"),
}

#: Units a likely-unit guess may name, most common first (spellings of one unit once).
_CANDIDATES = {"length": ("m", "mm", "um", "nm", "in"),
               "angle": ("rad", "deg", "mrad", "urad", "arcsec"),
               "time": ("s", "ms", "min", "h"),
               "velocity": ("m/s", "mm/s", "mm/min", "m/min", "deg/s"),
               "acceleration": ("m/s^2", "mm/s^2"),
               "speed": ("rad/s", "rpm", "Hz"),
               "temperature": ("degC", "K", "degF")}
#: Words in a sensor's name that make it a hot one (spindle, motor ...): up to 150 degC.
HOT_SENSOR_WORDS = ("spindle", "motor", "bearing", "drive", "hot")


def temperature_quantity(sensor: str) -> str:
    """``"temperature_hot"`` for a sensor named after a spindle, motor, bearing or drive
    (up to 150 degC), else ``"temperature"`` (structure, ambient: up to 80 degC).

    Parameters
    ----------
    sensor : str
        The sensor's name.

    Returns
    -------
    str
        A key of :data:`BOUNDS`.
    """
    name = sensor.lower()
    return "temperature_hot" if any(w in name for w in HOT_SENSOR_WORDS) else "temperature"


def to_si(values: np.ndarray, family: str, unit: str) -> np.ndarray:
    """``values`` in ``unit`` of a unit ``family`` in SI (temperatures in degC).

    Parameters
    ----------
    values : ndarray
        Values in ``unit``, any shape.
    family : str
        A key of :data:`UNITS`, or ``"temperature"``.
    unit : str
        A unit of that family (a key of its table, or of :data:`TEMPERATURE`).

    Returns
    -------
    ndarray of float64
        The values in SI ([m], [rad], [s] ...; temperatures [degC]), same shape.

    Raises
    ------
    KeyError
        A unit the family's table does not hold (callers check the unit first).
    """
    if family == "temperature":
        scale, offset = TEMPERATURE[unit]
        return np.asarray(values, dtype=np.float64) * scale + offset
    return np.asarray(values, dtype=np.float64) * UNITS[family][unit]


def _measure(si: np.ndarray, bound: Bound) -> tuple[float, float]:
    """The values' (smallest, largest) as the bound measures them."""
    if bound.measure == "magnitude":
        return 0.0, float(np.max(np.abs(si)))
    if bound.measure == "span":
        span = float(np.ptp(si))
        return span, span
    return float(np.min(si)), float(np.max(si))


def _plausible(si: np.ndarray, bound: Bound) -> bool:
    low, high = _measure(si, bound)
    if bound.measure == "magnitude":
        return high <= bound.high
    return low >= bound.low and high <= bound.high


def _distance(si: np.ndarray, bound: Bound) -> float:
    """How far the values lie from the quantity's typical figure (log for scales)."""
    low, high = _measure(si, bound)
    if bound.family == "temperature":
        return abs(0.5 * (low + high) - bound.typical)
    return abs(math.log10(max(high, 1e-300) / bound.typical))


def _bound(quantity: str) -> Bound:
    if quantity not in BOUNDS:
        raise ParameterError(f"plausibility: unknown quantity {quantity!r}; known: "
                             f"{', '.join(BOUNDS)}")
    return BOUNDS[quantity]


def likely_unit(values: np.ndarray, quantity: str, declared_unit: str = "") -> str | None:
    """The unit that brings ``values`` into ``quantity``'s plausible range (the one
    nearest its typical figure when several do), other than ``declared_unit``; None when
    no known unit does.

    Parameters
    ----------
    values : ndarray
        The values as given, any shape (non-finite ones are left out).
    quantity : str
        A key of :data:`BOUNDS`.
    declared_unit : str, optional
        The unit declared (not offered again).

    Returns
    -------
    str or None
        A unit of the quantity's family, or None.

    Raises
    ------
    ParameterError
        An unknown quantity.
    """
    bound = _bound(quantity)
    finite = np.asarray(values, dtype=np.float64)
    finite = finite[np.isfinite(finite)]
    if finite.size == 0:
        return None
    fits = [(_distance(to_si(finite, bound.family, unit), bound), unit)
            for unit in _CANDIDATES[bound.family] if unit != declared_unit
            and _plausible(to_si(finite, bound.family, unit), bound)]
    return min(fits)[1] if fits else None


#: How a message writes a unit (the map and the flags take the plain spelling).
_SHOWN_UNIT = {"um": "µm", "urad": "µrad", "degC": "°C", "degF": "°F", "in": "in (inches)"}


def shown_unit(unit: str) -> str:
    """``unit`` as a message writes it (``um`` -> ``µm``, ``degC`` -> ``°C``).

    Parameters
    ----------
    unit : str
        A unit in its plain spelling.

    Returns
    -------
    str
        The unit as written in messages.
    """
    return _SHOWN_UNIT.get(unit, unit)


def _values_found(raw: np.ndarray) -> str:
    low, high = float(raw.min()), float(raw.max())
    return f"value {low:.4g}" if low == high else f"values {low:.4g} … {high:.4g}"


def check_plausible(values: np.ndarray, quantity: str, declared_unit: str, where: str,
                    mend: str = "", error=ParameterError) -> None:
    """Refuse ``values`` (in ``declared_unit``) that are implausible for ``quantity``.

    Parameters
    ----------
    values : np.ndarray
        The values as the file gives them, in ``declared_unit`` (non-finite ones are
        not judged here: readers drop or refuse them by row).
    quantity : str
        A key of :data:`BOUNDS`.
    declared_unit : str
        The unit the values were declared in (a key of the quantity's unit table).
    where : str
        What the values are, for the message (``"column dev_x (err.x)"``).
    mend : str
        How to give another unit, appended to the message (``"declare it: dev_x:um"``).
    error : type
        The exception raised (the caller's: ParameterError, InputDataError).

    Raises
    ------
    error
        One line: ``where``, the range found, the declared unit, the likely unit (when
        one fits) and the plausible range.
    """
    bound = _bound(quantity)
    raw = np.asarray(values, dtype=np.float64).ravel()
    raw = raw[np.isfinite(raw)]
    if raw.size == 0 or _plausible(to_si(raw, bound.family, declared_unit), bound):
        return
    declared = shown_unit(declared_unit)
    text = f"{where}: {_values_found(raw)} declared {declared}"
    if bound.measure == "span":
        text += f" span {float(np.ptp(raw)):.4g} {declared}, an implausible {bound.label};"
    guess = likely_unit(raw, quantity, declared_unit)
    one = raw.min() == raw.max()
    text += f" {'looks' if one else 'look'} like {shown_unit(guess)}" if guess else \
        f" {'fits' if one else 'fit'} no known unit"
    text += f" (plausible {bound.label}: {bound.shown})"
    if mend:
        text += f"; {mend}"
    raise error(text)
