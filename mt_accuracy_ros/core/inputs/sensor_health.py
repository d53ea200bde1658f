"""Every temperature sensor judged before it is used: one rule for logs, surveys, bags, nodes.

A thermocouple breaks, a channel freezes, a logger writes a sentinel for "no
value", a sensor is re-seated mid-log. Fed to a model such a reading decides
it: a dead thermocouple at -180 degC becomes the "best" sensor, a constant one
makes its candidates vanish without a word. Here each sensor's readings
(degC, one per row) are judged; each problem found is a :class:`SensorFinding`
naming the sensor, its kind, its rows and what was done:

========== ================================================================ ==================
kind       what it is                                                       what is done
========== ================================================================ ==================
dead       a physically absent value: outside :data:`PHYSICAL_RANGE_C`      its rows, or the
           (an open thermocouple's -180, -273, 850) or exactly 0 over       sensor (below)
           :data:`MIN_ZERO_ROWS` rows or more (a logger's empty cell)
out_of     outside the workshop's :func:`workshop_range_c` (the plausibility   its rows, or the
_range     table's; possible in physics, not on a machine tool)             sensor
stuck      constant (exactly or within its quantisation) over               its rows, or the
           :data:`STUCK_MIN_SHARE` of the rows or more while the other      sensor
           sensors move (or, alone, over every row)
dropout    no reading (NaN): a gap in the logger's record                   its rows, or the
                                                                            sensor
jumping    a step :data:`JUMP_SIGMAS` times its own noise and at least      the sensor (which
           :data:`JUMP_MIN_K` that persists and no other sensor shares      side is right
                                                                            cannot be told)
========== ================================================================ ==================

A jump is a step between two readings, far beyond every other change near it: a spindle's
warm-up also rises by many noises, but over several readings (seen in an independent survey:
+2.2 K in one row of a 0.03 K sensor, then +1.6 K, +1.2 K, ...), and it is the signal.

"Its rows, or the sensor": a sensor whose bad rows are more than :data:`LEAVE_OUT_SHARE`
of the rows (or :data:`LEAVE_OUT_RUN_SHARE` of one run) is left out of every model and its
rows kept; fewer bad rows are left out themselves (the other sensors' readings on them
go too: a model needs every sensor on a row). Nothing is dropped or kept silently: each
finding's ``text`` says which.

Pure numpy, no ROS: :func:`judge_sensors` is the one implementation of the rule.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .plausibility import BOUNDS, temperature_quantity

#: Readings outside this [degC] are not a temperature of anything on a machine tool: a
#: sensor's "no value" (open thermocouple, -273, a logger's overflow).
PHYSICAL_RANGE_C = (-50.0, 200.0)

#: A machine tool's structure in a workshop [degC] (the plausibility table's: a spindle's,
#: a motor's sensor - by its name - up to its hot bound); outside it a reading is possible
#: in physics but not there (a sensor off its part, a wrong channel).
WORKSHOP_RANGE_C = (BOUNDS["temperature"].low, BOUNDS["temperature"].high)


def workshop_range_c(sensor: str) -> tuple[float, float]:
    """The plausible readings [degC] of ``sensor``: hot ones (spindle, motor ... by name)
    up to the plausibility table's hot bound.

    Parameters
    ----------
    sensor : str
        The sensor's name.

    Returns
    -------
    tuple of float
        (low, high) [degC].
    """
    bound = BOUNDS[temperature_quantity(sensor)]
    return bound.low, bound.high

#: Exactly 0 on this many rows in a row is a logger's empty cell, not 0 degC.
MIN_ZERO_ROWS = 3

#: A constant stretch over this share of the rows (at least :data:`STUCK_MIN_ROWS`) is a
#: stuck sensor when the others move.
STUCK_MIN_SHARE = 0.1
STUCK_MIN_ROWS = 20

#: "The others move" over a stretch: one of them spans this much [K] there, at least (a
#: quiet night holds every sensor within a quantum; a warm-up moves one by far more).
OTHERS_MOVE_K = 0.5

#: A step of this many times the sensor's own noise (and at least :data:`JUMP_MIN_K`)
#: that lasts :data:`JUMP_WINDOW` rows and no other sensor shares is a jump.
JUMP_SIGMAS = 30.0
JUMP_MIN_K = 1.0
JUMP_WINDOW = 20
#: A jump happens between two readings: its one-row change is this many times every other
#: one-row change within :data:`JUMP_WINDOW` rows. A warm-up also rises far beyond the
#: noise, but over several readings, each change near the last.
JUMP_ISOLATION = 4.0

#: More bad rows than this share of the rows (or of one run) leave the sensor out.
LEAVE_OUT_SHARE = 0.2
LEAVE_OUT_RUN_SHARE = 0.5

#: Row ranges a finding's text names, at most.
SHOWN_RANGES = 3


@dataclasses.dataclass(frozen=True)
class SensorFinding:
    """One problem of one sensor.

    Attributes
    ----------
    sensor : str
        The sensor (column) name.
    kind : str
        "dead", "out_of_range", "stuck", "dropout", "jumping", or "heated" (a note: readings
        above a workshop's range taken as a heated part's and kept, no rows).
    rows : tuple of int
        Its bad rows' numbers (the caller's ``data_rows``: 1-based rows of the file's data).
    text : str
        One line for the user: the sensor, the kind, the rows, what was done.
    left_out : bool
        The sensor is left out of every model (else only ``rows`` are left out).
    """

    sensor: str
    kind: str
    rows: tuple[int, ...]
    text: str
    left_out: bool


@dataclasses.dataclass
class SensorHealth:
    """The sensors judged: those kept (their bad rows NaN), and every finding.

    Attributes
    ----------
    kept : dict of str to ndarray, shape (N,)
        The sensors used [degC], bad rows NaN.
    findings : list of SensorFinding
        One per problem, in sensor order.
    """

    kept: dict[str, NDArray[np.float64]]
    findings: list[SensorFinding]

    @property
    def notes(self) -> list[str]:
        """Each finding's one line."""
        return [f.text for f in self.findings]

    @property
    def rows_left_out(self) -> NDArray[np.bool_]:
        """(N,) rows on which a kept sensor has no usable reading (a few bad rows set
        aside, or its own gaps): a model needs every sensor on a row, so the caller leaves
        these rows out. Empty (shape (0,)) when no sensor is kept."""
        values = list(self.kept.values())
        if not values:
            return np.zeros(0, dtype=bool)
        return ~np.all([np.isfinite(v) for v in values], axis=0)

    @property
    def left_out(self) -> list[str]:
        """The sensors left out of every model, in the order found."""
        return list(dict.fromkeys(f.sensor for f in self.findings if f.left_out))


