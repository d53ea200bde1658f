"""`mt-accuracy check LOG.csv --target COLUMN`: a thermal log, one run or many.

The log's later rows (after ``--train-fraction``; with runs, after the run
boundary nearest it) are **never seen** by any decision: they judge every model
version, the constant and least squares on every sensor, on the same rows.
Every decision is made inside the training rows:

1. the selection ranks candidates by forward validation (each block predicted
   by a fit on the blocks before it; with runs, blocks are whole runs);
2. a candidate that passes the selection's tests must then predict the last
   block of the training rows (the last training runs) from a fit on the
   blocks before it better than the model without it - the held-out judge,
   played inside the training rows. A candidate refused there is reported
   with both numbers, and the next one that passes the tests is judged the
   same way;
3. every candidate with a large CV gain that is not added is reported with
   the test that refused it and its numbers.

Before any of it the log is judged, and nothing is silent: the options
(:func:`validate_log_options`), the target's unit and that it moves
(:func:`check_target`), each sensor's unit (:func:`check_temperature_units`),
the ``--inputs`` patterns (only temperatures: :func:`select_temperature_inputs`),
the clock (:func:`clock_of_log`: equal stamps, jumps as breaks between runs) and
every sensor's health (:mod:`~..core.inputs.sensor_health`: dead, out of range,
stuck, dropping out, jumping - named with their rows and left out). A refusal is
one line; a decision taken is a note.
"""
from __future__ import annotations

import dataclasses
import fnmatch
import re
from pathlib import Path

import numpy as np

from ..core.errors import InputDataError, ParameterError
from .check_result import (CheckResult, ContestEntry, DataSource, ModelStep, NotAdded,
                           RunFigures, ThermalLog)

#: A candidate whose forward-CV error reduction is at least this is "a large gain":
#: when it is not added, the output says which test refused it.
LARGE_GAIN = 0.2

#: Candidates judged on the last training block per step, at most.
MAX_JUDGED = 6

#: Forward-validation blocks over the training rows (whole runs when there are runs).
MAX_BLOCKS = 6

#: Words of a column name that suggest it holds the time (for the error's hint).
TIME_WORDS = ("time", "date", "stamp", "zeit", "datum", "heure")


