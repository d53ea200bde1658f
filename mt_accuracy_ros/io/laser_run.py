"""A laser interferometer's positioning run (ISO 230-2) from a CSV file.

One row per reading, in the order measured. Which column is what, and in which
unit, comes from ``ROLE=COLUMN[:UNIT]`` (as ``mt-accuracy check --col``) or is read
off the header (``target_mm``, ``deviation_um``, ``actual_mm``, ``direction``,
``run``, ``temperature_C``):

======================  ==============================================  ==========
role                    meaning                                         default unit
======================  ==============================================  ==========
``target``              target position P_i                             mm
``measured``            actual position (deviation = measured - target) mm
``deviation``           positional deviation x_ij (instead of measured) um
``direction``           approach: +1 / -1, or as instruments write it   -
                        (``+``/``-``, ``up``/``down``, ``fwd``/``bwd``,
                        ``forward``/``backward``, ``↑``/``↓``)
``run``                 run j: a number or a name                       -
``temperature``         the material (scale) temperature                degC
======================  ==============================================  ==========

A header names its unit as the survey map's units do: ``target_mm``, ``target [mm]``,
``Target (mm)``, ``deviation_µm``, ``temperature [degF]``. A row whose cell is not a
number, or whose direction is no direction, is refused and named with its reason (every
one, ``LaserRun.refused``).

Without a direction column, each reading's approach is the sign of the move that
brought the axis to its target (a target read twice in a row at a turnaround: the
second reading is the way back). Without a run column, a run is one sweep each way (a new
one starts where the approach turns from down to up). Everything is converted to SI.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import InputDataError
import re

from .column_map import si_scale
from .csv_table import csv_header, read_csv_table

#: Reasons the one-line rows note carries (``LaserRun.refused`` holds every one).
SUMMARY_REASONS = 3

ROLES = ("target", "measured", "deviation", "direction", "run", "temperature")
DEFAULT_UNIT = {"target": "mm", "measured": "mm", "deviation": "um", "temperature": "degC"}
#: Header names tried for a role when no flag names its column (lower case, unit
#: suffix allowed: ``target_mm``, ``deviation_um``).
GUESSES = {"target": ("target", "nominal", "position"),
           "measured": ("measured", "actual"),
           "deviation": ("deviation", "error", "dev"),
           "direction": ("direction", "dir"), "run": ("run", "cycle"),
           "temperature": ("temperature", "temp", "material_temperature")}


@dataclass
class LaserRun:
    """The readings of one axis' runs, SI, in measured order."""

    target_m: np.ndarray
    deviation_m: np.ndarray
    direction: np.ndarray          # +1 / -1
    run: np.ndarray                # 0, 1, ...
    temperature_c: np.ndarray | None
    columns: dict[str, str] = field(default_factory=dict)
    rows_note: str = ""
    #: Every refused row: "row N column C: why".
    refused: list[str] = field(default_factory=list)


#: How instruments write an approach direction (lower case; numbers by their sign).
DIRECTION_WORDS = {"+": 1.0, "up": 1.0, "fwd": 1.0, "forward": 1.0, "↑": 1.0, "pos": 1.0,
                   "positive": 1.0, "-": -1.0, "down": -1.0, "bwd": -1.0, "backward": -1.0,
                   "back": -1.0, "↓": -1.0, "neg": -1.0, "negative": -1.0}


def direction_of(cell: str) -> float | None:
    """+1 / -1 for a direction as written (a word, an arrow, a signed number), or None."""
    text = cell.strip().lower()
    if text in DIRECTION_WORDS:
        return DIRECTION_WORDS[text]
    try:
        value = float(text)
    except ValueError:
        return None
    return float(np.sign(value)) if np.isfinite(value) and value != 0 else None


def header_unit(name: str) -> tuple[str, str]:
    """(base, unit) of a header: ``target_mm``, ``target [mm]``, ``Target (mm)`` -> (target,
    mm); without a unit -> (name, "")."""
    found = re.fullmatch(r"\s*(.+?)\s*[\[(]\s*([^\])]+?)\s*[\])]\s*", name)
    if found:
        return found.group(1), found.group(2)
    base, _, suffix = name.rpartition("_") if "_" in name else (name, "", "")
    return (base, suffix) if base else (name, "")


def _split_flag(flag: str) -> tuple[str, str, str]:
    role, sep, rest = flag.partition("=")
    if not sep or not rest or role.strip() not in ROLES:
        raise InputDataError(f"--col {flag!r}: expected ROLE=COLUMN[:UNIT] with ROLE one of "
                             f"{', '.join(ROLES)}")
    column, _, unit = rest.rpartition(":") if ":" in rest else (rest, "", "")
    return role.strip(), column.strip(), unit.strip()


def _guess(role: str, names: list[str]) -> tuple[str, str] | None:
    for name in names:
        base, suffix = header_unit(name)
        for candidate in GUESSES[role]:
            if name.lower() == candidate:
                return name, ""
            if base.lower() == candidate:
                return name, suffix
    return None


def _scale(role: str, unit: str, column: str) -> tuple[float, float]:
    quantity = "temperature" if role == "temperature" else "length"
    return si_scale(quantity, unit or DEFAULT_UNIT[role], f"{role} column {column!r}")