def noise_from_differences(values: ArrayLike) -> float:
    """The white-noise sigma of a smooth signal from its successive differences (von
    Neumann): the median absolute difference / (0.6745 sqrt 2), robust to steps. Same
    unit as ``values``.

    Parameters
    ----------
    values : array_like, shape (N,)
        The signal, any unit (non-finite differences are left out).

    Returns
    -------
    float
        Sigma in the values' unit; 0 for fewer than 3 usable values.
    """
    steps = np.diff(np.asarray(values, dtype=np.float64))
    steps = steps[np.isfinite(steps)]
    if steps.size < 2:
        return 0.0
    return float(np.median(np.abs(steps - np.median(steps))) / 0.6745 / np.sqrt(2.0))


def row_ranges(rows: ArrayLike, shown: int = SHOWN_RANGES) -> str:
    """Row numbers (sorted) as "5, 9-40, 77 and 2 more ranges".

    Parameters
    ----------
    rows : array_like of int, shape (R,)
        Row numbers, sorted.
    shown : int, optional
        Ranges named at most.

    Returns
    -------
    str
        The ranges, or "no row".
    """
    rows = np.asarray(rows, dtype=np.int64)
    if rows.size == 0:
        return "no row"
    cuts = np.flatnonzero(np.diff(rows) != 1) + 1
    parts = [f"{int(p[0])}" if p.size == 1 else f"{int(p[0])}-{int(p[-1])}"
             for p in np.split(rows, cuts)]
    more = len(parts) - shown
    return ", ".join(parts[:shown]) + (f" and {more} more range{'s' if more > 1 else ''}"
                                       if more > 0 else "")


