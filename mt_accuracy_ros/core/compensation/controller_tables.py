"""Positioning-error tables a control loads: SINUMERIK EEC, FANUC pitch error data, the
ISG / TwinCAT leadscrew error compensation list and LinuxCNC's joint compensation files.

Both controls compensate each linear axis' **positioning error** E_AA(q) (ISO 230-1)
from a table of equidistant points, interpolated between them; straightness, tilt
and squareness need their cross or volumetric compensations (the ISG parameter file
of :mod:`.cnc_export`). What a model holds beyond E_AA is said, never dropped
silently.

**SINUMERIK leadscrew / measuring-system error compensation (EEC)**, an ``.INI``
part program (SINUMERIK function manual K3, "Interpolatory compensation"):
``$AA_ENC_COMP[e,N,AX]`` the compensation value of point N [mm], ``$AA_ENC_COMP_STEP``
the distance between points [mm], ``$AA_ENC_COMP_MIN``/``_MAX`` the first and last
point's position [mm], ``$AA_ENC_COMP_IS_MODULO`` 0 for a linear axis; the control
holds at most MD38000 ``$MA_MM_ENC_COMP_MAX_POINTS`` points. A positive value moves
the axis in the negative direction, so the value is the error itself, E = actual -
nominal. The value at the reference point should be zero (no jump when the
compensation becomes active): the table is shifted so, and the shift is reported.

**FANUC pitch error compensation** (parameters 3620-3624 and the compensation data):
points at ``3624`` (interval) apart, numbered so that point ``3620`` is the reference
position, from ``3621`` (most negative) to ``3622`` (most positive); the value at point
n is the *increment* of the compensation over the section from point n-1 to n, in
detection units times the magnification ``3623``, an integer within the control's
range per point. The compensation is added to the command, so it is minus the
error; absolute values are rounded first and differenced, so rounding never
accumulates. Written as a parameter tape (``N<param>A<axis>P<value>``; compensation
data as ``N<10000 + point>P<value>``).

Spacing (:func:`spacing_for`): the coarsest of a list of round spacings whose table
holds the model within the instrument's band *and* samples every periodic effect at
8 or more points a period; a spacing asked for that cannot is refused with the
smallest one that can; a control's point limit that forces a coarser table is said,
with the error it leaves.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError
from .error_model import ErrorModel
from .user_tables import refuse_untabled

#: Round spacings tried, coarsest first [m].
NICE_SPACINGS_M = tuple(v * 1e-3 for v in (50, 40, 25, 20, 10, 8, 5, 4, 2.5, 2, 1.25, 1, 0.8,
                                           0.5, 0.4, 0.25, 0.2, 0.1, 0.05))
#: Points a table gives each period of a periodic effect, at least (a sinusoid
#: interpolated linearly at 8 points a period keeps 92 % of its amplitude).
POINTS_PER_PERIOD = 8

#: Point limits of the controls, per axis table (what forces a coarser table).
#: SINUMERIK: MD38000 $MA_MM_ENC_COMP_MAX_POINTS of the control (808D: 200); FANUC:
#: the compensation points one axis may use between its extremes (128 is common).
CONTROLLERS = {"siemens": {"max_points": 200, "name": "SINUMERIK EEC"},
               "twincat": {"max_points": 1499, "name": "ISG / TwinCAT leadscrew error "
                                                      "compensation (kw.ssfk)"},
               "linuxcnc": {"max_points": 256, "name": "LinuxCNC joint compensation "
                                                       "(COMP_FILE)"},
               "fanuc": {"max_points": 128, "name": "FANUC pitch error compensation",
                         "detection_unit_m": 1e-6, "magnification": 1, "step_limit": 7}}


@dataclass
class SpacingChoice:
    """A table spacing and why: the error it leaves and what limited it.

    Parameters
    ----------
    spacing_m : float
        Table spacing [m].
    max_error_m : float
        Largest |table - model| of any axis' E_AA [m].
    periods_m : dict of str to float
        Periodic effects: name -> period [m].
    limited_by : str
        "" or why the spacing is coarser than wished.
    errors_m : dict of str to float
        Axis -> its largest interpolation error [m].
    """

    spacing_m: float
    max_error_m: float                 # largest |table - model| of any axis' E_AA
    periods_m: dict[str, float]        # periodic effects: name -> period
    limited_by: str = ""               # "" or why the spacing is coarser than wished
    errors_m: dict[str, float] = field(default_factory=dict)   # per axis


def periodic_periods(model: ErrorModel) -> dict[str, float]:
    """The periods [m] of the model's periodic catalogue effects (name -> period).

    Parameters
    ----------
    model : ErrorModel
        The model.

    Returns
    -------
    dict of str to float
        Effect name -> ``setting.period_m`` [m], for effects that have one.
    """
    out = {}
    for name, entry in model.effects.items():
        setting = entry.get("setting") if isinstance(entry, dict) else None
        if setting and "period_m" in setting:
            out[name] = float(setting["period_m"])
    return out


def positioning_error(model: ErrorModel, axis: str, q: NDArray[np.float64]
                      ) -> NDArray[np.float64]:
    """The positioning error of ``axis`` at command ``q`` in the axis' own terms (actual
    minus commanded axis position) [m]: every fitted effect a table of it can hold.

    E_AA is the moving body's error along its direction in the machine frame; an axis
    whose positive command moves its body backwards (``sign`` -1: a table moving against
    the tool's commanded motion) is that much *behind* its command, so its table holds
    sign x E_AA. A table written without the sign would double such an axis' error.

    Parameters
    ----------
    model : ErrorModel
        The model whose fitted positioning errors are tabled.
    axis : str
        Linear axis letter.
    q : ndarray, shape (K,)
        Commands of ``axis`` [m].

    Returns
    -------
    ndarray, shape (K,)
        sign x E_AA [m].

    Raises
    ------
    ParameterError
        A fitted user effect of this axis no table can hold.
    """
    sign = model.machine.axes[axis].sign
    return sign * np.asarray(model.component_errors(axis, q, strict=True)[f"E{axis}{axis}"],
                             dtype=np.float64)


def linear_axes(model: ErrorModel) -> list[str]:
    """The linear axes in a control's order (X, Y, Z first: its axis numbers 1, 2, 3).

    Parameters
    ----------
    model : ErrorModel
        The model (its machine's axes).

    Returns
    -------
    list of str
        Linear axis letters.
    """
    machine = model.machine
    axes = [a for a in machine.axis_order if not machine.axes[a].is_rotary]
    return sorted(axes, key=lambda a: ("XYZUVW".index(a) if a in "XYZUVW" else 9, a))


def table_points(stroke: tuple[float, float], spacing_m: float) -> NDArray[np.float64]:
    """Equidistant points from the stroke's start covering its end (a control's table
    is equidistant: the last point may lie past the stroke's end).

    Parameters
    ----------
    stroke : tuple of float, (low, high)
        Travel [m].
    spacing_m : float
        Distance between points [m] (> 0).

    Returns
    -------
    ndarray, shape (K,)
        ``low + spacing_m * k``, k = 0 .. ceil(length / spacing_m) [m].
    """
    length = stroke[1] - stroke[0]
    count = int(np.ceil(length / spacing_m - 1e-9))
    return stroke[0] + spacing_m * np.arange(count + 1)


def interpolation_error(model: ErrorModel, axis: str, spacing_m: float,
                        dense: int = 20001) -> float:
    """max |linear interpolation of E_AA at ``spacing_m`` - E_AA| over the stroke [m].

    Parameters
    ----------
    model : ErrorModel
        The model whose fitted positioning errors are tabled.
    axis : str
        Linear axis letter.
    spacing_m : float
        Distance between table points [m].
    dense : int, optional
        Points the stroke is checked at.

    Returns
    -------
    float
        Largest interpolation error [m].
    """
    stroke = model.machine.axes[axis].stroke
    points = table_points(stroke, spacing_m)
    q = np.linspace(*stroke, dense)
    table = np.interp(q, points, positioning_error(model, axis, points))
    return float(np.max(np.abs(table - positioning_error(model, axis, q))))


def period_problems(periods: dict[str, float], spacing_m: float) -> list[str]:
    """Why ``spacing_m`` samples a periodic effect too coarsely (one line each).

    Parameters
    ----------
    periods : dict of str to float
        Effect name -> period [m].
    spacing_m : float
        Table spacing [m].

    Returns
    -------
    list of str
        One sentence per effect with fewer than :data:`POINTS_PER_PERIOD` points a period.
    """
    return [f"{name} has a {period * 1e3:.4g} mm period ({POINTS_PER_PERIOD} points a "
            f"period need <= {period / POINTS_PER_PERIOD * 1e3:.4g} mm)"
            for name, period in periods.items() if period / spacing_m < POINTS_PER_PERIOD]


def volumetric_spacing(model: ErrorModel, band_m: float) -> float:
    """The coarsest round spacing whose bilateral tables and volumetric file, read back and
    applied (:func:`.cnc_export.round_trip`), keep the TCP within ``band_m`` and sample
    every period at :data:`POINTS_PER_PERIOD` points or more.

    Parameters
    ----------
    model : ErrorModel
        The model exported.
    band_m : float
        Largest TCP error the tables may leave [m].

    Returns
    -------
    float
        Spacing [m] from :data:`NICE_SPACINGS_M` (the finest when none holds).
    """
    from .cnc_export import round_trip

    periods = periodic_periods(model)
    shortest = min((hi - lo for lo, hi in (model.machine.axes[a].stroke
                                        for a in linear_axes(model))), default=1.0)
    for spacing in NICE_SPACINGS_M:
        if spacing > shortest or period_problems(periods, spacing):
            continue
        if round_trip(model, spacing, points=500).tcp_max_error_m <= band_m:
            return spacing
    return NICE_SPACINGS_M[-1]


def _holds(model: ErrorModel, spacing_m: float, band_m: float, periods: dict[str, float]
           ) -> tuple[bool, dict[str, float]]:
    errors = {a: interpolation_error(model, a, spacing_m) for a in linear_axes(model)}
    return not period_problems(periods, spacing_m) and \
        max(errors.values(), default=0.0) <= band_m, errors


def spacing_for(model: ErrorModel, band_m: float, *, asked_m: float | None = None,
                max_points: int | None = None) -> SpacingChoice:
    """The table spacing (see the module docstring).

    Parameters
    ----------
    model : ErrorModel
        The model whose fitted positioning errors are tabled.
    band_m : float
        The largest interpolation error allowed [m] (the instrument's band).
    asked_m : float, optional
        A spacing the user asked for: refused (ParameterError, with the smallest spacing
        that holds the model) if it cannot hold it.
    max_points : int, optional
        The control's points per axis: a table may not need more.

    Returns
    -------
    SpacingChoice
        The spacing [m], the error it leaves [m] and what limited it.

    Raises
    ------
    ParameterError
        The asked spacing cannot hold the model, or not a positive number.
    """
    refuse_untabled(model)
    if not (np.isfinite(band_m) and band_m > 0):
        raise ParameterError(f"band {band_m!r} m: a positive number")
    periods = periodic_periods(model)
    axes = linear_axes(model)
    strokes = {a: model.machine.axes[a].stroke for a in axes}
    holding = None
    for spacing in NICE_SPACINGS_M:
        ok, errors = _holds(model, spacing, band_m, periods)
        if ok:
            holding = (spacing, errors)
            break
    if asked_m is not None:
        if not (np.isfinite(asked_m) and asked_m > 0):
            raise ParameterError(f"table spacing must be a positive number (got {asked_m!r})")
        ok, errors = _holds(model, asked_m, band_m, periods)
        if not ok:
            why = period_problems(periods, asked_m)
            worst = max(errors.values(), default=0.0)
            if worst > band_m:
                why.append(f"the table would leave {worst * 1e6:.3g} um against a band of "
                           f"{band_m * 1e6:.3g} um")
            smallest = (f"the coarsest spacing that holds it is {holding[0] * 1e3:g} mm"
                        if holding else "no spacing down to "
                        f"{NICE_SPACINGS_M[-1] * 1e3:g} mm holds it")
            raise ParameterError(f"spacing {asked_m * 1e3:g} mm cannot hold this model: "
                                 f"{'; '.join(why)}; {smallest}")
        holding = (asked_m, errors)
    if holding is None:
        holding = (NICE_SPACINGS_M[-1], {a: interpolation_error(model, a, NICE_SPACINGS_M[-1])
                                         for a in axes})
    spacing, errors = holding
    limited = ""
    if max_points is not None:
        needed = max(table_points(strokes[a], spacing).size for a in axes) if axes else 0
        if needed > max_points:
            longest = max(strokes[a][1] - strokes[a][0] for a in axes)
            coarse = next((s for s in NICE_SPACINGS_M[::-1]
                           if table_points((0.0, longest), s).size <= max_points),
                          NICE_SPACINGS_M[0])
            errors = {a: interpolation_error(model, a, coarse) for a in axes}
            limited = (f"the control holds {max_points} points per axis: {spacing * 1e3:g} mm "
                       f"needs {needed}, so the table is {coarse * 1e3:g} mm apart and leaves up "
                       f"to {max(errors.values()) * 1e6:.3g} um (band {band_m * 1e6:.3g} um)")
            spacing = coarse
    return SpacingChoice(spacing, max(errors.values(), default=0.0), periods, limited, errors)


# ----------------------------------------------------------------------- SINUMERIK
def siemens_eec(model: ErrorModel, spacing_m: float, *, axis_names: dict[str, str] | None
                = None, reference_m: dict[str, float] | None = None) -> tuple[str, dict]:
    """The EEC ``.INI`` text for every linear axis, and per axis the shift applied so the
    value at the reference point is zero [m].

    Parameters
    ----------
    model : ErrorModel
        The model whose fitted positioning errors are tabled.
    spacing_m : float
        Distance between table points [m].
    axis_names : dict of str to str, optional
        Axis -> the control's axis name (default ``<axis>1``, e.g. ``X1``).
    reference_m : dict of str to float, optional
        Axis -> reference point [m] (default: 0 clipped into the stroke).

    Returns
    -------
    text : str
        The part program: values, step, min and max in [mm].
    shifts : dict of str to float
        Axis -> shift subtracted from its table [m].

    Raises
    ------
    ParameterError
        A fitted user effect no table can hold.
    """
    lines = ["%_N_AX_EEC_INI", "CHANDATA(1)",
             f"; mt-accuracy: positioning error compensation of {model.machine.name}, "
             "values in mm (a positive value moves the axis negative: value = error)"]
    shifts = {}
    for axis in linear_axes(model):
        name = (axis_names or {}).get(axis, f"{axis}1")
        stroke = model.machine.axes[axis].stroke
        points = table_points(stroke, spacing_m)
        values = positioning_error(model, axis, points)
        reference = (reference_m or {}).get(axis, min(max(0.0, stroke[0]), stroke[1]))
        shift = float(np.interp(reference, points, values))
        shifts[axis] = shift
        values = values - shift
        for n, value in enumerate(values):
            lines.append(f"$AA_ENC_COMP[0,{n},{name}]={value * 1e3:.6f}")
        lines += [f"$AA_ENC_COMP_STEP[0,{name}]={spacing_m * 1e3:.6f}",
                  f"$AA_ENC_COMP_MIN[0,{name}]={points[0] * 1e3:.6f}",
                  f"$AA_ENC_COMP_MAX[0,{name}]={points[-1] * 1e3:.6f}",
                  f"$AA_ENC_COMP_IS_MODULO[0,{name}]=0"]
    lines.append("M17")
    return "\n".join(lines) + "\n", shifts


# ----------------------------------------------------------------------- FANUC
#: FANUC numbers the pitch error compensation points of all axes 0..1023.
FANUC_POINTS = 1024


@dataclass
class FanucAxis:
    """One axis' FANUC pitch error compensation parameters.

    Parameters
    ----------
    axis_number : int
        The control's axis number (1, 2, 3 ...).
    reference_point : int
        Compensation point number of the reference position (parameter 3620).
    most_negative, most_positive : int
        First and last point numbers (3621, 3622).
    magnification : int
        Compensation magnification (3623).
    interval_units : int
        Point interval [detection units] (3624).
    increments : dict of int to int
        Point number -> increment over the section ending there [detection units /
        magnification].
    """
    axis_number: int
    reference_point: int       # 3620
    most_negative: int         # 3621
    most_positive: int         # 3622
    magnification: int         # 3623
    interval_units: int        # 3624 [detection units]
    increments: dict[int, int]  # point -> increment [detection units / magnification]


def fanuc_pitch(model: ErrorModel, spacing_m: float, *, detection_unit_m: float = 1e-6,
                magnification: int = 1, step_limit: int = 7, first_point: int = 0,
                reference_m: dict[str, float] | None = None
                ) -> tuple[str, dict[str, FanucAxis]]:
    """The parameter tape and its content per axis (see the module docstring).

    Parameters
    ----------
    model : ErrorModel
        The model whose fitted positioning errors are tabled.
    spacing_m : float
        Distance between table points [m].
    detection_unit_m : float, optional
        The control's detection unit [m].
    magnification : int, optional
        Compensation magnification (parameter 3623).
    step_limit : int, optional
        Largest increment per point the control takes [x magnification detection units].
    first_point : int, optional
        Number of the first compensation point used.
    reference_m : dict of str to float, optional
        Axis -> reference point [m] (default: 0 clipped into the stroke).

    Returns
    -------
    tape : str
        The parameter tape.
    axes : dict of str to FanucAxis
        Axis -> its parameters and increments.

    Raises
    ------
    ParameterError
        The spacing is not a whole number of detection units, or an increment exceeds
        ``step_limit`` x ``magnification`` (a finer spacing or a larger magnification
        is needed: both are named), or more than 1024 points in all.
    """
    interval = spacing_m / detection_unit_m
    if abs(interval - round(interval)) > 1e-6 * max(1.0, interval):
        raise ParameterError(f"spacing {spacing_m * 1e3:g} mm is not a whole number of "
                             f"detection units ({detection_unit_m * 1e3:g} mm)")
    lines = ["%", f"(MT-ACCURACY PITCH ERROR COMPENSATION OF {model.machine.name.upper()})"]
    axes, point = {}, first_point
    for number, axis in enumerate(linear_axes(model), start=1):
        stroke = model.machine.axes[axis].stroke
        reference = (reference_m or {}).get(axis, min(max(0.0, stroke[0]), stroke[1]))
        below = int(np.ceil((reference - stroke[0]) / spacing_m - 1e-9))
        above = int(np.ceil((stroke[1] - reference) / spacing_m - 1e-9))
        positions = reference + spacing_m * np.arange(-below, above + 1)
        # The compensation is minus the error, zero at the reference; rounded as absolute
        # values, then differenced (rounding never accumulates along the axis).
        absolute = -(positioning_error(model, axis, positions) -
                     float(np.interp(reference, positions,
                                     positioning_error(model, axis, positions))))
        counts = np.round(absolute / (detection_unit_m * magnification)).astype(np.int64)
        steps = np.diff(counts)
        if steps.size and np.max(np.abs(steps)) > step_limit:
            worst = int(np.max(np.abs(steps)))
            raise ParameterError(
                f"axis {axis}: a pitch error increment of {worst} x {magnification} detection "
                f"units between two points exceeds the control's {step_limit}: use a finer "
                f"spacing than {spacing_m * 1e3:g} mm or magnification (3623) "
                f">= {int(np.ceil(worst * magnification / step_limit))}")
        first = point
        reference_point = first + below
        increments = {first + k: int(steps[k - 1]) for k in range(1, positions.size)}
        increments[first] = 0          # the section before the first point: nothing
        axes[axis] = FanucAxis(number, reference_point, first, first + positions.size - 1,
                               magnification, int(round(interval)), increments)
        point = first + positions.size
    if point > FANUC_POINTS:
        raise ParameterError(f"{point} pitch error compensation points for "
                             f"{len(axes)} axes at {spacing_m * 1e3:g} mm; the control numbers "
                             f"0..{FANUC_POINTS - 1} for all axes together: use a coarser "
                             "spacing (the error it leaves is given by --controller's choice)")
    for parameter, field_name in ((3620, "reference_point"), (3621, "most_negative"),
                                  (3622, "most_positive"), (3623, "magnification"),
                                  (3624, "interval_units")):
        lines.append(f"N{parameter}" + "".join(
            f"A{a.axis_number}P{getattr(a, field_name)}" for a in axes.values()))
    for a in axes.values():
        for n in sorted(a.increments):
            lines.append(f"N{10000 + n}P{a.increments[n]}")
    lines.append("%")
    return "\n".join(lines) + "\n", axes


def directional_errors(model: ErrorModel, axis: str, spacing_m: float, most_points: int,
                       limit: str) -> tuple[NDArray, NDArray, NDArray]:
    """(points, error moving positive, error moving negative) (n,) [m] of ``axis``'s
    positioning error on a table of ``spacing_m``: moving positive the axis lags its
    reversal half behind, moving negative it leads by as much. More than ``most_points``
    points is refused, saying ``limit`` and the spacing that fits.

    Parameters
    ----------
    model : ErrorModel
        The model whose fitted positioning errors are tabled.
    axis : str
        Linear axis letter.
    spacing_m : float
        Distance between table points [m].
    most_points : int
        Points the control holds per axis.
    limit : str
        The limit's wording, quoted in the refusal.

    Returns
    -------
    points : ndarray, shape (n,)
        Table positions [m].
    forward, reverse : ndarray, shape (n,)
        Positioning error moving positive / negative [m].

    Raises
    ------
    ParameterError
        More than ``most_points`` points, or a user effect no table can hold.
    """
    stroke = model.machine.axes[axis].stroke
    points = table_points(stroke, spacing_m)
    if points.size > most_points:
        needed = (stroke[1] - stroke[0]) / (most_points - 1)
        raise ParameterError(f"axis {axis}: {points.size} compensation points at "
                             f"{spacing_m * 1e3:g} mm; {limit}: use a spacing of "
                             f"{needed * 1e3:.4g} mm or more")
    error = positioning_error(model, axis, points)
    half = 0.5 * model.backlash_m(axis)
    return points, error - half, error + half


# ----------------------------------------------------------------------- ISG / TwinCAT
#: Entries of one leadscrew error compensation table the control holds by default
#: (P-COMP-00059 ``kw.ssfk.max_points``; ``kw_nr_max`` must stay below it).
ISG_MAX_POINTS = 1500

#: The list's length unit with ``kw.ssfk.unit`` = 1 (metric) [m].
ISG_UNIT_M = 1e-7


@dataclass
class IsgAxis:
    """One axis' leadscrew error compensation list: interval and start [0.1 um], values
    per direction [0.1 um] (``neg`` None when unilateral).

    Parameters
    ----------
    axis_number : int
        ``kopf.achs_nr``.
    axis_name : str
        ``kopf.log_achs_name``.
    interval : int
        ``kw.ssfk.interval`` [0.1 um].
    start : int
        ``kw.ssfk.kw_startpos`` [0.1 um].
    pos : list of int
        Values moving positive [0.1 um].
    neg : list of int or None
        Values moving negative [0.1 um]; None when unilateral.
    """

    axis_number: int
    axis_name: str
    interval: int
    start: int
    pos: list[int]
    neg: list[int] | None


def isg_leadscrew_lists(model: ErrorModel, spacing_m: float, *, bilateral: bool = True,
                        max_points: int = ISG_MAX_POINTS,
                        axis_numbers: dict[str, int] | None = None
                        ) -> tuple[dict[str, str], dict[str, IsgAxis]]:
    """The ISG / TwinCAT CNC leadscrew error compensation list (``kw.ssfk``) of every
    linear axis: {file name: text} and the content per axis.

    Written to the ISG kernel's published rules (axis compensation, "Leadscrew error
    compensation (kw.ssfk.*)", P-COMP-00017..00025): the list header ``kopf.achs_nr``
    and ``kopf.log_achs_name``; ``kw.ssfk.unit`` 1 (metric: every length in 0.1 um);
    equidistant points - ``kw.ssfk.interval`` apart from ``kw.ssfk.kw_startpos`` -,
    ``kw.ssfk.kw_nr_max`` of them (below P-COMP-00059, default 1500);
    ``kw.ssfk.bilateral`` 1 with a value per direction (``table[i].pos`` moving
    positive, ``table[i].neg`` moving negative: the reversal error lives in the table,
    as ISG recommends instead of a separate backlash compensation) or 0 with one value
    for both; ``kw.ssfk.modulo`` 0 for a linear axis. A value is the axis' positioning
    error at the point, actual minus programmed position (ISG's example list: measured
    19856.5 um at 19866.7 um programmed gives ``pos`` -102), rounded to 0.1 um. Comment
    lines start with ``# ``.

    Parameters
    ----------
    model : ErrorModel
        The model whose fitted positioning errors are tabled.
    spacing_m : float
        Distance between table points [m].
    bilateral : bool, optional
        A value per direction (True) or their mean for both.
    max_points : int, optional
        ``kw.ssfk.max_points`` of the control.
    axis_numbers : dict of str to int, optional
        Axis -> the control's axis number (default 1, 2, 3 in :func:`linear_axes` order).

    Returns
    -------
    texts : dict of str to str
        File name (``achskw<n>.lis``) -> list text.
    axes : dict of str to IsgAxis
        Axis -> its list content [0.1 um].

    Raises
    ------
    ParameterError
        A spacing that is not a whole number of 0.1 um, or more points than the control
        holds (the spacing that fits is named).
    """
    interval = spacing_m / ISG_UNIT_M
    if not spacing_m > 0 or abs(interval - round(interval)) > 1e-6 * max(1.0, interval):
        raise ParameterError(f"spacing {spacing_m * 1e3:g} mm is not a whole number of 0.1 um "
                             "(kw.ssfk.interval)")
    texts, axes = {}, {}
    for number, axis in enumerate(linear_axes(model), start=1):
        number = (axis_numbers or {}).get(axis, number)
        points, forward, reverse = directional_errors(
            model, axis, spacing_m, max_points - 1,
            f"the control holds fewer than {max_points} (kw.ssfk.max_points)")
        both = (forward + reverse) / 2.0
        pos = np.round((forward if bilateral else both) / ISG_UNIT_M).astype(np.int64)
        neg = np.round(reverse / ISG_UNIT_M).astype(np.int64) if bilateral else None
        record = IsgAxis(number, axis, int(round(interval)),
                         int(round(points[0] / ISG_UNIT_M)), [int(v) for v in pos],
                         None if neg is None else [int(v) for v in neg])
        lines = [f"# mt-accuracy: leadscrew error compensation of {model.machine.name}, "
                 f"axis {axis}",
                 "# values: actual - programmed position, 0.1 um (kw.ssfk.unit 1)",
                 f"kopf.achs_nr                {number}",
                 f"kopf.log_achs_name          {axis}",
                 "kw.ssfk.unit                1",
                 f"kw.ssfk.interval            {record.interval}",
                 f"kw.ssfk.kw_startpos         {record.start}",
                 f"kw.ssfk.kw_nr_max           {points.size}",
                 f"kw.ssfk.bilateral           {1 if bilateral else 0}",
                 "kw.ssfk.modulo              0"]
        lines += [f"kw.ssfk.table[{i}].pos {v}" for i, v in enumerate(record.pos)]
        if record.neg is not None:
            lines += [f"kw.ssfk.table[{i}].neg {v}" for i, v in enumerate(record.neg)]
        texts[f"achskw{number}.lis"] = "\n".join(lines) + "\n"
        axes[axis] = record
    return texts, axes


# ----------------------------------------------------------------------- LinuxCNC
#: Compensation triplets LinuxCNC's motion module holds per joint (EMCMOT_COMP_SIZE).
LINUXCNC_MAX_POINTS = 256


def linuxcnc_comp_files(model: ErrorModel, spacing_m: float, *, file_type: int = 0,
                        unit_m: float = 1e-3) -> tuple[dict[str, str], dict[str, str]]:
    """LinuxCNC joint compensation files (``[JOINT_n]`` ``COMP_FILE``) of every linear axis:
    ({file name: text}, {axis: the INI lines that load it}).

    Written to LinuxCNC's rules (INI configuration, ``COMP_FILE`` / ``COMP_FILE_TYPE``,
    and the loader's reading of them): one line per point, three numbers separated by
    spaces in machine units (``unit_m``: mm by default, as ``LINEAR_UNITS``), nothing
    else - the loader stops at the first line that is not three numbers, so the file
    has no header or comment; nominals strictly ascending from the smallest; at most
    256 points a joint. The first number is the nominal (commanded) position. Type 0:
    then the actual position moving positive and moving negative (nominal + the error
    of that direction). Type 1: the trims the control adds to the command, nominal -
    actual, moving positive and negative. A joint with a ``COMP_FILE`` uses no
    ``BACKLASH``: the reversal error is in the two columns.

    Parameters
    ----------
    model : ErrorModel
        The model whose fitted positioning errors are tabled.
    spacing_m : float
        Distance between table points [m].
    file_type : {0, 1}, optional
        ``COMP_FILE_TYPE``: actual positions (0) or trims (1).
    unit_m : float, optional
        The machine unit [m] (1e-3: mm).

    Returns
    -------
    texts : dict of str to str
        File name (``<axis>.comp``) -> text in machine units.
    ini : dict of str to str
        Axis -> its ``[JOINT_n]`` lines.

    Raises
    ------
    ParameterError
        A file type other than 0 or 1, or more than 256 points (the spacing that fits is
        named).
    """
    if file_type not in (0, 1):
        raise ParameterError(f"COMP_FILE_TYPE {file_type!r}: 0 (actual positions) or 1 "
                             "(trims)")
    texts, ini = {}, {}
    for number, axis in enumerate(linear_axes(model)):
        points, forward, reverse = directional_errors(
            model, axis, spacing_m, LINUXCNC_MAX_POINTS,
            f"LinuxCNC holds {LINUXCNC_MAX_POINTS} a joint")
        if file_type == 0:
            second, third = points + forward, points + reverse
        else:
            second, third = -forward, -reverse
        name = f"{axis}.comp"
        texts[name] = "".join(f"{p / unit_m:.6f} {a / unit_m:.6f} {b / unit_m:.6f}\n"
                              for p, a, b in zip(points, second, third))
        ini[axis] = f"[JOINT_{number}]\nCOMP_FILE = {name}\nCOMP_FILE_TYPE = {file_type}"
    return texts, ini


def uncovered_effects(model: ErrorModel) -> list[str]:
    """Fitted effects a positioning table does not hold (straightness, tilts, squareness,
    thermal): the control's other compensations, or the real-time offset, carry them.

    Parameters
    ----------
    model : ErrorModel
        The model.

    Returns
    -------
    list of str
        Names of fitted catalogue effects other than an axis' own positioning error.
    """
    from ..effects import is_catalogue_entry

    out = []
    for name, entry in model.effects.items():
        if not is_catalogue_entry(entry) or "family" not in entry:
            continue
        variant = str(entry.get("variant", ""))
        if entry["family"] in ("positioning", "positioning_periodic") and \
                len(variant) == 3 and variant[1] == variant[2]:
            continue
        out.append(name)
    return out
