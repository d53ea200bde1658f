"""The named variables an error can depend on, at N readings in time order.

Every effect family of the catalogue, every user expression and the
residual localisation read the machine's state through one
:class:`Variables` object, so that a variable means the same thing
everywhere. Names (the ones a user writes in an expression):

==================  ==================================================  =========
name                meaning                                             unit
==================  ==================================================  =========
``x y z a b c``     command position of that axis                       m, rad
``v_x`` ...         command velocity                                    m/s, rad/s
``acc_x`` ...       command acceleration (given, or d v / d t)          m/s^2
``dir_x`` ...       direction of the last motion (+1 / -1, 0 unknown)   1
``t``               time since the first reading (of its run)           s
``T_<sensor>``      rise of that temperature over its reference         K
``spindle_speed``   spindle speed                                       rad/s
``spindle_rpm``     the same in rpm (the unit machine tools speak)      1/min
==================  ==================================================  =========

First-order lags (a structure's temperature or growth following its heat
source with a time constant tau, Zhu eqs. 3.9-3.10 and the modal time
constants of Zhu eq. 3.17) are computed by :func:`first_order_lag`, exactly for
an input that is piecewise linear between readings. A lag of a temperature
starts in steady state (equal to its input at the first reading) - not from
zero, which would add a start-up ramp of the whole temperature; a lag of an
operating input (spindle speed, axis feed) starts from rest, a cold machine.

A record made of many **runs** (a log of many days, each a cold start; an
experiment repeated) gives ``run_starts``: every lag restarts at its run's
first reading as above, and ``t`` is the time since the run's start - the
time between runs (a night, a restarted clock) means nothing to the machine.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputDataError
from ..validation import as_samples
from .lru import ByteBoundedCache

AXIS_LETTERS = "XYZABC"
#: Lagged signals kept per set of readings [bytes] (:meth:`Variables.lag`).
LAG_MEMO_BYTES = 16 * 2 ** 20
#: ... and only while it can hold this many (a catalogue's thermal candidates ask for
#: 44-66 lags per selection step).
LAG_MEMO_KEPT = 64


def first_order_lag(time_s: ArrayLike, signal: ArrayLike, tau_s: float, *,
                    initial: float | None = None) -> NDArray[np.float64]:
    """y with tau dy/dt = u - y at the samples of u (shape (N,)), u piecewise linear.

    Between samples k and k+1, with u = u_k + s (t - t_k), s = (u_{k+1} - u_k) / dt:

        y_{k+1} = u_{k+1} - s tau + (y_k - u_k + s tau) exp(-dt / tau)

    which is exact for that input (no step-size error). Over equal stamps (dt = 0) y
    holds still. ``initial`` is y_0 (default u_0: steady state). ``tau_s`` = 0 returns
    u itself.

    Parameters
    ----------
    time_s : array_like, shape (N,)
        Sample times [s], not decreasing.
    signal : array_like, shape (N,)
        The input u at those times, any unit (the output has the same).
    tau_s : float
        Time constant [s], finite and >= 0.
    initial : float, optional
        y at the first sample, in the signal's unit (default u_0).

    Returns
    -------
    ndarray, shape (N,)
        The lagged signal y, in the signal's unit.

    Raises
    ------
    InputDataError
        Times that are not increasing, or non-finite values.
    """
    t = np.asarray(time_s, dtype=np.float64)
    u = np.asarray(signal, dtype=np.float64)
    if t.shape != u.shape or t.ndim != 1:
        raise InputDataError(f"lag: time {t.shape} and signal {u.shape} must be equal 1-D")
    if t.size == 0:
        return u.copy()
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(u))):
        raise InputDataError("lag: NaN/inf in the time or the signal")
    if tau_s < 0 or not np.isfinite(tau_s):
        raise InputDataError(f"lag: time constant {tau_s!r} s must be finite and >= 0")
    if tau_s == 0:
        return u.copy()
    dt = np.diff(t)
    if np.any(dt < 0):
        raise InputDataError("lag: the readings' times must not decrease")
    with np.errstate(divide="ignore", invalid="ignore"):
        slope_tau = np.where(dt > 0, np.diff(u) / np.where(dt > 0, dt, 1.0), 0.0) * tau_s
    start = u[0] if initial is None else float(initial)
    # The lag e = y - u obeys e_{k+1} = decay_k e_k + slope_tau_k (decay_k - 1), solved in
    # closed form over stretches whose total decay stays above e^-500 (no underflow):
    # e_n = P_n (e_s + sum_j b_j / P_{j+1}), P the running product of the decays.
    gain = slope_tau * np.expm1(-dt / tau_s)
    # Equal stamps (a coarse logger): no time passes, so y holds still and the lag takes
    # the input's step (the limit of a vanishing dt; without this y jumped with u).
    gain = np.where(dt > 0, gain, -np.diff(u))
    log_product = np.concatenate(([0.0], np.cumsum(-dt / tau_s)))
    lag = np.empty_like(u)
    lag[0] = start - u[0]
    s = 0
    while s < u.size - 1:
        end = max(s + 1, int(np.searchsorted(-log_product, -log_product[s] + 500.0,
                                             side="right")) - 1)
        end = min(end, u.size - 1)
        relative = log_product[s:end + 1] - log_product[s]          # log P_n / P_s
        inflow = np.cumsum(gain[s:end] * np.exp(-relative[1:]))
        lag[s + 1:end + 1] = np.exp(relative[1:]) * (lag[s] + inflow)
        s = end
    return u + lag


def run_starts_of(run_of_row: ArrayLike) -> NDArray[np.intp]:
    """(R,) first row of each run from a run label per row (N,) whose runs are contiguous.

    Parameters
    ----------
    run_of_row : array_like, shape (N,)
        A run label per row, equal within a run (any comparable values).

    Returns
    -------
    ndarray of int, shape (R,)
        Row index of each run's first row (starts with 0; empty for no rows).
    """
    labels = np.asarray(run_of_row)
    if labels.size == 0:
        return np.zeros(0, dtype=np.intp)
    return np.concatenate(([0], np.flatnonzero(labels[1:] != labels[:-1]) + 1)).astype(np.intp)


def subset_run_starts(run_starts: NDArray[np.intp], n: int, rows) -> NDArray[np.intp]:
    """The run starts of ``rows`` (an index or mask into n rows, in time order).

    Parameters
    ----------
    run_starts : ndarray of int, shape (R,)
        First row of each run of the n rows.
    n : int
        Number of rows.
    rows : ndarray of int or bool
        The rows kept: indices in time order, or a mask of shape (n,).

    Returns
    -------
    ndarray of int, shape (R',)
        First row of each run among the kept rows, as indices into them.
    """
    label = np.zeros(n, dtype=np.intp)
    label[np.asarray(run_starts)[1:]] = 1
    return run_starts_of(np.cumsum(label)[rows])


@dataclass
class LagState:
    """Where a lag stood at its last sample, so that a stream continues it.

    Attributes
    ----------
    time_s : float
        Time of the last sample [s].
    signal : float
        The input there, in the signal's unit.
    value : float
        The lag's output there, in the signal's unit.
    """

    time_s: float
    signal: float
    value: float


@dataclass
class Variables:
    """The machine's state at N readings (time order), by name.

    positions / velocities / accelerations / directions : axis letter -> (N,)
    temperatures : sensor -> (N,) [degC]; ``reference_temperatures_c`` the
    values the rises are taken from (default: each sensor's first reading).
    time_s : (N,) absolute or relative [s]. spindle_speed_rad_s : (N,) or None.
    lag_states : optional store that continues lags across calls (live nodes).
    run_starts : optional (R,) increasing row indices, the first row of each run
    (the first is 0): lags restart and ``t`` counts from each run's start.

    Parameters
    ----------
    positions : dict of str to ndarray, shape (N,)
        Axis letter -> command position [m] (rotary [rad]); a scalar is broadcast.
    time_s : ndarray, shape (N,), optional
        Reading times [s].
    velocities : dict of str to ndarray, shape (N,), optional
        Axis letter -> command velocity [m/s] (rotary [rad/s]).
    accelerations : dict of str to ndarray, shape (N,), optional
        Axis letter -> command acceleration [m/s^2] (rotary [rad/s^2]).
    directions : dict of str to ndarray, shape (N,), optional
        Axis letter -> direction of the last motion (+1 / -1, 0 unknown).
    temperatures : dict of str to ndarray, shape (N,), optional
        Sensor name -> temperature [degC].
    reference_temperatures_c : dict of str to float, optional
        Sensor name -> reference of its rise [degC] (default its first reading).
    spindle_speed_rad_s : ndarray, shape (N,), optional
        Spindle speed [rad/s].
    lag_states : dict, optional
        (key, tau [s]) -> :class:`LagState`, kept across calls (live nodes).
    run_starts : ndarray of int, shape (R,), optional
        First row of each run, increasing from 0.

    Raises
    ------
    InputDataError
        No positions, or run starts that are not increasing row indices from 0.
    """

    positions: dict[str, NDArray[np.float64]]
    time_s: NDArray[np.float64] | None = None
    velocities: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    accelerations: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    directions: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    temperatures: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    reference_temperatures_c: dict[str, float] = field(default_factory=dict)
    spindle_speed_rad_s: NDArray[np.float64] | None = None
    lag_states: dict | None = None
    run_starts: NDArray[np.intp] | None = None

    def __post_init__(self) -> None:
        self._lag_memo: ByteBoundedCache | None = None   # lags kept: lag()
        if not self.positions:
            raise InputDataError("variables: no axis positions")
        self.n = int(np.size(next(iter(self.positions.values()))))
        cast = lambda d: {k: as_samples(v, self.n) for k, v in d.items()}  # noqa: E731
        self.positions = cast(self.positions)
        self.velocities = cast(self.velocities)
        self.accelerations = cast(self.accelerations)
        self.directions = cast(self.directions)
        self.temperatures = cast(self.temperatures)
        if self.time_s is not None:
            self.time_s = np.broadcast_to(np.asarray(self.time_s, dtype=np.float64).ravel(),
                                          (self.n,))
        if self.spindle_speed_rad_s is not None:
            self.spindle_speed_rad_s = np.broadcast_to(
                np.asarray(self.spindle_speed_rad_s, dtype=np.float64).ravel(), (self.n,))
        if self.run_starts is not None:
            starts = np.asarray(self.run_starts, dtype=np.intp).ravel()
            if self.n and (starts.size == 0 or starts[0] != 0 or np.any(np.diff(starts) <= 0)
                           or starts[-1] >= self.n):
                raise InputDataError(f"run starts {starts.tolist()[:8]}: increasing row "
                                     f"indices from 0, below {self.n}")
            self.run_starts = starts if starts.size > 1 else None

    def run_slices(self) -> list[slice]:
        """The rows of each run (one slice of every row without runs)."""
        if self.run_starts is None:
            return [slice(0, self.n)]
        edges = list(self.run_starts) + [self.n]
        return [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]

    # ------------------------------------------------------------ primitives
    def rise(self, sensor: str) -> NDArray[np.float64]:
        """Temperature rise of ``sensor`` over its reference [K], shape (N,).

        Parameters
        ----------
        sensor : str
            Sensor name.

        Returns
        -------
        ndarray, shape (N,)
            Temperature minus the sensor's reference [K].

        Raises
        ------
        InputDataError
            No such sensor.
        """
        if sensor not in self.temperatures:
            raise InputDataError(f"no temperature {sensor!r}; have "
                                 f"{', '.join(sorted(self.temperatures)) or 'none'}")
        values = self.temperatures[sensor]
        reference = self.reference_temperatures_c.get(sensor)
        if reference is None:
            reference = float(values[0])
        return values - reference

    def span_s(self) -> float:
        """The longest stretch of time one run covers [s] (the record's, without runs): what
        a lag or a drift can be seen over."""
        if self.time_s is None or self.n < 2:
            return 0.0
        return max(float(np.ptp(self.time_s[rows])) if rows.stop > rows.start else 0.0
                   for rows in self.run_slices())

    def relative_time(self) -> NDArray[np.float64]:
        """Time since the first reading [s] - of its run, when there are runs."""
        if self.time_s is None:
            raise InputDataError("this effect needs the readings' times")
        if self.run_starts is None:
            return self.time_s - self.time_s[0]
        out = np.empty(self.n)
        for rows in self.run_slices():
            out[rows] = self.time_s[rows] - self.time_s[rows.start]
        return out

    def velocity(self, axis: str) -> NDArray[np.float64]:
        """The command velocity of ``axis``, shape (N,) [m/s] (rotary [rad/s]).

        Parameters
        ----------
        axis : str
            Axis letter.

        Returns
        -------
        ndarray, shape (N,)
            Velocity [m/s] (rotary [rad/s]).

        Raises
        ------
        InputDataError
            No velocity of that axis.
        """
        if axis not in self.velocities:
            raise InputDataError(f"this effect needs the {axis} velocity")
        return self.velocities[axis]

    def acceleration(self, axis: str) -> NDArray[np.float64]:
        """Given accelerations, else the time derivative of the velocity [m/s^2].

        Parameters
        ----------
        axis : str
            Axis letter.

        Returns
        -------
        ndarray, shape (N,)
            Acceleration [m/s^2] (rotary [rad/s^2]); zeros when the times do not increase.

        Raises
        ------
        InputDataError
            Neither accelerations nor velocities and times of that axis.
        """
        if axis in self.accelerations:
            return self.accelerations[axis]
        v = self.velocity(axis)
        if self.time_s is None or self.n < 2:
            raise InputDataError(f"the {axis} acceleration needs accelerations or times")
        return np.gradient(v, self.time_s) if np.all(np.diff(self.time_s) > 0) else \
            np.zeros(self.n)

    def direction(self, axis: str) -> NDArray[np.float64]:
        """The last direction of motion where known, else sign(v).

        Parameters
        ----------
        axis : str
            Axis letter.

        Returns
        -------
        ndarray, shape (N,)
            +1 / -1, 0 where unknown (dimensionless).

        Raises
        ------
        InputDataError
            Neither directions nor velocities of that axis.
        """
        if axis in self.directions:
            held = self.directions[axis]
            return np.where(held != 0, np.sign(held), np.sign(self.velocities.get(
                axis, np.zeros(self.n))))
        return np.sign(self.velocity(axis))

    def spindle_speed(self) -> NDArray[np.float64]:
        if self.spindle_speed_rad_s is None:
            raise InputDataError("this effect needs the spindle speed")
        return self.spindle_speed_rad_s

    def lag(self, key: str, signal: NDArray[np.float64], tau_s: float, *,
            from_rest: bool = False) -> NDArray[np.float64]:
        """First-order lag of ``signal`` (see :func:`first_order_lag`), continued from
        ``lag_states[key, tau]`` when that state lies before these readings.

        Without live states the result is a function of the readings alone: it is kept
        (read-only, up to :data:`LAG_MEMO_BYTES`) for the next design that asks for the
        same signal and time constant - a selection asks again at every step.

        Parameters
        ----------
        key : str
            Name of the lagged signal (the key of its live state).
        signal : ndarray, shape (N,)
            The input, any unit (the output has the same).
        tau_s : float
            Time constant [s].
        from_rest : bool, optional
            Start from 0 (an operating input, a cold machine) instead of steady state.

        Returns
        -------
        ndarray, shape (N,)
            The lagged signal, in the signal's unit (read-only when kept).

        Raises
        ------
        InputDataError
            No reading times, or times that decrease.
        """
        if self.lag_states is not None:
            return self._lag(key, signal, tau_s, from_rest)
        signal = np.ascontiguousarray(signal, dtype=np.float64)
        if self._lag_memo is None:
            # A selection step asks for dozens before asking again: nothing is kept that
            # the memo could not hold that many of (1e5 readings: 0.8 MB each).
            self._lag_memo = ByteBoundedCache(LAG_MEMO_BYTES, LAG_MEMO_KEPT)
        memo_key = (key, float(tau_s), bool(from_rest), hashlib.sha1(signal).digest())
        lagged = self._lag_memo.get(memo_key)
        if lagged is None:
            lagged = self._lag(key, signal, tau_s, from_rest)
            lagged.flags.writeable = False
            self._lag_memo.put(memo_key, lagged)
        return lagged

    def _lag(self, key: str, signal: NDArray[np.float64], tau_s: float, from_rest: bool
             ) -> NDArray[np.float64]:
        if self.run_starts is not None and self.lag_states is None:
            # Each run from its own first reading (a cold start, a new day).
            t, out = self.relative_time(), np.empty(self.n)
            for rows in self.run_slices():
                out[rows] = first_order_lag(t[rows], signal[rows], tau_s,
                                            initial=0.0 if from_rest else None)
            return out
        t = self.relative_time() if self.lag_states is None else self.time_s
        state_key = (key, float(tau_s))
        state = self.lag_states.get(state_key) if self.lag_states is not None else None
        if state is not None and self.time_s is not None and t[0] >= state.time_s:
            y = first_order_lag(np.concatenate([[state.time_s], t]),
                                np.concatenate([[state.signal], signal]), tau_s,
                                initial=state.value)[1:]
        else:
            y = first_order_lag(t, signal, tau_s, initial=0.0 if from_rest else None)
        if self.lag_states is not None and self.n:
            self.lag_states[state_key] = LagState(float(t[-1]), float(signal[-1]), float(y[-1]))
        return y

    # ------------------------------------------------------------ by name
    def names(self) -> list[str]:
        """Every scalar variable available here (see the module table)."""
        out = [a.lower() for a in self.positions]
        out += [f"v_{a.lower()}" for a in self.velocities]
        out += [f"dir_{a.lower()}" for a in self.velocities if a in self.positions]
        if self.time_s is not None:
            out.append("t")
            out += [f"acc_{a.lower()}" for a in self.velocities]
        else:
            out += [f"acc_{a.lower()}" for a in self.accelerations]
        out += [f"T_{s}" for s in self.temperatures]
        if self.spindle_speed_rad_s is not None:
            out += ["spindle_speed", "spindle_rpm"]
        return list(dict.fromkeys(out))

    def get(self, name: str) -> NDArray[np.float64]:
        """The variable ``name`` (N,); raises InputDataError naming what exists.

        Parameters
        ----------
        name : str
            A variable's name (see the module table), e.g. ``x``, ``v_x``, ``T_spindle``.

        Returns
        -------
        ndarray, shape (N,)
            The variable in its unit (module table).

        Raises
        ------
        InputDataError
            An unknown name, or one whose data is missing.
        """
        try:
            if name == "t":
                return self.relative_time()
            if name == "spindle_speed":
                return self.spindle_speed()
            if name == "spindle_rpm":
                return self.spindle_speed() * 60.0 / (2.0 * np.pi)
            if name.startswith("T_"):
                return self.rise(name[2:])
            for prefix, getter in (("v_", self.velocity), ("acc_", self.acceleration),
                                   ("dir_", self.direction)):
                if name.startswith(prefix) and name[len(prefix):].upper() in AXIS_LETTERS:
                    return getter(name[len(prefix):].upper())
            if len(name) == 1 and name.upper() in self.positions:
                return self.positions[name.upper()]
        except InputDataError:
            pass
        raise InputDataError(f"unknown variable {name!r}; available: {', '.join(self.names())}")

    def subset(self, rows) -> "Variables":
        """The variables at some of the readings, runs kept.

        Parameters
        ----------
        rows : ndarray of int or bool
            The rows kept: indices in time order, or a mask of shape (N,).

        Returns
        -------
        Variables
            The same variables at those rows (references kept; live lag states not carried).
        """
        pick = lambda d: {k: np.asarray(v)[rows] for k, v in d.items()}  # noqa: E731
        return Variables(pick(self.positions),
                         None if self.time_s is None else self.time_s[rows],
                         pick(self.velocities), pick(self.accelerations), pick(self.directions),
                         pick(self.temperatures), dict(self.reference_temperatures_c),
                         None if self.spindle_speed_rad_s is None else
                         self.spindle_speed_rad_s[rows],
                         run_starts=None if self.run_starts is None else
                         subset_run_starts(self.run_starts, self.n, rows))