def true_stretches(mask: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """Each run of True in ``mask``.

    Parameters
    ----------
    mask : ndarray of bool, shape (N,)
        Any flags.

    Returns
    -------
    list of (int, int)
        ``[(start, stop))`` of each run of True, in order.
    """
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def dead_rows(values: NDArray[np.float64]) -> NDArray[np.bool_]:
    """(N,) rows reading a physically absent value: outside :data:`PHYSICAL_RANGE_C`, or
    exactly 0 over :data:`MIN_ZERO_ROWS` rows in a row.

    Parameters
    ----------
    values : ndarray, shape (N,)
        The sensor's readings [degC] (NaN for no reading).

    Returns
    -------
    ndarray of bool, shape (N,)
        The dead rows.
    """
    low, high = PHYSICAL_RANGE_C
    finite = np.isfinite(values)
    dead = finite & ((values < low) | (values > high))
    zero = finite & (values == 0.0)
    for a, b in true_stretches(zero):
        if b - a >= MIN_ZERO_ROWS:
            dead[a:b] = True
    return dead


def out_of_range_rows(values: NDArray[np.float64],
                      workshop_c: tuple[float, float] = WORKSHOP_RANGE_C) -> NDArray[np.bool_]:
    """(N,) finite rows outside ``workshop_c`` [degC] (dead ones not counted).

    Parameters
    ----------
    values : ndarray, shape (N,)
        The sensor's readings [degC] (NaN for no reading).
    workshop_c : tuple of float, optional
        (low, high) plausible readings [degC] (default :data:`WORKSHOP_RANGE_C`).

    Returns
    -------
    ndarray of bool, shape (N,)
        The rows out of range.
    """
    low, high = workshop_c
    return np.isfinite(values) & ((values < low) | (values > high)) & ~dead_rows(values)


def _quantum(values: NDArray[np.float64]) -> float:
    """The sensor's resolution [K]: its smallest non-zero step (0 when it never moves)."""
    steps = np.abs(np.diff(values[np.isfinite(values)]))
    steps = steps[steps > 0]
    return float(steps.min()) if steps.size else 0.0


def _flat_stretches(values: NDArray[np.float64], tolerance: float) -> list[tuple[int, int]]:
    """[(start, stop)) of the longest stretches, taken greedily from the first row, whose
    finite readings span ``tolerance`` or less (a NaN ends a stretch)."""
    out, start, low, high = [], 0, np.inf, -np.inf
    for i, value in enumerate(values.tolist()):
        if value != value:                         # NaN
            out.append((start, i))
            start, low, high = i + 1, np.inf, -np.inf
            continue
        low, high = min(low, value), max(high, value)
        if high - low > tolerance:
            out.append((start, i))
            start, low, high = i, value, value
    out.append((start, len(values)))
    return [(a, b) for a, b in out if b - a >= 2]


def stuck_rows(values: NDArray[np.float64], others: list[NDArray[np.float64]]
               ) -> NDArray[np.bool_]:
    """(N,) rows of a stretch where the sensor holds still (within one quantum) over
    :data:`STUCK_MIN_SHARE` of the rows or more while another sensor spans
    :data:`OTHERS_MOVE_K` or more; with no other sensor, only a sensor constant on every
    finite row.

    Parameters
    ----------
    values : ndarray, shape (N,)
        The sensor's readings [degC] (NaN for no reading).
    others : list of ndarray, shape (N,)
        The other sensors' readings [degC].

    Returns
    -------
    ndarray of bool, shape (N,)
        The stuck rows.
    """
    n = values.size
    stuck = np.zeros(n, dtype=bool)
    finite = np.isfinite(values)
    if finite.sum() < 2:
        return stuck
    if not others:
        if np.ptp(values[finite]) == 0.0:
            stuck[finite] = True
        return stuck
    quantum = _quantum(values)
    # Resolutions coarser than a tenth of a kelvin are a logger's, not a frozen channel's.
    tolerance = quantum * (1 + 1e-9) if 0 < quantum <= 0.1 else 0.0
    least = max(STUCK_MIN_ROWS, int(np.ceil(STUCK_MIN_SHARE * n)))
    for start, stop in _flat_stretches(values, tolerance):
        if stop - start < least:
            continue
        moving = [np.ptp(o[start:stop][np.isfinite(o[start:stop])]) for o in others
                  if np.isfinite(o[start:stop]).sum() >= 2]
        if moving and max(moving) >= OTHERS_MOVE_K:
            stuck[start:stop] = True
    return stuck


def _step_at(values: NDArray[np.float64], k: int, window: int) -> float:
    """The level after row k-1 minus the level before it (medians of ``window`` rows)."""
    before = values[max(0, k - window):k]
    after = values[k:k + window]
    before, after = before[np.isfinite(before)], after[np.isfinite(after)]
    if before.size < 2 or after.size < 2:
        return 0.0
    return float(np.median(after) - np.median(before))


def _isolated(steps: NDArray[np.float64], j: int, window: int) -> bool:
    """Is the one-row change ``steps[j]`` :data:`JUMP_ISOLATION` times every other change
    within ``window`` rows (a step between two readings, not a fast rise)?"""
    near = np.concatenate([steps[max(0, j - window):j], steps[j + 1:j + 1 + window]])
    near = near[np.isfinite(near)]
    return near.size == 0 or steps[j] >= JUMP_ISOLATION * float(near.max())


def jump_rows(values: NDArray[np.float64], others: list[NDArray[np.float64]],
              breaks: NDArray[np.bool_] | None = None) -> list[int]:
    """Rows (indices) where the sensor steps by :data:`JUMP_SIGMAS` times its noise and
    :data:`JUMP_MIN_K` or more between two readings (:data:`JUMP_ISOLATION`), the step
    lasting :data:`JUMP_WINDOW` rows, while no other
    sensor steps by more than its own :data:`JUMP_SIGMAS` noises there. ``breaks`` (N,):
    rows that start a new run or follow a clock jump (a step there is the break's).

    Parameters
    ----------
    values : ndarray, shape (N,)
        The sensor's readings [degC] (NaN for no reading).
    others : list of ndarray, shape (N,)
        The other sensors' readings [degC].
    breaks : ndarray of bool, shape (N,), optional
        Rows that start a run or follow a clock jump.

    Returns
    -------
    list of int
        Row indices (0-based) of the jumps: the first row after each step.
    """
    # A quantised sensor's noise reads 0 off its differences: one quantum is its floor.
    noise = max(noise_from_differences(values), _quantum(values))
    threshold = max(JUMP_SIGMAS * noise, JUMP_MIN_K)
    steps = np.abs(np.diff(values))
    candidates = np.flatnonzero(np.nan_to_num(steps, nan=0.0) >= 0.5 * threshold) + 1
    found = []
    for k in candidates:
        if breaks is not None and breaks[k]:
            continue
        if abs(_step_at(values, int(k), JUMP_WINDOW)) < threshold:
            continue
        if not _isolated(steps, int(k) - 1, JUMP_WINDOW):
            continue
        shared = any(abs(_step_at(o, int(k), JUMP_WINDOW)) >=
                     max(JUMP_SIGMAS * noise_from_differences(o), JUMP_MIN_K) for o in others)
        if not shared and (not found or k - found[-1] > JUMP_WINDOW):
            found.append(int(k))
    return found


def _too_many(bad: NDArray[np.bool_], run_of_row: NDArray[np.intp] | None,
              run_names: list[str] | None) -> tuple[bool, list[str]]:
    """(leave the sensor out, the runs mostly bad) by :data:`LEAVE_OUT_SHARE` and
    :data:`LEAVE_OUT_RUN_SHARE`."""
    runs: list[str] = []
    if run_of_row is not None and bad.size:
        count = int(run_of_row.max()) + 1
        share = np.bincount(run_of_row, weights=bad, minlength=count) / \
            np.maximum(np.bincount(run_of_row, minlength=count), 1)
        names = run_names or [str(k) for k in range(count)]
        runs = [names[k] for k in np.flatnonzero(share > LEAVE_OUT_RUN_SHARE)]
    return bool(bad.mean() > LEAVE_OUT_SHARE) or bool(runs), runs


def _describe(kind: str, values: NDArray[np.float64], bad: NDArray[np.bool_],
              others: bool = True, workshop_c: tuple[float, float] = WORKSHOP_RANGE_C) -> str:
    """What the bad rows read, in words."""
    seen = values[bad & np.isfinite(values)]
    if kind == "dropout":
        return "no reading"
    if kind == "stuck":
        return f"stuck at {seen[0]:.6g} degC{' while the others move' if others else ''}"
    span = f"{seen.min():.4g}" if np.ptp(seen) < 0.05 * max(abs(seen.min()), 1.0) else \
        f"{seen.min():.4g} ... {seen.max():.4g}"
    if kind == "dead":
        return f"reads {span} degC, a physically absent value (dead)"
    low, high = workshop_c
    return f"reads {span} degC, outside a workshop's {low:g} ... {high:g} degC"


def judge_sensors(temperatures: dict[str, ArrayLike], data_rows: ArrayLike | None = None,
                  run_of_row: ArrayLike | None = None, run_names: list[str] | None = None,
                  breaks: ArrayLike | None = None, *, row_label: str = "data row"
                  ) -> SensorHealth:
    """Judge each sensor (module docstring): the sensors kept and every finding.

    Parameters
    ----------
    temperatures : dict of str to array, shape (N,)
        Each sensor's readings [degC]; NaN where it gave none.
    data_rows : array of int, shape (N,), optional
        Each row's number for the texts (default 1..N).
    run_of_row, run_names : optional
        The run of each row and the runs' names: a sensor mostly bad in one run is left
        out, and a step at a run's start is not a jump.
    breaks : array of bool, shape (N,), optional
        Rows after a break of the record (a clock jump): a step there is not a jump.
    row_label : str
        What ``data_rows`` number, in the texts ("data row" for a log's rows after its
        header, "file row" for a survey's rows counted with the header as row 1,
        "reading" for a bag's reference readings).

    Returns
    -------
    SensorHealth
        ``kept``: the sensors used, each a float copy with its bad rows NaN (the caller
        leaves those rows out); ``findings``: one per problem, in sensor order.
    """
    series = {name: np.asarray(v, dtype=np.float64).copy() for name, v in temperatures.items()}
    n = next(iter(series.values())).size if series else 0
    rows = np.arange(1, n + 1) if data_rows is None else np.asarray(data_rows)
    runs = None if run_of_row is None else np.asarray(run_of_row, dtype=np.intp)
    cut = np.zeros(n, dtype=bool) if breaks is None else np.asarray(breaks, dtype=bool).copy()
    if runs is not None and n:
        cut[1:] |= np.diff(runs) != 0
    kept, findings = {}, []
    for name, values in series.items():
        # A sensor is judged against the others' sane readings only.
        others = [np.where(dead_rows(o) | out_of_range_rows(o, workshop_range_c(other)),
                           np.nan, o)
                  for other, o in series.items() if other != name]
        sensor_findings = _judge_one(name, values, others, rows, runs, run_names, cut,
                                     row_label)
        findings += sensor_findings
        if any(f.left_out for f in sensor_findings):
            continue
        for finding in sensor_findings:
            values[np.isin(rows, finding.rows)] = np.nan
        kept[name] = values
    return SensorHealth(kept, findings)


#: A heated part's coolest readings lie this close to the other sensors' coolest [K]: it
#: starts where the machine does, so its unit is theirs.
HEATED_START_K = 5.0


def coolest_reading(values: NDArray[np.float64]) -> float:
    """The lowest reading that is not a dead sensor's (a heater's first reading, before it
    rises: even its second may lie kelvins above).

    Parameters
    ----------
    values : ndarray, shape (N,)
        One sensor's readings [degC].

    Returns
    -------
    float
        The lowest live reading [degC]; NaN when none is live.
    """
    alive = values[np.isfinite(values) & ~dead_rows(values)]
    return float(alive.min()) if alive.size else float("nan")


def heated_part(values: NDArray[np.float64], outside: NDArray[np.bool_],
                others: list[NDArray[np.float64]],
                workshop_c: tuple[float, float]) -> str:
    """Why a sensor whose readings rise above a workshop's range is a heated part (a
    heater, a bed, a hot end) in degC, or "" when it is not.

    A unit slip (degF declared degC) moves every reading, its coolest too; a heated part
    starts where the machine does. So readings above the range are a heated part's when
    none lies below it or beyond physics, each stretch above it is entered and left
    gradually, and the sensor's coolest reading lies within :data:`HEATED_START_K` of the
    other sensors' coolest.

    Parameters
    ----------
    values : ndarray, shape (N,)
        The sensor's readings [degC as declared].
    outside : ndarray of bool, shape (N,)
        Its rows outside ``workshop_c``.
    others : list of ndarray, shape (N,)
        The other sensors' sane readings [degC].
    workshop_c : tuple of float
        The sensor's workshop range [degC].

    Returns
    -------
    str
        The note's words, or "".
    """
    finite = values[np.isfinite(values)]
    if not outside.any() or not others or finite.size < 2:
        return ""
    seen = values[outside]
    if np.any(seen <= workshop_c[1]) or np.any(seen > PHYSICAL_RANGE_C[1]):
        return ""
    coolest = coolest_reading(values)
    rise = float(np.nanmax(values)) - coolest
    # Heating moves: each stretch above the range lasts, varies, and is entered and left
    # by steps far smaller than the whole rise (a glitch, a wrong channel: one step).
    for start, stop in true_stretches(outside):
        entry = abs(values[start] - values[start - 1]) if start > 0 else 0.0
        exit_ = abs(values[stop] - values[stop - 1]) if stop < values.size else 0.0
        if stop - start < 3 or np.ptp(values[start:stop]) == 0.0 or \
                max(entry, exit_) > 0.5 * rise:
            return ""
    starts = [coolest_reading(o) for o in others if np.isfinite(o).sum() >= 3]
    if not starts or abs(coolest - float(np.median(starts))) > HEATED_START_K:
        return ""
    return (f"reads up to {seen.max():.4g} degC, above a structure's {workshop_c[1]:g} degC, "
            f"from {coolest:.4g} degC at its coolest as the other sensors "
            f"({np.median(starts):.4g} degC): taken as a heated part (a heater, a bed, a "
            "spindle) and kept - give its unit if it is not degC")


def _judge_one(name: str, values: NDArray[np.float64], others: list[NDArray[np.float64]],
               rows: NDArray, runs: NDArray[np.intp] | None, run_names: list[str] | None,
               breaks: NDArray[np.bool_], row_label: str = "data row"
               ) -> list[SensorFinding]:
    """The findings of one sensor (see :func:`judge_sensors`)."""
    workshop_c = workshop_range_c(name)
    dead = dead_rows(values)
    outside = out_of_range_rows(values, workshop_c)
    heated = heated_part(values, outside, others, workshop_c)
    if heated:
        outside = np.zeros_like(outside)
    missing = ~np.isfinite(values)
    sane = np.where(dead | outside, np.nan, values)
    stuck = stuck_rows(sane, others) & ~missing
    bad_kinds = [("dead", dead), ("out_of_range", outside), ("stuck", stuck),
                 ("dropout", missing)]
    bad = dead | outside | stuck | missing
    leave_out, mostly_bad_runs = _too_many(bad, runs, run_names)
    jumps = [] if leave_out else jump_rows(np.where(stuck, np.nan, sane), others, breaks)
    leave_out = leave_out or bool(jumps)
    where = (f" (run{'s' if len(mostly_bad_runs) > 1 else ''} {', '.join(mostly_bad_runs)})"
             if mostly_bad_runs else "")
    unit_s = f"{row_label.split()[-1]}s"            # "rows" of a file, "readings" of a bag
    action = f"left out of every model (its {unit_s} kept)" if leave_out else \
        f"those {unit_s} left out"
    findings = [SensorFinding(name, "heated", (), f"sensor {name}: {heated}", False)] \
        if heated else []
    for kind, mask in bad_kinds:
        if not mask.any():
            continue
        count = int(mask.sum())
        # The runs a finding names are those its own rows lie in.
        if runs is not None and mostly_bad_runs:
            own = {(run_names or [str(k) for k in range(int(runs.max()) + 1)])[k]
                   for k in np.unique(runs[mask])}
            kind_runs = [r for r in mostly_bad_runs if r in own]
            where = (f" (run{'s' if len(kind_runs) > 1 else ''} {', '.join(kind_runs)})"
                     if kind_runs else "")
        if kind == "dropout" and leave_out and count == int(bad.sum()):
            # The wording a dead thermocouple's gaps have always had.
            text = (f"sensor {name}: no reading in {count} of {values.size} {unit_s}{where} - "
                    f"dead, {action}")
        else:
            text = (f"sensor {name}: {_describe(kind, values, mask, bool(others), workshop_c)} "
                    f"at {row_label}s {row_ranges(rows[mask])} ({count} of {values.size} "
                    f"{unit_s}){where} - "
                    f"{action}")
        findings.append(SensorFinding(name, kind, tuple(int(r) for r in rows[mask]), text,
                                      leave_out))
    for k in jumps:
        step = _step_at(np.where(stuck, np.nan, sane), k, JUMP_WINDOW)
        findings.append(SensorFinding(
            name, "jumping", tuple(int(r) for r in rows[k:]),
            f"sensor {name}: jumps by {step:+.3g} K at {row_label} {int(rows[k])} (its noise "
            f"{noise_from_differences(sane):.2g} K; no other sensor steps there) - left out "
            "of every model (which side is right cannot be told)", True))
    return findings


def refuse_wrong_temperature_unit(name: str, values: ArrayLike, declared: str, where: str,
                                  mend: str, error: type[Exception],
                                  others_coolest_c: float | None = None) -> None:
    """Refuse a sensor whose readings, in their ``declared`` unit, lie mostly where no
    machine's temperature does and another unit would put them (kelvin declared as degC).

    The one line between a unit problem and a sensor problem, for logs and surveys alike:
    the *share* of the rows decides. When the median reading is a plausible temperature
    the column is in its unit and a dead stretch (an open thermocouple's -180, a logger's
    0) is a sensor problem for :func:`judge_sensors`, row by row. When most readings are
    implausible and the middle 90 % of them fit another unit, it is a unit problem,
    refused. Readings beyond any unit (a dead sensor's -180 on every row) fit none: the
    judge's too.

    Parameters
    ----------
    name : str
        The sensor's name (a spindle's or a motor's is allowed hotter: by name).
    values : array
        Its readings in ``declared`` (NaN where it gave none).
    declared : str
        Their unit (a key of the temperature unit table).
    where, mend : str
        What the values are and how to give another unit, for the message; ``{guess}``
        in ``mend`` becomes the likely unit.
    error : type
        The exception raised (the caller's: ParameterError, InputDataError).
    others_coolest_c : float, optional
        The other sensors' coolest reading [degC]: a sensor whose coolest reading lies
        within :data:`HEATED_START_K` of it is in their unit however hot it runs (a heater
        held at 100 degC), and is left to :func:`judge_sensors` (:func:`heated_part`).

    Raises
    ------
    error
        One line naming the values, the declared unit and the likely one.
    """
    from .plausibility import check_plausible, likely_unit, to_si

    raw = np.asarray(values, dtype=np.float64)
    finite = raw[np.isfinite(raw)]
    if finite.size == 0:
        return
    quantity = temperature_quantity(name)
    middle = float(np.median(to_si(finite, "temperature", declared)))
    if BOUNDS[quantity].low <= middle <= BOUNDS[quantity].high:
        return
    coolest = coolest_reading(to_si(raw, "temperature", declared))
    if others_coolest_c is not None and abs(coolest - others_coolest_c) <= HEATED_START_K:
        return
    low, high = np.percentile(finite, [5, 95])
    core = finite[(finite >= low) & (finite <= high)]
    guess = likely_unit(core, quantity, declared)
    if guess is not None:
        # The whole column is shown when its every reading fits the likely unit.
        shown = finite if likely_unit(finite, quantity, declared) == guess else core
        check_plausible(shown, quantity, declared, where, mend=mend.format(guess=guess),
                        error=error)
