"""What a CNC does with the compensation it is sent: the two inputs real controllers have.

A CNC takes volumetric compensation in one of two ways, and a virtual machine
tool or a controller adapter applies it the same way:

* **tables** (:class:`TableCompensation`) - per-axis tables of the ISO 230-1
  component errors (EXX, EYX, ..., ECX against the X position) and the
  squareness errors, as volumetric-compensation packages read them. The
  controller interpolates each table linearly at the axis' command position and
  combines the components through its own kinematic chain (the machine's
  nominal description), so angular errors reach the TCP with their Abbe arms
  (Kidani eqs. 2.10-2.12). The correction is minus that error, added to the
  command: Kidani's command compensation p2 = p1 - delta e (Kidani eq. 3.16).
* **a real-time offset** (:class:`RealtimeOffset`) - the latest correction
  streamed by the compensation broadcaster, taken by the controller at its
  interpolation cycle. Each correction is computed for the command at its
  stamp; the controller applies it at the first cycle at or after
  ``stamp + delay`` (a fixed delay, so that applied offsets do not depend on
  network jitter), or at its arrival when it comes later than that. A
  correction that arrives later than ``max_age`` after its stamp is *stale*:
  counted and not applied, the last valid one stays.

Both are pure bookkeeping on numpy arrays (no ROS); refusals return a reason
that the caller counts and reports.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ParameterError
from ..kinematics.chain import ErrorOverrides, KinematicModel
from ..kinematics.machine import MachineDescription

#: Largest correction a controller takes [m]: more is a unit mistake or a broken model.
MAX_CORRECTION_M = 1e-3
#: Incomplete table versions a controller holds at most while their axes arrive.
MAX_STAGED_VERSIONS = 4
#: Largest table value by default: 10 mm, 10 mrad (the controller's parameter narrows it).
TABLE_MAX_VALUE = 1e-2
#: A rotary correction larger than this [rad] (0.5 deg) is refused as a unit mistake.
MAX_CORRECTION_RAD = float(np.radians(0.5))
#: Component letters of a table column, ISO 230-1: E<component><axis>.
TABLE_COMPONENTS = "XYZABC"


# --------------------------------------------------------------------- real-time offset
@dataclass
class OffsetStatistics:
    """What the real-time input did, for /diagnostics and reports."""

    offered: int = 0
    applied: int = 0          # accepted and applied (at most max_age after its stamp)
    stale: int = 0            # arrived later than max_age after its stamp: not applied
    refused: int = 0          # malformed: not finite, too large, stamp not increasing
    reasons: dict[str, int] = field(default_factory=dict)
    latencies_s: deque = field(default_factory=lambda: deque(maxlen=20000))
    #: Stamps [ns] of the first and the last stale correction (-1: none), and the oldest
    #: age one arrived with [s]: when the path missed its deadline, and by how much.
    first_stale_ns: int = -1
    last_stale_ns: int = -1
    worst_stale_age_s: float = 0.0

    def latency_percentiles(self) -> tuple[float, float, float]:
        """(p50, p99, max) of stamp -> applied latency [s]; NaN before the first."""
        if not self.latencies_s:
            return (float("nan"),) * 3
        values = np.asarray(self.latencies_s)
        return (float(np.percentile(values, 50)), float(np.percentile(values, 99)),
                float(values.max()))


class RealtimeOffset:
    """The controller's real-time compensation input: a fixed-delay, zero-order-hold buffer.

    Parameters
    ----------
    cycle_s : float
        Controller interpolation cycle [s] (> 0): offsets change only at its ticks.
    delay_s : float
        Fixed input delay [s] (>= 0): a correction stamped t applies from t + delay.
    max_age_s : float
        A correction arriving more than this after its stamp is stale [s] (> delay).
    rotary_axes : int
        Rotary axes of the machine: each correction also carries one angle [rad]
        per rotary axis (the tool-orientation part of a 5-axis compensation),
        held and applied together with its position part.
    max_correction_m : float, optional
        The controller's own limit on each position component [m]: a larger
        correction is refused.

    Raises
    ------
    ParameterError
        A value that is not finite or below its minimum, or ``max_age_s < delay_s``.
    """

    def __init__(self, cycle_s: float, delay_s: float, max_age_s: float,
                 rotary_axes: int = 0, max_correction_m: float = MAX_CORRECTION_M) -> None:
        for name, value, low in (("cycle_s", cycle_s, 1e-6), ("delay_s", delay_s, 0.0),
                                 ("max_age_s", max_age_s, 1e-6),
                                 ("max_correction_m", max_correction_m, 1e-9)):
            if not (np.isfinite(value) and value >= low):
                raise ParameterError(f"{name} = {value!r} s: must be finite and >= {low}")
        if max_age_s < delay_s:
            raise ParameterError(f"max_age_s ({max_age_s} s) must not be below delay_s "
                                 f"({delay_s} s): every correction would be stale")
        self.rotary_axes = int(rotary_axes)
        #: The controller's own limit [m]: a larger correction is refused, whatever the model.
        self.max_correction_m = float(max_correction_m)
        self.cycle_ns = int(round(cycle_s * 1e9))
        self.delay_ns = int(round(delay_s * 1e9))
        self.max_age_ns = int(round(max_age_s * 1e9))
        # Accepted corrections in stamp order: (applied_from_ns, stamp_ns, correction, version).
        self._applied_from: list[int] = []
        self._corrections: list[NDArray[np.float64]] = []
        self._versions: list[int] = []
        self._last_stamp = -1
        self.statistics = OffsetStatistics()

    def _ceil_cycle(self, t_ns: int) -> int:
        return -(-t_ns // self.cycle_ns) * self.cycle_ns

    def _refuse(self, reason: str, stale: bool = False) -> str:
        if stale:
            self.statistics.stale += 1
        else:
            self.statistics.refused += 1
        key = reason.split(":")[0]
        self.statistics.reasons[key] = self.statistics.reasons.get(key, 0) + 1
        return reason

    def offer(self, stamp_ns: int, arrival_ns: int, correction_m: ArrayLike,
              version: int, rotary_rad: ArrayLike = ()) -> str | None:
        """Take one correction (3,) [m] (and ``rotary_rad`` (R,) [rad]) stamped ``stamp_ns``.

        Returns ``None`` or the refusal reason.

        Parameters
        ----------
        stamp_ns : int
            Time the correction was computed for [ns].
        arrival_ns : int
            Time it reached the controller [ns].
        correction_m : array_like, shape (3,)
            Position correction [m], bed frame.
        version : int
            Model version that computed it; an older one than the last applied is refused.
        rotary_rad : array_like, shape (R,) or (0,), optional
            Rotary-axis corrections [rad], R = ``rotary_axes`` (empty: zeros).

        Returns
        -------
        str or None
            None when accepted, else the reason (not finite, too large, out of order,
            stale, old model); counted in :attr:`statistics`.
        """
        self.statistics.offered += 1
        correction = np.asarray(correction_m, dtype=np.float64).reshape(-1)
        rotary = np.asarray(rotary_rad, dtype=np.float64).reshape(-1)
        if correction.size != 3 or not np.all(np.isfinite(correction)):
            return self._refuse("not finite: correction with NaN/inf or not 3 components")
        if rotary.size not in (0, self.rotary_axes) or not np.all(np.isfinite(rotary)):
            return self._refuse(f"not finite: rotary correction with NaN/inf or not "
                                f"{self.rotary_axes} components")
        if np.max(np.abs(correction)) > self.max_correction_m:
            return self._refuse(f"too large: |correction| {np.max(np.abs(correction)):.3g} m "
                                f"> the controller's limit {self.max_correction_m:g} m (a unit "
                                "mistake or a broken model?)")
        if rotary.size and np.max(np.abs(rotary)) > MAX_CORRECTION_RAD:
            return self._refuse(f"too large: |rotary correction| {np.max(np.abs(rotary)):.3g} rad"
                                f" > {MAX_CORRECTION_RAD} rad (degrees sent as radians?)")
        correction = np.concatenate([correction, rotary if rotary.size
                                     else np.zeros(self.rotary_axes)])
        if stamp_ns <= self._last_stamp:
            return self._refuse(f"out of order: stamp {stamp_ns} ns not after the last "
                                f"accepted {self._last_stamp} ns")
        age = arrival_ns - stamp_ns
        if age > self.max_age_ns:
            stats = self.statistics
            stats.first_stale_ns = stamp_ns if stats.first_stale_ns < 0 else stats.first_stale_ns
            stats.last_stale_ns = stamp_ns
            stats.worst_stale_age_s = max(stats.worst_stale_age_s, age * 1e-9)
            return self._refuse(f"stale: arrived {age / 1e6:.1f} ms after its stamp, allowed "
                                f"{self.max_age_ns / 1e6:.1f} ms; the last valid one stays",
                                stale=True)
        if self._versions and version < self._versions[-1]:
            return self._refuse(f"old model: version {version} after version "
                                f"{self._versions[-1]} was applied")
        applied_from = self._ceil_cycle(max(stamp_ns + self.delay_ns, arrival_ns))
        self._last_stamp = stamp_ns
        self._applied_from.append(applied_from)
        self._corrections.append(correction)
        self._versions.append(int(version))
        self.statistics.applied += 1
        self.statistics.latencies_s.append((applied_from - stamp_ns) * 1e-9)
        return None

    def at(self, times_ns: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Applied correction (N, 3) [m] and its model version (N,) at controller times.

        The offset live at time t is the last accepted correction applied from
        a cycle tick at or before t (zero and version 0 before the first).

        Parameters
        ----------
        times_ns : array_like of int, shape (N,)
            Controller times [ns].

        Returns
        -------
        values : ndarray, shape (N, 3)
            Live position correction [m].
        versions : ndarray of int64, shape (N,)
            Its model version (0 before the first).
        """
        values, versions = self.at_with_rotary(times_ns)
        return values[:, :3], versions

    def at_with_rotary(self, times_ns: ArrayLike) -> tuple[NDArray[np.float64],
                                                          NDArray[np.int64]]:
        """As :meth:`at`, the values (N, 3 + R): position [m], then rotary [rad].

        Parameters
        ----------
        times_ns : array_like of int, shape (N,)
            Controller times [ns].

        Returns
        -------
        values : ndarray, shape (N, 3 + R)
            Live correction: position [m], then one angle per rotary axis [rad].
        versions : ndarray of int64, shape (N,)
            Its model version (0 before the first).
        """
        t = np.atleast_1d(np.asarray(times_ns, dtype=np.int64))
        tick = (t // self.cycle_ns) * self.cycle_ns
        out = np.zeros((t.size, 3 + self.rotary_axes))
        versions = np.zeros(t.size, dtype=np.int64)
        if not self._applied_from:
            return out, versions
        # applied_from is non-decreasing: stamps increase and the delay is fixed,
        # except that a late arrival can push one past its successor - take the max.
        starts = np.maximum.accumulate(np.asarray(self._applied_from, dtype=np.int64))
        index = np.searchsorted(starts, tick, side="right") - 1
        live = index >= 0
        out[live] = np.asarray(self._corrections)[index[live]]
        versions[live] = np.asarray(self._versions)[index[live]]
        return out, versions

    def forget_before(self, t_ns: int) -> None:
        """Drop corrections superseded before ``t_ns`` (keeps the one live then).

        Parameters
        ----------
        t_ns : int
            Controller time [ns].
        """
        if len(self._applied_from) < 2:
            return
        starts = np.maximum.accumulate(np.asarray(self._applied_from, dtype=np.int64))
        keep = max(0, int(np.searchsorted(starts, t_ns, side="right")) - 1)
        if keep:
            del self._applied_from[:keep], self._corrections[:keep], self._versions[:keep]


# --------------------------------------------------------------------- tables
@dataclass
class AxisTable:
    """One axis' compensation table: grid (M,) [m] and component columns (M,) each.

    Parameters
    ----------
    axis : str
        Linear axis letter.
    grid_m : ndarray, shape (M,)
        Strictly ascending positions [m].
    components : dict of str to ndarray, shape (M,)
        ISO name (e.g. ``"EYX"``) -> values [m] (translational) or [rad] (angular).
    version : int
        Model version the table belongs to.
    """

    axis: str
    grid_m: NDArray[np.float64]
    components: dict[str, NDArray[np.float64]]   # ISO name (e.g. "EYX") -> values [m or rad]
    version: int


class TableCompensation:
    """The controller's compensation tables, combined through its kinematic chain.

    Parameters
    ----------
    machine : MachineDescription
        The controller's nominal machine (axis order, strokes, chain offsets):
        what a CNC's volumetric-compensation package is configured with.
    max_correction_m : float, optional
        Largest translational table value taken [m] (angular values: 10 mrad).

    Attributes
    ----------
    version : int
        Model version of the live tables (0 before any).
    revision : int
        Counts every change of the live tables or squareness (a new version or a
        refinement of the live one): a correction computed at an unchanged revision
        is still the one :meth:`correction` would give.
    """

    def __init__(self, machine: MachineDescription,
                 max_correction_m: float = TABLE_MAX_VALUE) -> None:
        self.machine = machine
        #: Largest translational table value the controller takes [m] (angles: 10 mrad).
        self.max_correction_m = float(max_correction_m)
        self._kinematics = KinematicModel(machine)
        self.tables: dict[str, AxisTable] = {}
        self.squareness: dict[str, float] = {}
        self.version = 0
        self.revision = 0
        self.linear_axes = [a for a in machine.axis_order if not machine.axes[a].is_rotary]
        # Tables of a version not yet live, per version: (axis -> table, squareness).
        self._staged: dict[int, tuple[dict[str, AxisTable], dict[str, float]]] = {}
        self.refusals: dict[str, int] = {}

    def _refuse(self, reason: str) -> str:
        key = reason.split(":")[0]
        self.refusals[key] = self.refusals.get(key, 0) + 1
        return reason

    def offer(self, axis: str, columns: list[str], values: ArrayLike,
              squareness_names: list[str], squareness: ArrayLike, version: int) -> str | None:
        """Validate and take one axis' table; ``None`` or the refusal reason.

        A table is refused (and the axis keeps its last valid one) when its axis
        is not a linear axis of the machine, a column is not ``<AXIS>_m`` then
        ``E<c><AXIS>_<m|rad>``, a value is NaN/inf, the grid is not strictly
        ascending, leaves a gap (a step over 1.5 times the median step) or does
        not cover the stroke, or its model version is older than the live one.

        Parameters
        ----------
        axis : str
            Linear axis letter.
        columns : list of str
            Column names: ``<AXIS>_m`` then ``E<c><AXIS>_m`` or ``E<c><AXIS>_rad``.
        values : array_like, shape (M * len(columns),) or (M, len(columns))
            Row-major table: positions [m], then each column in its unit [m] / [rad].
        squareness_names : list of str
            Location error names: squareness (``EC0Y`` ...), rotary lines' tilts
            (``EA0C`` ...) and offsets (``EX0C`` ...).
        squareness : array_like, shape (len(squareness_names),)
            Their values, [rad] for an angle and [m] for an offset, each within 1e-2 (10
            mrad, 10 mm).
        version : int
            Model version; a new one goes live once every linear axis' table of it is in.

        Returns
        -------
        str or None
            None when taken (live or staged), else the reason; counted in :attr:`refusals`.
        """
        axis = str(axis).upper()
        spec = self.machine.axes.get(axis)
        if spec is None or spec.is_rotary:
            linear = (a for a in self.machine.axis_order if not self.machine.axes[a].is_rotary)
            return self._refuse(f"unknown axis: table for axis {axis!r}; the machine's linear "
                                f"axes are {', '.join(linear)}")
        if version < self.version:
            return self._refuse(f"old model: table of version {version} after version "
                                f"{self.version}")
        columns = [str(c) for c in columns]
        if not columns or columns[0] != f"{axis}_m":
            return self._refuse(f"bad columns: the first column of axis {axis}'s table must be "
                                f"'{axis}_m', got {columns[:1]}")
        parsed = {}
        for column in columns[1:]:
            name, _, unit = column.partition("_")
            if len(name) != 3 or name[0] != "E" or name[1] not in TABLE_COMPONENTS or \
                    name[2] != axis or unit != ("m" if name[1] in "XYZ" else "rad"):
                return self._refuse(f"bad columns: {column!r} is not E<XYZABC>{axis}_<m|rad>")
            parsed[name] = len(parsed) + 1
        data = np.asarray(values, dtype=np.float64).reshape(-1)
        if data.size == 0 or data.size % len(columns):
            return self._refuse(f"bad shape: {data.size} values do not fill {len(columns)} "
                                "columns")
        data = data.reshape(-1, len(columns))
        if data.shape[0] < 2 or not np.all(np.isfinite(data)):
            return self._refuse("gap: fewer than 2 rows or NaN/inf values in the table")
        grid = data[:, 0]
        steps = np.diff(grid)
        if np.any(steps <= 0):
            return self._refuse("gap: table positions are not strictly ascending")
        if steps.max() > 1.5 * np.median(steps):
            return self._refuse(f"gap: a step of {steps.max() * 1e3:.1f} mm in a table of "
                                f"{np.median(steps) * 1e3:.1f} mm steps")
        low, high = spec.stroke
        if grid[0] > low + 1e-3 or grid[-1] < high - 1e-3:
            return self._refuse(f"gap: the table covers {grid[0]:.3f}..{grid[-1]:.3f} m, the "
                                f"stroke {low:.3f}..{high:.3f} m")
        limits = np.array([TABLE_MAX_VALUE if str(c).endswith("_rad") else
                           self.max_correction_m for c in columns[1:]])
        if np.any(np.abs(data[:, 1:]) > limits):
            return self._refuse(f"too large: a table value beyond the controller's limit "
                                f"({self.max_correction_m:g} m, {TABLE_MAX_VALUE:g} rad; a "
                                "unit mistake?)")
        names = [str(n) for n in squareness_names]
        square = np.asarray(squareness, dtype=np.float64).reshape(-1)
        if square.size != len(names) or not np.all(np.isfinite(square)) or \
                np.any(np.abs(square) > 1e-2):
            return self._refuse("bad squareness: names and values differ in number, are "
                                "not finite or beyond 10 mrad (an angle) or 10 mm (an offset)")
        table = AxisTable(axis, grid.copy(),
                          {name: data[:, col].copy() for name, col in parsed.items()},
                          int(version))
        squareness = dict(zip(names, (float(v) for v in square)))
        version = int(version)
        if version == self.version:
            # A refinement of the live version (a new measured profile): per axis, at once.
            self.tables[axis] = table
            self.squareness = squareness
            self.revision += 1
            return None
        # A new version goes live as a whole: once every linear axis' table of it is in.
        # Switched axis by axis, the CNC would apply X's new table with Y's old one (or
        # none) for as long as the other messages take - under load, long enough for a
        # test's readings to see an uncompensated Y.
        staged = self._staged.setdefault(version, ({}, {}))
        # Versions that never complete (a peer sending one axis with ever newer versions)
        # must not pile up: the newest few are kept.
        for old in sorted(self._staged)[:-MAX_STAGED_VERSIONS]:
            del self._staged[old]
        staged[0][axis] = table
        staged[1].update(squareness)
        if set(staged[0]) >= set(self.linear_axes):
            self.tables.update(staged[0])
            self.squareness = dict(staged[1])
            self.version = version
            self.revision += 1
            self._staged = {v: t for v, t in self._staged.items() if v > version}
        return None

    def error(self, positions: dict[str, ArrayLike]) -> NDArray[np.float64]:
        """TCP error (N, 3) [m] the tables describe at command positions (axis -> (N,)).

        Parameters
        ----------
        positions : dict of str to array_like, shape (N,)
            Axis commands [m] (rotary [rad]), every axis of the machine.

        Returns
        -------
        ndarray, shape (N, 3)
            TCP position error [m], bed frame (end values held beyond a table).
        """
        q = {a: np.atleast_1d(np.asarray(positions[a], dtype=np.float64))
             for a in self.machine.axis_order}
        overrides = ErrorOverrides(use_description=False)
        for axis, table in self.tables.items():
            for name, column in table.components.items():
                # Outside the table the end values hold, as CNC tables do.
                overrides.motion[name] = np.interp(q[axis], table.grid_m, column)
        for name, value in self.squareness.items():
            overrides.location[name] = value
        return self._kinematics.tcp_error(q, overrides=overrides, check_stroke=False)["position"]

    def correction(self, positions: dict[str, ArrayLike]) -> NDArray[np.float64]:
        """Value to add to the command (N, 3) [m]: minus the tables' TCP error (Kidani eq. 3.16).

        Parameters
        ----------
        positions : dict of str to array_like, shape (N,)
            Axis commands [m] (rotary [rad]), every axis of the machine.

        Returns
        -------
        ndarray, shape (N, 3)
            Correction [m], bed frame (zero before any table).
        """
        if not self.tables and not self.squareness:
            n = np.atleast_1d(np.asarray(next(iter(positions.values())))).size
            return np.zeros((n, 3))
        return -self.error(positions)