def infer_directions(target: np.ndarray) -> np.ndarray:
    """The approach of each reading: the sign of the move that brought the axis there;
    a target read twice in a row is a turnaround (the second reading is the way back)."""
    steps = np.sign(np.diff(target))
    direction = np.empty(target.size)
    if target.size == 0:
        return direction
    nonzero = steps[steps != 0]
    direction[0] = nonzero[0] if nonzero.size else 1.0
    for k in range(1, target.size):
        direction[k] = steps[k - 1] if steps[k - 1] != 0 else -direction[k - 1]
    return direction


def infer_runs(direction: np.ndarray) -> np.ndarray:
    """Run j of each reading: a run is one sweep each way, so a new one starts whenever
    the approach turns from down to up (a reading missing from a sweep then stays a gap
    of that run, not a shift of every later one)."""
    turns = np.concatenate(([0], (direction[1:] > 0) & (direction[:-1] < 0)))
    return np.cumsum(turns).astype(np.int64)


def read_laser_run(path: str | Path, flags: list[str] | None = None, *,
                   resolution_m: float = 1e-6) -> LaserRun:
    """Read ``path`` (see the module docstring); raises :class:`InputDataError` naming
    the column or role at fault."""
    names = csv_header(path)
    roles: dict[str, tuple[str, str]] = {}
    for flag in flags or []:
        role, column, unit = _split_flag(flag)
        roles[role] = (column, unit)
    for role in ROLES:
        if role not in roles and not (role == "deviation" and "measured" in roles) and \
                not (role == "measured" and "deviation" in roles):
            guess = _guess(role, names)
            if guess is not None:
                roles[role] = guess
    if "measured" in roles and "deviation" in roles:
        # The header had both: the deviation column is the one read.
        if not any(f.startswith("measured=") for f in flags or []):
            del roles["measured"]
    for role, (column, _) in roles.items():
        if column not in names:
            raise InputDataError(f"{role}: no column {column!r}; columns: {', '.join(names)}")
    if "target" not in roles or not ({"measured", "deviation"} & set(roles)):
        raise InputDataError(f"{Path(path).name}: need a target column and a measured-position "
                             f"or deviation column (--col target=COLUMN:mm --col "
                             f"deviation=COLUMN:um); columns: {', '.join(names)}")
    text = tuple(roles[r][0] for r in ("direction", "run") if r in roles)
    table = read_csv_table(path, text_columns=text, keep_reasons=10 ** 9)
    refused = list(table.drop_reasons)
    table.drop_reasons = refused[:SUMMARY_REASONS]
    if "direction" in roles:
        column = roles["direction"][0]
        read = [direction_of(str(cell)) for cell in table.columns[column]]
        bad = [k for k, d in enumerate(read) if d is None]
        for k in bad:
            refused.append(f"row {int(table.data_rows[k]) + 1} column {column}: "
                           f"{str(table.columns[column][k])[:20]!r} is not a direction (+/-, "
                           "up/down, fwd/bwd, forward/backward, ↑/↓, +1/-1)")
        keep = np.array([d is not None for d in read], dtype=bool)
        if not keep.any():
            raise InputDataError(f"direction column {column!r}: no row has a direction (+/-, "
                                 "up/down, fwd/bwd, forward/backward, ↑/↓, +1/-1)")
        table.columns = {name: values[keep] for name, values in table.columns.items()}
        table.data_rows = table.data_rows[keep]
        table.rows_dropped += len(bad)
        table.drop_reasons = refused[:SUMMARY_REASONS]

    def values(role):
        column, unit = roles[role]
        scale, offset = _scale(role, unit, column)
        return np.asarray(table.columns[column], dtype=np.float64) * scale + offset

    target = values("target")
    if "deviation" in roles:
        deviation = values("deviation")
    else:
        deviation = values("measured") - target
    # Mixed units: deviations comparable to the target spacing are a unit slip (e.g. the
    # measured position in um against targets in mm), never a positioning error.
    spacing = np.median(np.diff(np.unique(np.round(target / resolution_m)))) * resolution_m \
        if np.unique(np.round(target / resolution_m)).size > 1 else 0.0
    if spacing > 0 and np.median(np.abs(deviation)) > 0.1 * spacing:
        which = "deviation" if "deviation" in roles else "measured"
        raise InputDataError(
            f"mixed units: the median |deviation| {np.median(np.abs(deviation)) * 1e3:.4g} mm "
            f"is over a tenth of the target spacing {spacing * 1e3:.4g} mm - check the units "
            f"of {roles['target'][0]!r} and {roles[which][0]!r} (COLUMN:UNIT)")
    if "direction" in roles:
        direction = np.array([direction_of(str(cell)) for cell in
                              table.columns[roles["direction"][0]]], dtype=np.float64)
    else:
        direction = infer_directions(target)
    if "run" in roles:
        # Runs by name or number, in the order the file first reaches them.
        labels = [str(cell).strip() for cell in table.columns[roles["run"][0]]]
        order = {label: k for k, label in enumerate(dict.fromkeys(labels))}
        run = np.array([order[label] for label in labels], dtype=np.int64)
    else:
        run = infer_runs(direction)
    temperature = values("temperature") if "temperature" in roles else None
    return LaserRun(target, deviation, direction, np.asarray(run, dtype=np.int64), temperature,
                    {role: column for role, (column, _) in roles.items()}, table.summary(),
                    refused)