def _validation_split(training, blocks):
    """(fit rows, validation rows, what the validation rows are) of the training rows: the
    last forward block (whole runs), or the last sixth of the rows without runs."""
    if blocks is not None:
        last = blocks == blocks[-1]
    else:
        last = np.arange(training.n) >= training.n - max(4, training.n // MAX_BLOCKS)
    return ~last, last


def joint_design(terms, frame, component: int, zeroed: bool):
    """(design (N, P), ridge penalties [(start, stop, strength)], each term's column span)
    of ``terms`` [(family, variant, setting)] on ``component`` of ``frame`` - with an
    offset column first unless the runs were zeroed (their zero is known)."""
    n = frame.residual.shape[0]
    columns = [] if zeroed else [np.ones((n, 1))]
    penalties, spans, start = [], [], 0 if zeroed else 1
    for family, variant, setting in terms:
        design = frame.ctx.measured_design(family, variant, setting)[:, component, :]
        key = getattr(family, "penalty_setting", None)
        if key:
            penalties.append((start, start + design.shape[1], float(setting.get(key, 0.0))))
        columns.append(design)
        spans.append((start, start + design.shape[1]))
        start += design.shape[1]
    return (np.column_stack(columns) if columns else np.zeros((n, 0))), penalties, spans


def validation_rmse(terms, frame, component: int, fit, judge, zeroed: bool) -> float:
    """RMS error on ``judge`` rows of ``terms`` [(family, variant, setting)] fitted jointly
    (with an offset unless the runs were zeroed) on ``fit`` rows to the residual of
    ``frame`` (:class:`~..core.workbench.diagnosis.ResidualFrame`) [m]."""
    from ..core.workbench.selection import penalised_fit

    y = frame.residual[:, component]
    x, penalties, _ = joint_design(terms, frame, component, zeroed)
    if x.shape[1] == 0:
        return float(np.sqrt(np.mean(y[judge] ** 2)))
    coefficients, _, _ = penalised_fit(x[fit], y[fit], penalties)
    return float(np.sqrt(np.mean((y[judge] - x[judge] @ coefficients) ** 2)))


#: Families that are a whole model of a log in one term: they contest the step-by-step
#: model as a whole (:func:`forward_blocks`, :func:`pooled_rmse`).
WHOLE_MODELS = ("sensor_least_squares", "all_sensors_ridge", "temperature_components")


def forward_blocks(terms, frame, component: int, blocks, zeroed: bool) -> list[dict]:
    """Forward validation of ``terms`` fitted jointly, block by block: each block (whole
    runs) predicted by a fit on the blocks before it. One dict per judged block: the
    rows fitted and judged, and the RMS error on the judged ones [m]."""
    out = []
    for b in range(1, int(blocks[-1]) + 1):
        judge, fit = blocks == b, blocks < b
        out.append({"trained_rows": int(fit.sum()), "judged_rows": int(judge.sum()),
                    "rmse": validation_rmse(terms, frame, component, fit, judge, zeroed)})
    return out


def pooled_rmse(per_block: list[dict]) -> float:
    """The blocks' squared errors pooled over every judged row [m]."""
    count = sum(b["judged_rows"] for b in per_block)
    squared = sum(b["rmse"] ** 2 * b["judged_rows"] for b in per_block)
    return float(np.sqrt(squared / max(count, 1)))


def regime_blocks(terms, frame, component: int, regimes, zeroed: bool) -> list[dict]:
    """Each regime group of the training rows (:class:`~..core.workbench.regimes.Regimes`)
    predicted by ``terms`` fitted jointly on the other groups' rows - a model judged on a
    working condition it was not fitted on, Zhu's robustness test (Zhu 2008 ch. 3). One
    dict per judged group: its name, the rows fitted and judged, the RMS error on the
    judged ones [m] and how far the terms' inputs left their fitted range there (a share
    of the span, :func:`~..core.workbench.regimes.range_excess`)."""
    from ..core.workbench.regimes import range_excess
    from ..core.workbench.selection import penalised_fit

    if regimes.by == "one regime":
        return []
    y = frame.residual[:, component]
    x, penalties, _ = joint_design(terms, frame, component, zeroed)
    out = []
    for g, name in enumerate(regimes.group_names):
        judge = regimes.group_of_row == g
        fit = ~judge
        if judge.sum() < 2 or fit.sum() < max(4, x.shape[1] + 1):
            continue
        if x.shape[1] == 0:
            rmse, excess = float(np.sqrt(np.mean(y[judge] ** 2))), 0.0
        else:
            coefficients, _, _ = penalised_fit(x[fit], y[fit], penalties)
            rmse = float(np.sqrt(np.mean((y[judge] - x[judge] @ coefficients) ** 2)))
            excess = range_excess(x[fit], x[judge])
        out.append({"regime": name, "trained_rows": int(fit.sum()),
                    "judged_rows": int(judge.sum()), "rmse": rmse, "range_excess": excess})
    return out


def telling_regimes(across: dict[str, list[dict]], constant: list[dict]) -> set[str]:
    """The training regimes that tell whole models apart: those on which some contestant,
    fitted on the other regimes, predicts better than a constant fitted there too.

    A regime no model predicts better than a constant (a log of one heating, judged on its
    dwell from a fit on the heating alone) says that nothing extrapolates there, not which
    model extrapolates better: every contestant's figure on it is set by the missing
    regime, and letting it decide would choose at random among failures. (Charging a
    model's gross failures there - beyond 2 or 10 times the constant's error - was tried
    on the real logs and chose worse models held out: a constant's error on a flat regime
    can be tiny, and the ratio then says little.)

    Parameters
    ----------
    across : dict of str to list of dict
        Each contestant's :func:`regime_blocks`.
    constant : list of dict
        The same blocks of a constant (:func:`regime_blocks` of no terms).

    Returns
    -------
    set of str
        The regimes that decide.
    """
    constant_rmse = {b["regime"]: b["rmse"] for b in constant}
    best: dict[str, float] = {}
    for blocks_of in across.values():
        for b in blocks_of:
            best[b["regime"]] = min(best.get(b["regime"], np.inf), b["rmse"])
    return {r for r, v in best.items() if v < constant_rmse.get(r, np.inf)}


def deciding_blocks(blocks_of: list[dict], compared: set[str]) -> list[dict]:
    """A model's regime blocks that decide: those of the regimes that tell models apart
    (``compared``, :func:`telling_regimes`)."""
    return [b for b in blocks_of if b["regime"] in compared]


def robust_score(forward: float, deciding: list[dict]) -> float:
    """The worse of a model's ``forward`` error and its error pooled over its ``deciding``
    regime blocks (:func:`deciding_blocks`) [m]; ``forward`` alone when none decides."""
    return max(forward, pooled_rmse(deciding)) if deciding else forward


def _say_untold_regimes(across: dict[str, list[dict]], compared: set[str],
                        notes: list[str]) -> None:
    """A note naming the training regimes no contestant predicted better than a constant
    (left out of the cross-regime figures), when there are any."""
    judged = list(dict.fromkeys(b["regime"] for blocks_of in across.values()
                                for b in blocks_of))
    untold = [r for r in judged if r not in compared]
    if untold:
        notes.append(f"no model predicts the training regime{'s' if len(untold) > 1 else ''} "
                     f"{', '.join(untold)} from the others better than a constant: "
                     f"{'they do' if len(untold) > 1 else 'it does'} not decide between the "
                     "models (the forward figure"
                     f"{' and the other regimes do' if len(untold) < len(judged) else ' does'})")


#: Whole models whose decisive errors lie this close to the best one's are alike: the one
#: whose inputs left their fitted range least, across regimes, is the model.
ALIKE_SHARE = 0.1


def contest_winner(scores: dict[str, float], excess: dict[str, float]) -> str:
    """The model of a contest: the lowest score, unless others within :data:`ALIKE_SHARE`
    of it extrapolated less (then the one that extrapolated least; the step-by-step model
    first on a tie)."""
    best = min(scores.values())
    alike = [k for k, v in scores.items() if v <= best * (1.0 + ALIKE_SHARE)]
    return min(alike, key=lambda k: (round(excess.get(k, 0.0), 2), scores[k],
                                     k != "step by step"))


def joint_refit(candidates, terms, frame, component: int, zeroed: bool) -> list:
    """The ``candidates`` with their parameters (and k = 1 uncertainties) refitted jointly
    on every training row of ``frame`` (their ``terms`` as in :func:`validation_rmse`)."""
    from ..core.workbench.selection import penalised_fit

    x, penalties, spans = joint_design(terms, frame, component, zeroed)
    values, errors, _ = penalised_fit(x, frame.residual[:, component], penalties)
    out = []
    for candidate, (family, variant, setting), (a, b) in zip(candidates, terms, spans):
        names = family.parameter_names(variant, setting)
        # The fit saw this component's columns only: parameters of the others stay zero.
        used = np.any(x[:, a:b] != 0, axis=0)
        parameters = {n: float(values[a + j]) if used[j] else 0.0 for j, n in enumerate(names)}
        uncertainties = {n: float(errors[a + j]) if used[j] else 0.0
                         for j, n in enumerate(names)}
        out.append(dataclasses.replace(candidate, parameters=parameters,
                                       parameter_uncertainties=uncertainties))
    return out


def _log_families(training, obs_structure: list[str], target):
    """The catalogue's families plus the log-only ones, their sensor sets chosen on the
    training rows: every structure sensor, and key sensors of correlated groups."""
    from ..core.effects import families as catalogue_families
    from ..core.effects.log_models import (SensorLeastSquares, TemperatureComponents,
                                           sensor_groups)

    chosen: dict[str, str] = {}
    if len(obs_structure) >= 2:
        chosen["+".join(obs_structure)] = "every structure sensor"
    groups = sensor_groups({s: training.temperatures[s] for s in obs_structure}, target)
    for variant, how in groups.items():
        chosen.setdefault(variant, how)
    return [f for f in catalogue_families() if not f.log_only] + \
        [SensorLeastSquares(chosen), TemperatureComponents()]


def per_run_figures(names: list[str], run_of_row, train, residuals: dict[str, np.ndarray]
                    ) -> list[dict]:
    """One row per run: its rows, whether the selection saw it, and each model's RMSE on
    it [m] (``residuals``: name -> (N,) residual)."""
    out = []
    for k, name in enumerate(names):
        rows = run_of_row == k
        entry = {"run": name, "rows": int(rows.sum()),
                 "part": "training" if bool(train[rows].all()) else "held out"}
        for label, residual in residuals.items():
            entry[label] = float(np.sqrt(np.mean(residual[rows] ** 2)))
        out.append(entry)
    return out


def large_gains_not_added(first, final, added: list[str], judged: set[str], auto: int,
                          min_reduction: float, room: int) -> list[NotAdded]:
    """Each candidate of the first diagnosis with a CV gain of :data:`LARGE_GAIN` or more
    that was neither added nor judged already, with the test that refused it (its
    numbers), looked up where the ``final`` diagnosis stands; at most ``room``."""
    from ..core.workbench.diagnosis import selection_refusal

    out = []
    for option in first.ranking:
        if len(out) >= room:
            break
        if option.error_reduction < LARGE_GAIN or option.name in added or option.name in judged:
            continue
        reason = selection_refusal(option, min_reduction)
        if reason.startswith("the held-out block test") and added:
            reason += f"; {', '.join(added)} {'were' if len(added) > 1 else 'was'} added instead"
        if not reason:
            later = next((o for o in final.ranking if o.name == option.name), None)
            if not added:
                reason = "not tried: --auto 0 adds nothing by itself" if not auto else \
                    f"not judged: beyond the first {MAX_JUDGED} candidates of a step"
            elif later is None:
                reason = f"{', '.join(added)} covers it (no longer a candidate)"
            else:
                left = selection_refusal(later, min_reduction, block_test=False)
                reason = (f"after {', '.join(added)}: {left}" if left else
                          f"after {', '.join(added)} it gains {100 * later.error_reduction:.0f} "
                          "% and was not judged (--auto used up, or candidates ranked before "
                          "it)")
        out.append(NotAdded(option.name, option.error_reduction, reason))
    return out


@dataclasses.dataclass
class LogData:
    """A log read and checked: its table, its observations, and what was said about it."""

    table: object
    obs: object
    target_column: str
    unit: str
    to_unit: float
    run_names: list[str] | None
    notes: list[str]
    #: (N,) each observation's data row in the file (1-based, the header and any units
    #: row not counted), as the other notes number rows.
    file_rows: np.ndarray | None = None


def _in_seconds(name: str, values: np.ndarray, units: dict[str, str]
                ) -> tuple[np.ndarray, str]:
    """A time column in seconds, from the unit a units row or its name gives (``t_min``,
    ``time [h]``; seconds when neither does), and a note when it was converted."""
    from ..io.column_map import UNITS, column_unit

    unit = column_unit(name, "time", units)
    if unit in ("", "s"):
        return values, ""
    return values * UNITS["time"][unit], f"time {name} converted from {unit} to s"


def _in_celsius(temperatures: dict[str, np.ndarray], units: dict[str, str] | None = None
                ) -> tuple[dict[str, np.ndarray], list]:
    """Temperatures in °C (as sensor_msgs/Temperature), each from the unit a units row
    (``units``) or its column's name gives (``T1_K``, ``T2 [°F]``; °C when neither
    does), and a note of those converted."""
    from ..core.inputs.sensor_health import coolest_reading
    from ..io.column_map import TEMPERATURE, column_unit

    out, converted = {}, []
    declared = {name: column_unit(name, "temperature", units) or "degC"
                for name in temperatures}
    coolest = {name: coolest_reading(values * TEMPERATURE[declared[name]][0] +
                              TEMPERATURE[declared[name]][1])
               for name, values in temperatures.items()}
    for name, values in temperatures.items():
        unit = declared[name]
        others = [c for other, c in coolest.items() if other != name and np.isfinite(c)]
        check_temperature_units(name, values, unit,
                                float(np.median(others)) if others else None)
        scale, offset = TEMPERATURE[unit]
        out[name] = values * scale + offset if (scale, offset) != (1.0, 0.0) else values
        if unit not in ("degC", "C"):
            converted.append(f"{name} ({unit})")
    return out, ([f"temperatures converted to °C: {', '.join(converted)}"] if converted else [])


def validate_log_options(auto: int, train_fraction: float) -> None:
    """Refuse the options a log cannot use, naming the flag (whatever the parser let by).

    Raises
    ------
    ParameterError
        ``auto`` negative (a count of terms); ``train_fraction`` outside 0.2 ... 0.9 (the
        rows after it judge the model; fewer than a tenth cannot).
    """
    if not (isinstance(auto, (int, np.integer)) and auto >= 0):
        raise ParameterError(f"--auto {auto}: give a count of terms to add, 0 or more (0 adds "
                             "nothing by itself)")
    if not (np.isfinite(train_fraction) and 0.2 <= train_fraction <= 0.9):
        raise ParameterError(f"--train-fraction {train_fraction}: between 0.2 and 0.9 (the "
                             "rows after it judge the model)")


#: Words of a column name that make it a temperature when no unit says so.
TEMPERATURE_NAME = re.compile(r"^(t|temp|temperature|tc|th)[\W_]*\d*([\W_]|$)|temp",
                              re.IGNORECASE)

#: Quantities whose unit in a column's name or units row makes it no temperature.
OTHER_QUANTITIES = ("length", "speed", "time", "velocity", "acceleration", "angle")


def temperature_look(name: str, values: np.ndarray, units: dict[str, str]) -> str:
    """"" when column ``name`` looks like a temperature (a temperature unit in its name or
    units row, a temperature's name - T3, temp_bed -, or readings a temperature of a
    machine would have), else why not ("spindle_rpm (rpm)")."""
    from ..core.inputs.plausibility import likely_unit
    from ..core.inputs.sensor_health import dead_rows
    from ..io.column_map import column_unit

    if column_unit(name, "temperature", units):
        return ""
    for quantity in OTHER_QUANTITIES:
        unit = column_unit(name, quantity, units)
        if unit:
            return f"{name} ({unit})"
    if TEMPERATURE_NAME.search(name):
        return ""
    finite = values[np.isfinite(values)]
    # A dead thermocouple's one value (-180, -273) on every row is a temperature column
    # whose sensor is absent: the sensors' judge names it and leaves it out.
    if finite.size and dead_rows(finite).all():
        return ""
    if finite.size and likely_unit(np.percentile(finite, [5, 95]), "temperature_hot", "") \
            is not None:
        return ""
    span = (f"{finite.min():.4g} ... {finite.max():.4g}" if finite.size else "no reading")
    return f"{name} (reads {span}, no temperature)"


def select_temperature_inputs(names: list[str], patterns: list[str], excluded: tuple,
                              columns: dict[str, np.ndarray], units: dict[str, str]
                              ) -> tuple[list[str], list[str]]:
    """(the columns the ``--inputs`` patterns match that look like temperatures, a note
    naming the matched ones left out).

    Raises
    ------
    InputDataError
        A pattern that matches no temperature column (each pattern must match one).
    """
    selected: list[str] = []
    left_out: dict[str, str] = {}
    for pattern in patterns:
        matched = [n for n in names if fnmatch.fnmatch(n, pattern) and n not in excluded]
        found = []
        for name in matched:
            why = temperature_look(name, columns[name], units)
            if why:
                left_out[name] = why
            else:
                found.append(name)
        if not found:
            raise InputDataError(
                f"--inputs {pattern!r} matches no temperature column"
                + (f" (it matched {', '.join(left_out[n] for n in matched)})" if matched else "")
                + f"; columns: {', '.join(n for n in names if n not in excluded)}")
        selected += [n for n in found if n not in selected]
    notes = [f"--inputs {' '.join(patterns)} also matched {', '.join(left_out.values())}: "
             "no temperatures, left out of the inputs"] if left_out else []
    return selected, notes


def _target_has_a_unit(flag: str, names: list[str], units: dict[str, str]) -> None:
    """Refuse a target whose unit neither its flag, its name nor a units row gives, saying
    how to give it."""
    from ..io.column_map import column_unit

    if ":" not in flag and flag.strip() in names and \
            not column_unit(flag.strip(), "length", units):
        name = flag.strip()
        raise InputDataError(f"target {name}: no unit in --target, its name or a units row; "
                             f"give its unit as {name}:UNIT, e.g. --target {name}:um (or mm, "
                             "m, nm, in)")


def check_target(column: str, values: np.ndarray, unit: str) -> None:
    """Refuse a target with nothing to model or in an implausible unit.

    Raises
    ------
    InputDataError
        The target is constant; or its values, in ``unit``, are no thermal displacement
        (beyond 5 mm, or spanning under 10 nm): naming the unit they look like.
    """
    from ..core.inputs.plausibility import check_plausible, likely_unit

    finite = values[np.isfinite(values)]
    if finite.size >= 2 and np.ptp(finite) == 0.0:
        raise InputDataError(f"target {column} is constant ({finite[0]:g} {unit} on all "
                             f"{finite.size} rows): nothing to model")
    from ..core.inputs.plausibility import UNITS

    to_mm = UNITS["length"].get(unit, 0.0) * 1e3
    if to_mm and finite.size and np.ptp(finite) * to_mm <= 5.0 < \
            np.max(np.abs(finite)) * to_mm:
        raise InputDataError(
            f"target {column} sits {np.median(finite) * to_mm:.4g} mm from zero but spans "
            f"{np.ptp(finite) * to_mm:.3g} mm: a position, not a displacement? Give its "
            "change from a reference (subtract its first reading) as the target")
    for quantity in ("error", "deviation_spread"):
        guess = likely_unit(finite, quantity, unit)
        check_plausible(finite, quantity, unit, f"target {column}",
                        mend=f"declare its unit: --target {column}:{guess or 'UNIT'}",
                        error=InputDataError)


def check_temperature_units(name: str, values: np.ndarray, declared: str,
                            others_coolest_c: float | None = None) -> None:
    """Refuse a sensor whose readings, in their ``declared`` unit, lie mostly where no
    machine's temperature does and another unit would put them (kelvin declared as degC).
    Readings beyond any unit (a dead sensor's -180) are the sensors' judge's, row by row.
    The surveys' rule too (:func:`~..core.inputs.sensor_health.refuse_wrong_temperature_unit`).
    ``others_coolest_c``: the other sensors' coolest reading [degC]; a sensor that starts
    where they start is in their unit, however hot it is held (a heater).

    Raises
    ------
    InputDataError
        Naming the sensor, its values, the declared unit and the likely one.
    """
    from ..core.inputs.sensor_health import refuse_wrong_temperature_unit

    refuse_wrong_temperature_unit(name, values, declared, f"sensor {name}",
                                  f"give its unit in its name ({name}_{{guess}}) or a units row",
                                  InputDataError, others_coolest_c)


def _complete_rows(temperatures: dict[str, np.ndarray]) -> np.ndarray:
    """(N,) rows where every sensor has a reading."""
    values = list(temperatures.values())
    return np.all([np.isfinite(v) for v in values], axis=0) if values else np.asarray(True)


def clock_of_log(time_s: np.ndarray, time_column: str, data_rows, run_of_row, run_names,
                 row_period_s: float | None):
    """(time [s], run of each row, run names, rows after a clock jump, notes): the log's
    clock judged.

    Equal stamps on every row are no time: refused, or - with ``--row-period`` - the row
    order at that period, said. A clock jump (:func:`~..core.workbench.log_runs.clock_breaks`)
    is a break between runs when the log has no run column (said, with its row and size);
    inside a run of a run column it is refused. Equal stamps are named with their rows.

    Raises
    ------
    InputDataError
        One stamp on every row without ``--row-period``; a clock jump inside a run.
    """
    from ..core.workbench.log_runs import clock_breaks, duration_text, run_labels

    notes = []
    finite = time_s[np.isfinite(time_s)]
    if time_column and finite.size >= 2 and np.ptp(finite) == 0.0:
        if row_period_s is None:
            raise InputDataError(f"time column {time_column} holds one stamp ({finite[0]:g}) "
                                 "on every row: no time to model lags with; give --row-period "
                                 "SECONDS to take the row order, one row every SECONDS")
        time_s = np.arange(time_s.size, dtype=np.float64) * float(row_period_s)
        notes.append(f"time column {time_column} holds one stamp on every row: the row order "
                     f"taken, one row every {row_period_s:g} s (--row-period)")
        return time_s, run_of_row, run_names, np.zeros(time_s.size, bool), notes
    breaks, clock_notes = clock_breaks(time_s, data_rows)
    rows = np.arange(1, time_s.size + 1) if data_rows is None else np.asarray(data_rows)
    if breaks.any() and run_of_row is not None:
        inside = np.flatnonzero(breaks[1:] & (np.diff(run_of_row) == 0)) + 1
        if inside.size:
            k = int(inside[0])
            raise InputDataError(f"the clock jumps by {duration_text(time_s[k] - time_s[k - 1])} "
                                 "inside "
                                 f"run {run_names[run_of_row[k]]!r} at data row {int(rows[k])}: "
                                 "start a new run there (a new value in the run column) or "
                                 "fix the stamps")
        breaks[:] = False
        clock_notes = [n for n in clock_notes if not n.startswith("the clock jumps")]
    elif breaks.any():
        labels = np.cumsum(breaks) + 1
        run_of_row, run_names = run_labels(labels.astype(str), data_rows, "clock-break")
        notes.append(f"{len(run_names)} runs between the clock's jumps: " + ", ".join(
            f"run {name} (data rows {int(rows[labels == k + 1][0])}-"
            f"{int(rows[labels == k + 1][-1])})" for k, name in enumerate(run_names)))
    return time_s, run_of_row, run_names, breaks, clock_notes + notes


def _table_notes(table, time_column: str, split_time: list[str]) -> list[str]:
    """What the file itself told: a units row, a clock or date-time time column."""
    notes = []
    if table.units:
        notes.append("units from the row under the header: " + ", ".join(
            f"{name} {unit}" for name, unit in table.units.items()))
    if time_column in table.clock_columns:
        notes.append(f"time from the clock of {time_column} (times of day without a date: "
                     "a step back of more than 12 h is taken as midnight passing)")
    elif time_column in table.date_time_columns:
        notes.append(f"time from the date-times of {' + '.join(split_time) or time_column} "
                     "(seconds since its first, a stamp without a zone taken as UTC)")
    return notes


def _without_failed_readings(table, target_column: str, target_scale: float, unit: str,
                             run_of_row: np.ndarray | None, inputs: list[np.ndarray]
                             ) -> tuple[np.ndarray, str]:
    """The target [m] with its failed readings (:mod:`~..core.inputs.target_outliers`, each
    run judged alone) NaN, counted among the table's dropped rows, and the note naming them
    ("" when none); a target with more spikes than failed readings make is refused."""
    from ..core.inputs.target_outliers import MAX_SPIKE_SHARE, target_spikes

    values = table.columns[target_column]
    starts = None if run_of_row is None else np.r_[True, np.diff(run_of_row) != 0]
    spikes = target_spikes(values, starts, inputs)
    if not spikes.count:
        return values * target_scale, ""
    if spikes.count > MAX_SPIKE_SHARE * values.size:
        raise InputDataError(f"target {target_column}: {spikes.count} of {values.size} "
                             "readings far from the readings either side and back, too many "
                             "to be failed readings - is the target the displacement (a "
                             "position, a noisy channel)?")
    text = spikes.text(target_column, unit, table.data_rows)
    table.drop_rows(spikes.count, f"{spikes.count} with a failed target reading (see the "
                    "notes)")
    return np.where(spikes.rows, np.nan, values) * target_scale, text


def read_log(path: Path, target: str, time_column: str, inputs: list[str],
             drivers: list[str], row_period_s: float | None, component: str,
             uncertainty_m: float | None, run_column: str | None, zeroed_runs: bool
             ) -> LogData:
    """The log's columns as observations (SI), its runs checked, dead sensors left out;
    one-line errors naming the row, run or column (see :func:`check_csv`)."""
    from ..core.workbench.log_runs import (leave_out_dead_sensors, mixed_units_problem,
                                           run_labels, run_level_notes, run_starts)
    from ..core.workbench.thermal_log import (complete_log_rows, kept_data_rows,
                                              log_observations)
    from ..io.csv_table import csv_header, joined_columns, read_csv_table
    from .check import _column_and_unit

    header = csv_header(path)
    # A date and a time of day in two columns: --time-column DATE+TIME.
    split_time = joined_columns(time_column, header)
    fixed = {flag.split(":", 1)[0].strip() for flag in [target, *drivers]} | \
        {time_column, run_column, *split_time}
    # A temperature column may have holes (a dead thermocouple): kept as NaN, decided below.
    table = read_csv_table(path, text_columns=(run_column,) if run_column else (),
                           gap_columns=tuple(n for n in header if n not in fixed),
                           time_columns=(time_column,))
    names = table.names
    columns = table.columns
    _target_has_a_unit(target, names, table.units)
    target_column, target_scale, unit = _column_and_unit(target, names, "length", "target",
                                                         table.units)
    time_note = ""
    if time_column in names:
        time_s = columns[time_column]
        if time_column in table.date_time_columns and time_s.size:
            time_s = time_s - time_s[0]     # seconds since the first stamp
        else:
            time_s, time_note = _in_seconds(time_column, time_s, table.units)
    elif row_period_s is not None:
        time_s = np.arange(len(columns[names[0]]), dtype=np.float64) * float(row_period_s)
    else:
        timely = [n for n in names if any(w in n.lower() for w in TIME_WORDS)]
        raise InputDataError(f"{path}: no time column {time_column!r} (give --time-column"
                             f"{' ' + timely[0] if timely else ''}, or --row-period SECONDS "
                             f"for one row every SECONDS); columns: {', '.join(names)}")
    selected, input_notes = select_temperature_inputs(
        names, inputs, (target_column, time_column, run_column, *split_time), columns,
        table.units)
    speed = None
    for driver in drivers:
        column, scale, _ = _column_and_unit(driver, names, "speed", "driver", table.units)
        if speed is not None:
            raise InputDataError("one --driver: the spindle speed (the heat source the "
                                 "catalogue models, heat_source:spindle_speed)")
        speed = columns[column] * scale
    run_of_row, run_names = None, None
    temperatures, notes = _in_celsius({n: columns[n] for n in selected}, table.units)
    notes += input_notes
    notes += [time_note] if time_note else []
    notes += _table_notes(table, time_column, split_time)
    if run_column:
        run_of_row, run_names = run_labels(columns[run_column], table.data_rows, run_column)
    time_s, run_of_row, run_names, breaks, clock_notes = clock_of_log(
        time_s, time_column if time_column in names else "", table.data_rows, run_of_row,
        run_names, row_period_s)
    notes += clock_notes
    # Failed readings first, each run alone: a missed homing's few millimetres must not
    # read as a unit, a zeroed gauge's morning ramp not as a failed reading.
    target_m, spike_note = _without_failed_readings(
        table, target_column, target_scale, unit, run_of_row,
        list(temperatures.values()) + ([] if speed is None else [speed]))
    check_target(target_column, target_m / target_scale, unit)
    notes += [spike_note] if spike_note else []
    if run_of_row is not None:
        # A run in another unit is refused before the sensors' judge sees it: a run of
        # kelvin reads like a dead sensor's run, and would be left out as one.
        problem = mixed_units_problem(target_m, temperatures, run_of_row, run_names,
                                      zeroed_runs)
        if problem:
            raise InputDataError(problem)
    complete_before = _complete_rows(temperatures)
    temperatures, health_notes = leave_out_dead_sensors(temperatures, run_of_row, run_names,
                                                        table.data_rows, breaks)
    notes += health_notes
    # A few holes in a live sensor: those rows are left out, counted with their reasons;
    # so are the few bad readings the sensors' judge set aside (named in the notes).
    table.drop_gaps_of(set(temperatures))
    judged_out = int(np.sum(complete_before & ~_complete_rows(temperatures)))
    if judged_out:
        table.drop_rows(judged_out, f"{judged_out} with a bad sensor reading (see the notes)")
    if not temperatures:
        raise InputDataError(f"{path}: every input sensor is left out ({'; '.join(health_notes)})"
                             [:400] + " - give live sensors with --inputs")
    if run_of_row is not None:
        notes += run_level_notes(temperatures, run_of_row, run_names)
    obs = log_observations(time_s, target_m, temperatures, spindle_speed_rad_s=speed,
                           component=component, uncertainty_m=uncertainty_m,
                           run_of_row=run_of_row, run_names=run_names, zeroed_runs=zeroed_runs,
                           data_rows=table.data_rows)
    # Each row left out counted once (a failed target reading on a row with a sensor's gap
    # has two reasons).
    table.rows_dropped = table.rows_read - obs.n
    complete = complete_log_rows(time_s, target_m, temperatures, speed)
    if obs.run_of_row is not None:
        # Rows with a hole in a sensor (not dead) are left out: the runs that remain.
        kept_runs = np.asarray(run_of_row)[complete]
        run_names = [run_names[k] for k in kept_runs[run_starts(obs.run_of_row)]]
    return LogData(table, obs, target_column, unit, 1.0 / target_scale, run_names, notes,
                   kept_data_rows(table.data_rows, complete))


@dataclasses.dataclass
class _LogSearch:
    """What a thermal log's search works on: every row and the training rows, the starting
    model's residual frame on them, the component, and the last training block every
    term must predict from the blocks before it (:func:`_validation_split`)."""

    obs: object                 # every row (ThermalLogObservations)
    train: np.ndarray           # (N,) bool: the rows the selection sees
    training: object            # the training rows' observations
    frame: object               # ResidualFrame of the starting model on the training rows
    component: int
    fit_rows: np.ndarray
    judge_rows: np.ndarray
    judged_what: str            # the last training block, in words
    unit: str                   # the target's unit, and that unit per metre
    to_unit: float
    family_of: dict
    diagnose: object            # model -> Diagnosis on the training rows
    regimes: object             # Regimes of the training rows (runs, heating, cooling ...)

    def term(self, candidate) -> tuple:
        """(family, variant, setting) of a candidate."""
        return (self.family_of[candidate.effect], candidate.variant, candidate.setting)

    def validation(self, terms: list) -> float:
        """RMS error on the last training block of ``terms`` fitted on the blocks before [m]."""
        return validation_rmse(terms, self.frame, self.component, self.fit_rows,
                               self.judge_rows, self.obs.zeroed_runs)

    def step(self, model, diagnosis, validation: float) -> ModelStep:
        """The step of ``model`` (its ``diagnosis`` on the training rows)."""
        from ..core.workbench.thermal_log import held_out_rmse

        return ModelStep(model.version, sorted(model.effects), diagnosis.baseline_rmse,
                         diagnosis.text(), held_out_rmse=held_out_rmse(model, self.obs, self.train),
                         cv_rmse=diagnosis.baseline_cv_rmse, validation_rmse=validation)


@dataclasses.dataclass
class _Progress:
    """The step-by-step search as it stands: the model, its diagnosis and steps, the terms
    accepted, and what was said and refused on the way."""

    model: object
    diagnosis: object
    steps: list[ModelStep]
    validation: float
    first: object               # the starting model's diagnosis
    accepted: list = dataclasses.field(default_factory=list)
    accepted_terms: list = dataclasses.field(default_factory=list)
    warnings: list[str] = dataclasses.field(default_factory=list)
    not_added: list[NotAdded] = dataclasses.field(default_factory=list)
    refusals: list[str] = dataclasses.field(default_factory=list)
    refused_names: set = dataclasses.field(default_factory=set)


def _judged_candidate(search: _LogSearch, progress: _Progress, min_reduction: float):
    """(the candidate to add, its error on the last training block) or (None, the error as
    it stands). Each of the first :data:`MAX_JUDGED` usable candidates must predict the last
    training block better than the model without it (each one worse is recorded as not
    added); of those that do, the one whose worse error - on that block, or on each regime
    of the training rows predicted from the others (:func:`regime_blocks`, those that
    :func:`telling_regimes`) - is least is added, those the block test confirms first. A
    term chosen forward in time alone may fail the first time the machine does what the
    training rows did elsewhere."""
    from ..core.workbench.diagnosis import selection_refusal

    # Those the block test confirms first, then - on a log whose runs differ so much that
    # it confirms none - the rest that pass every other test.
    usable = [o for o in progress.diagnosis.ranking if o.name not in progress.refused_names and
              not selection_refusal(o, min_reduction, block_test=False)]
    usable.sort(key=lambda o: bool(selection_refusal(o, min_reduction)))
    before, unit, to_unit = progress.validation, search.unit, search.to_unit
    passing = []
    for option in usable[:MAX_JUDGED]:
        terms = progress.accepted_terms + [search.term(option)]
        value = search.validation(terms)
        if value < before:
            passing.append((option, value, regime_blocks(
                terms, search.frame, search.component, search.regimes,
                search.obs.zeroed_runs)))
            continue
        progress.refused_names.add(option.name)
        test = f"predicting {search.judged_what} from the training rows before them"
        progress.not_added.append(NotAdded(option.name, option.error_reduction, test,
                                           before=before, after=value))
        progress.refusals.append(f"not added: {option.name} (CV {100 * option.error_reduction:.0f}"
                                 f" % better) - {test}, its error would rise from "
                                 f"{before * to_unit:.4g} to {value * to_unit:.4g} {unit}")
    if not passing:
        return None, before
    # The regimes some candidate predicts better than a constant decide with the block.
    constant = regime_blocks([], search.frame, search.component, search.regimes,
                             search.obs.zeroed_runs)
    compared = telling_regimes({o.name: across for o, _, across in passing}, constant)

    def order(entry):
        option, value, across = entry
        return (bool(selection_refusal(option, min_reduction)),
                robust_score(value, deciding_blocks(across, compared)))

    option, value, _ = min(passing, key=order)
    return option, value


def _step_by_step(search: _LogSearch, start_model, add: list[str], auto: int,
                  min_reduction: float) -> _Progress:
    """The search from ``start_model``: the effects asked for (``add``) first, then up to
    ``auto`` the selection judges; after each, every added term refitted jointly."""
    from ..core.workbench.diagnosis import add_effect
    from .check import candidate_named

    diagnosis = search.diagnose(start_model)
    validation = search.validation([])
    progress = _Progress(start_model, diagnosis, [search.step(start_model, diagnosis,
                                                              validation)], validation, diagnosis)
    queue = list(add)
    while True:
        if queue:
            candidate = candidate_named(progress.diagnosis, queue.pop(0), "add", "log")
            after = search.validation(progress.accepted_terms + [search.term(candidate)])
            if after > progress.validation:
                progress.warnings.append(
                    f"warning: {candidate.name} (asked for) raised the error on "
                    f"{search.judged_what} from {progress.validation * search.to_unit:.4g} to "
                    f"{after * search.to_unit:.4g} {search.unit}")
        elif auto and len(progress.steps) - 1 < auto:
            candidate, after = _judged_candidate(search, progress, min_reduction)
            if candidate is None:
                break
        else:
            break
        progress.accepted_terms.append(search.term(candidate))
        progress.accepted.append(candidate)
        progress.validation = after
        # Every added term refitted jointly on the training rows (a term fitted to the
        # residual of the ones before it leaves their share of the shared signal wrong).
        model = start_model
        for refitted in joint_refit(progress.accepted, progress.accepted_terms, search.frame,
                                    search.component, search.obs.zeroed_runs):
            model = add_effect(model, refitted, search.training)
        progress.model, progress.diagnosis = model, search.diagnose(model)
        progress.steps[-1].record_added([candidate])
        progress.steps.append(search.step(model, progress.diagnosis, after))
    return progress


def _contest(search: _LogSearch, progress: _Progress, first, start_model, blocks,
             validation_blocks, rivals_too: bool, notes: list[str]
             ) -> tuple[list[ContestEntry], dict[str, float]]:
    """Whole models against one another, by the same forward validation over every
    training block and, when the training rows hold several regimes, each regime
    predicted from the others (:func:`regime_blocks`): the step-by-step model, and
    (``rivals_too``) each model a thermal engineer fits in one go (least squares or ridge
    on every sensor, principal components). The worse of a model's two errors decides
    (:func:`contest_winner`); a rival that wins becomes the model (``progress`` takes it,
    said in ``notes``). Returns (the contest, best first; each model's pooled forward
    error [m], the step-by-step model's first)."""
    from ..core.workbench.diagnosis import add_effect
    from ..core.workbench.thermal_log import held_out_rmse

    c, zeroed = search.component, search.obs.zeroed_runs
    terms_of = {"step by step": progress.accepted_terms}
    rivals = {}
    for option in first.ranking if rivals_too else []:
        # (A rival the step-by-step model consists of is that model: not run twice.)
        if option.effect in WHOLE_MODELS and not option.refusal and \
                option.name not in terms_of and progress.accepted_terms != [search.term(option)]:
            terms_of[option.name] = [search.term(option)]
            rivals[option.name] = option
    per_block = {name: forward_blocks(terms, search.frame, c, validation_blocks, zeroed)
                 for name, terms in terms_of.items()}
    across = {name: regime_blocks(terms, search.frame, c, search.regimes, zeroed)
              for name, terms in terms_of.items()}
    contest = {name: pooled_rmse(blocks_of) for name, blocks_of in per_block.items()}
    constant = regime_blocks([], search.frame, c, search.regimes, zeroed)
    compared = telling_regimes(across, constant)
    _say_untold_regimes(across, compared, notes)
    told = {name: deciding_blocks(blocks_of, compared) for name, blocks_of in across.items()}
    for blocks_of in across.values():
        for b in blocks_of:
            b["decides"] = b["regime"] in compared
    score = {name: robust_score(contest[name], told[name]) for name in terms_of}
    excess = {name: max((b["range_excess"] for b in across[name]), default=0.0)
              for name in terms_of}
    winner = contest_winner(score, excess)
    # Each contestant's figures on the held-out rows, for the reader only: computed after
    # the decision, they decide nothing (how well the contest chose).
    held_out = {"step by step": progress.steps[-1].held_out_rmse}
    rival_models = {}
    for name, option in rivals.items():
        (refitted,) = joint_refit([option], [search.term(option)], search.frame, c, zeroed)
        rival_models[name] = (refitted, add_effect(start_model, refitted, search.training))
        held_out[name] = held_out_rmse(rival_models[name][1], search.obs, search.train)
    held_excess = _held_out_excess(search, start_model, terms_of)
    step_by_step = [name for s in progress.steps for name in s.added or []]
    if winner != "step by step":
        _take_rival(search, progress, winner, rival_models[winner], rivals[winner],
                    score, excess, told, blocks, notes)
    return [ContestEntry(name, step_by_step if name == "step by step" else [name],
                         contest[name], per_block[name], held_out[name], name == winner,
                         pooled_rmse(told[name]) if told[name] else None, across[name],
                         score[name], excess[name], held_excess[name])
            for name in sorted(score, key=score.get)], contest


def _held_out_excess(search: _LogSearch, start_model, terms_of: dict) -> dict[str, float]:
    """How far each contestant's inputs leave their training range on the held-out rows,
    a share of the span (:func:`~..core.workbench.regimes.range_excess`)."""
    from ..core.workbench.diagnosis import residual_frame
    from ..core.workbench.regimes import range_excess

    if search.train.all():
        return {name: 0.0 for name in terms_of}
    whole = residual_frame(start_model, search.obs)
    out = {}
    for name, terms in terms_of.items():
        x = joint_design(terms, whole, search.component, True)[0]
        out[name] = range_excess(x[search.train], x[~search.train]) if x.shape[1] else 0.0
    return out


def _take_rival(search: _LogSearch, progress: _Progress, winner: str, rival, option,
                score: dict, excess: dict, across: dict, blocks, notes: list[str]) -> None:
    """The contest's winner, a whole-model rival, becomes the model (said in ``notes``, with
    the rule that chose it: a lower score, or one within :data:`ALIKE_SHARE` whose inputs
    left their fitted range less)."""
    unit, to_unit = search.unit, search.to_unit
    how = "forward and across regimes (the worse of the two)" if across[winner] else "forward"
    rows = "runs" if blocks is not None else "rows"
    mine, theirs = score[winner] * to_unit, score["step by step"] * to_unit
    if score[winner] <= score["step by step"]:
        notes.append(f"{winner} predicts the training {rows} {how} better ({mine:.4g} {unit}) "
                     f"than the step-by-step model ({theirs:.4g} {unit}): it is the model")
    else:
        notes.append(f"{winner} predicts the training {rows} {how} within "
                     f"{100 * ALIKE_SHARE:.0f} % of the step-by-step model ({mine:.4g} against "
                     f"{theirs:.4g} {unit}) and its inputs left their fitted range less "
                     f"({excess[winner]:.2g} against {excess['step by step']:.2g} of the "
                     "span): it is the model")
    refitted, progress.model = rival
    progress.steps = progress.steps[:1]
    first_step = progress.steps[0]
    first_step.added = [winner]
    first_step.parameters = {winner: refitted.parameters}
    first_step.parameter_uncertainties = {winner: refitted.parameter_uncertainties}
    progress.diagnosis = search.diagnose(progress.model)
    progress.steps.append(search.step(progress.model, progress.diagnosis,
                                      search.validation([search.term(option)])))


def _sensor_weights(first, steps: list[ModelStep], added: list[str], temperatures
                    ) -> tuple[dict, dict]:
    """(the sensors a sensor model leans on: name -> share of its spread, whose weights
    they are): the model's sensor model, else the all-sensor ridge candidate's."""
    from ..core.effects.thermal import sensor_weights

    ridge = [(name, step.parameters[name]) for step in steps for name in step.added or []
             if name.startswith(("all_sensors_ridge", "sensor_least_squares"))] + \
        [(c_.name, c_.parameters) for c_ in first.ranking if c_.effect == "all_sensors_ridge"]
    if not ridge:
        return {}, {}
    carried = dict(sensor_weights(ridge[0][1], temperatures)[:6])
    sensors = ridge[0][0].split(":", 1)[1].count("+") + 1
    in_model = ridge[0][0] in added
    return carried, {"name": ridge[0][0], "sensors": sensors, "in_model": in_model,
                     "words": f"the {'model' if in_model else 'candidate'} "
                              f"{ridge[0][0].split(':', 1)[0]} over {sensors} "
                              f"sensor{'s' if sensors > 1 else ''}"}


def check_csv(path: Path, target: str, time_column: str, inputs: list[str], drivers: list[str],
              add: list[str], auto: int, train_fraction: float, min_reduction: float,
              model_terms: list[str], row_period_s: float | None = None,
              component: str = "z", uncertainty_m: float | None = None,
              structure_length_m: float | None = None, run_column: str | None = None,
              zeroed_runs: bool = False, walk_forward_period: str | None = None,
              progress=None) -> CheckResult:
    """A thermal log (one displacement column, temperature inputs, a spindle speed; one run
    or many) on the survey engine (:mod:`~mt_accuracy_ros.core.workbench.thermal_log`).

    Its time is the time column, or - without one - the row order at ``row_period_s``
    seconds a row. ``run_column``: rows of one run share its value (time restarts or
    jumps between runs; lags restart each run); ``zeroed_runs``: the instrument was
    zeroed at each run's start. Decisions are made on the training rows only (module
    docstring); everything is SI in the JSON (metres); printed lines speak the target
    column's unit. ``walk_forward_period`` ("4h", "run"): the log is also replayed in
    time, the model made again at each period's end from every row so far and judged on
    the next period (:mod:`.check_walk`); ``progress`` is called with a line per period.
    """
    from ..core.workbench.log_runs import split_at_run
    from ..core.workbench.walk_forward import parse_period

    validate_log_options(auto, train_fraction)
    period_s = parse_period(walk_forward_period) if walk_forward_period else None
    if zeroed_runs and not run_column:
        raise InputDataError("--zeroed-runs needs --run COLUMN (the instrument was zeroed at "
                             "each run's start)")
    log = read_log(path, target, time_column, inputs, drivers, row_period_s, component,
                   uncertainty_m, run_column, zeroed_runs)
    obs = log.obs
    if obs.run_of_row is not None:
        train = split_at_run(obs.run_of_row, train_fraction)
    else:
        train = np.arange(obs.n) < int(train_fraction * obs.n)
    options = SearchOptions(add, auto, min_reduction, model_terms,
                            structure_length_m, component)
    if walk_forward_period:
        from .check_walk import walk_forward_of_log, walk_periods_of_log

        # A period that leaves too little to walk is refused before any search.
        periods = walk_periods_of_log(log, period_s)
    searched = search_log(log, train, options)
    result = _log_result(path, log, searched)
    if walk_forward_period:
        result.log.walk_forward = walk_forward_of_log(log, periods, walk_forward_period,
                                                      options, progress)
    return result


@dataclasses.dataclass(frozen=True)
class SearchOptions:
    """What the user asked the search of a log: the effects to add first (``add``), how
    many the selection may add (``auto``), its least CV reduction, the starting model's
    terms, the structure's length for the physics bounds [m] (None: the default) and the
    measured component."""

    add: list[str]
    auto: int
    min_reduction: float
    model_terms: list[str]
    structure_length_m: float | None
    component: str


@dataclasses.dataclass
class LogSearched:
    """A log's search done on its training rows: the search's frame, its progress (the
    model), the starting and empty models, the forward blocks and the contest of whole
    models (best first) with each one's pooled forward error [m]."""

    search: _LogSearch
    progress: _Progress
    start_model: object
    empty: object
    blocks: object
    contest: list[ContestEntry]
    forward: dict[str, float]
    options: SearchOptions


def search_log(log: LogData, train: np.ndarray, options: SearchOptions) -> LogSearched:
    """The model of a log made from its ``train`` rows (N,) bool alone: the starting terms,
    the effects asked for, the selection's steps, the contest of whole models (forward and
    across the training rows' regimes). What it decides is said in ``log.notes``.

    Raises
    ------
    InputDataError
        Fewer than 8 training rows without runs.
    """
    from ..core.workbench.diagnosis import add_effect, diagnose, residual_frame
    from ..core.workbench.log_runs import run_blocks
    from ..core.workbench.regimes import find_regimes
    from ..core.workbench.thermal_log import DEFAULT_STRUCTURE_LENGTH_M, log_model
    from .check import candidate_named

    obs, run_names = log.obs, log.run_names
    runs = obs.run_of_row is not None
    training = obs.subset(np.flatnonzero(train))
    blocks = run_blocks(training.run_of_row, MAX_BLOCKS) if runs else None
    if blocks is not None and blocks[-1] < 1:
        blocks = None
    empty = model = log_model(obs, options.structure_length_m or DEFAULT_STRUCTURE_LENGTH_M)
    if runs and blocks is None:
        log.notes.append("one training run: forward validation cuts it into blocks of rows")
    folds = min(5, training.n // 4)
    if blocks is None and folds < 2:
        raise InputDataError(f"{training.n} training rows (of {obs.n}): the selection needs "
                             "at least 8")
    c = "xyz".index(options.component)
    structure = sorted(n for n, v in training.temperatures.items()
                       if np.ptp(v) > 1e-3)
    family_list = _log_families(training, structure, training.measured_m[:, c])

    def diagnosis_of(current):
        return diagnose(current, training, min_reduction=options.min_reduction, forward=True,
                        folds=folds, blocks=blocks, family_list=family_list)

    for name in options.model_terms:   # the starting model's terms, on the training rows
        model = add_effect(model, candidate_named(diagnosis_of(model), name, "start with",
                                                  "log"), training)
    fit_rows, judge_rows = _validation_split(training, blocks)
    validation_blocks = blocks if blocks is not None else \
        np.repeat(np.arange(MAX_BLOCKS), -(-training.n // MAX_BLOCKS))[:training.n]
    judged_runs = sorted({run_names[k] for k in training.run_of_row[judge_rows]},
                         key=run_names.index) if runs else []
    judged_what = (f"run{'s' if len(judged_runs) > 1 else ''} {', '.join(judged_runs)}"
                   if runs else f"the last {int(judge_rows.sum())} training rows")
    regimes = find_regimes(training.time_s, training.temperatures, training.run_of_row,
                           [run_names[k] for k in np.unique(training.run_of_row)]
                           if runs else None, training.spindle_speed_rad_s)
    search = _LogSearch(obs, train, training, residual_frame(model, training), c, fit_rows,
                        judge_rows, judged_what, log.unit, log.to_unit,
                        {f.name: f for f in family_list}, diagnosis_of, regimes)
    progress = _step_by_step(search, model, options.add, options.auto, options.min_reduction)
    contest, forward = _contest(search, progress, progress.first, model, blocks,
                                validation_blocks, bool(options.auto and not options.add),
                                log.notes)
    return LogSearched(search, progress, model, empty, blocks, contest, forward, options)


def extrapolation_lines(log: LogData, obs, train: np.ndarray) -> tuple[str, str]:
    """(the regimes the held-out rows hold that the training rows never held, the sensors
    read beyond their training range there), each "" when there is none: why a model may
    predict the held-out rows worse than it predicted its training rows."""
    from ..core.workbench.regimes import find_regimes, sensors_leaving_range

    rows = log.file_rows if log.file_rows is not None and len(log.file_rows) == obs.n \
        else None
    regimes = find_regimes(obs.time_s, obs.temperatures, obs.run_of_row, log.run_names,
                           obs.spindle_speed_rad_s)
    held = ~train
    parts = []
    for what, part in (("", "trend"), ("spindle programs ", "program")):
        trained = regimes.labels_in(train, part)
        new = [k for k in regimes.labels_in(held, part) if k not in trained]
        if not new:
            continue
        where = [f"{s.kind} {s.rows_text(rows)}" for s in regimes.stretches
                 if held[s.start:s.stop].any() and getattr(s, part) in new]
        parts.append(f"{what}{', '.join(new)} ({', '.join(where[:2])}), which the training "
                     f"rows never held (they held {', '.join(trained)})")
    regime_line = ("the held-out rows hold " + "; and ".join(parts)) if parts else ""
    leaving = sensors_leaving_range(obs.temperatures, train, held)
    sensor_line = ("on the held-out rows " + "; ".join(e.text() for e in leaving[:3])
                   if leaving else "")
    return regime_line, sensor_line


def physics_bound_line(not_added: list[NotAdded]) -> str:
    """The first least-squares fit on sensors the physics bound refused, in words with the
    mend (``--structure-length``), or "": why least squares on every input may beat the
    model held out while the model could not be it."""
    bounded = next((e for e in not_added if e.name.startswith("sensor_least_squares") and
                    e.test.startswith("physics refuses its fit (")), None)
    if bounded is None:
        return ""
    # "physics refuses its fit (WHY)": WHY alone.
    reason = bounded.test[len("physics refuses its fit ("):-1]
    return (f"{bounded.name} was refused by the physics bound ({reason}): if the structure "
            "between the sensors and the tool is longer than the bound assumes, give "
            "--structure-length METRES")


def _log_result(path: Path, log: LogData, searched: LogSearched) -> CheckResult:
    """The large gains not added, the held-out figures and the result of a thermal log's
    check (its search done: :func:`search_log`)."""
    from ..core.workbench.thermal_log import (all_inputs_least_squares_residual,
                                              held_out_residual, held_out_rmse)
    from .check import _model_yaml, error_figures

    search, progress, start_model, empty = searched.search, searched.progress, \
        searched.start_model, searched.empty
    contest, forward = searched.contest, searched.forward
    auto, min_reduction = searched.options.auto, searched.options.min_reduction
    obs, train, first, to_unit, unit = search.obs, search.train, progress.first, log.to_unit, \
        log.unit
    notes, warnings, not_added, refusals = log.notes, progress.warnings, progress.not_added, \
        progress.refusals
    steps, model = progress.steps, progress.model
    added = [name for s in steps for name in s.added or []]
    # Every large CV gain not added, with the test that refused it and its numbers.
    for entry in large_gains_not_added(first, progress.diagnosis, added,
                                       {e.name for e in not_added}, auto, min_reduction,
                                       room=12 - len(not_added)):
        not_added.append(entry)
        refusals.append(f"not added: {entry.name} (CV {100 * entry.cv_reduction:.0f} % "
                        f"better) - {entry.test}")
    constant = held_out_rmse(empty, obs, train)
    judge = ~train
    before_residual = held_out_residual(start_model, obs, train)
    after_residual = held_out_residual(model, obs, train)
    squares_residual = all_inputs_least_squares_residual(obs, train)
    squares = float(np.sqrt(np.mean(squares_residual[judge] ** 2)))
    final = steps[-1].held_out_rmse
    regime_line, sensor_line = extrapolation_lines(log, obs, train)
    chosen = next(entry for entry in contest if entry.chosen)
    if regime_line:
        notes.append(f"{regime_line}: the model is judged on a regime it was not fitted on "
                     f"(its inputs leave their training range by {chosen.held_out_range_excess:.2g}"
                     " of its span there)" + (f"; {sensor_line}" if sensor_line else ""))
    bound_line = physics_bound_line(not_added)
    why = "; ".join(x for x in (regime_line, sensor_line, bound_line) if x) or \
        "no regime the training rows lacked and no sensor beyond its training range explain it"
    if final > constant:
        warnings.append(f"warning: the model's held-out RMSE {final * to_unit:.4g} {unit} is "
                        f"worse than a constant's ({constant * to_unit:.4g} {unit}) - {why}")
    if final > squares * (1.0 + 1e-9):
        warnings.append(f"warning: least squares on every input ({squares * to_unit:.4g} "
                        f"{unit}) beats the model ({final * to_unit:.4g} {unit}) held out - "
                        f"{why}")
    carried, carrier = _sensor_weights(first, steps, added, obs.temperatures)
    thermal = ThermalLog(
        target=log.target_column, target_unit=unit, target_unit_per_m=to_unit,
        component="xyz"[search.component], rows=obs.n, train_rows=int(train.sum()),
        decided_on=f"the training rows only; a term must also predict {search.judged_what} "
                   "from the training rows before them",
        figures_before_held_out_m=error_figures(before_residual[judge]),
        figures_after_held_out_m=error_figures(after_residual[judge]),
        held_out_baseline_rmse=steps[0].held_out_rmse, not_added=not_added,
        not_added_lines=refusals, constant_held_out_rmse=constant, notes=notes,
        step_by_step_added=next(e.terms for e in contest if e.name == "step by step"),
        model_contest_forward_rmse=forward,
        model_chosen=chosen.name, model_contest=contest,
        judged_on="held-out rows after the training rows, unseen by every decision",
        all_inputs_least_squares_held_out_rmse=squares,
        baselines_held_out_m={"constant": constant, "least squares on every input": squares,
                              "model": final},
        sensors_carrying_weight=carried, sensors_carrying_weight_of=carrier,
        zeroed_runs=obs.zeroed_runs)
    table, c = log.table, search.component
    result = CheckResult(
        kind="thermal_log", data=str(path), machine=model.machine.name, readings=obs.n,
        band=obs.uncertainty_m, baseline_rmse=first.baseline_rmse,
        baseline_cv_rmse=first.baseline_cv_rmse,
        ranking=[c_.as_dict() for c_ in first.ranking[:30]],
        named=[c_.as_dict() for c_ in first.selected], verdict=first.verdict(),
        localisation=first.localisation.as_dict() if first.localisation else {},
        added=added, final_rmse=final, steps=steps,
        final_diagnosis=progress.diagnosis.text(), final_verdict=progress.diagnosis.verdict(),
        model_yaml=_model_yaml(model),
        source=DataSource(rows_read=table.rows_read, rows_dropped=table.rows_dropped,
                          rows_note=table.summary()),
        log=thermal, warnings=warnings,
        validation=("forward by whole runs: each block of runs predicted by a fit on the "
                    "runs before it" if searched.blocks is not None else
                    "forward: each block predicted by a fit on the blocks before it"),
        plot={"time": obs.time_s, "target": obs.measured_m[:, c],
              "before": obs.measured_m[:, c] - before_residual,
              "after": obs.measured_m[:, c] - after_residual, "train": train,
              "unit_scale": to_unit, "unit": unit,
              "run_starts": None if obs.run_starts is None else obs.run_starts,
              "run_names": log.run_names})
    if obs.run_of_row is not None:
        residuals = {"constant_rmse": held_out_residual(empty, obs, train),
                     "least_squares_rmse": squares_residual, "model_rmse": after_residual}
        result.runs = [RunFigures(**entry) for entry in
                       per_run_figures(log.run_names, obs.run_of_row, train, residuals)]
    return result
