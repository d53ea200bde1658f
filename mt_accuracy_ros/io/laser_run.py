"""A laser interferometer's positioning run (ISO 230-2) from a CSV file.

One row per reading, in the order measured. Which column is what, and in which
unit, comes from ``ROLE=COLUMN[:UNIT]`` (as ``mt-accuracy check --col``) or is read
off the header (``target_mm``, ``deviation_um``, ``actual_mm``, ``direction``,
``run``, ``temperature_C``):

======================  ==============================================  ==========
role                    meaning                                         unit
======================  ==============================================  ==========
``target``              target position P_i                             length
``measured``            actual position (deviation = measured - target) length
``deviation``           positional deviation x_ij (instead of measured) length
``direction``           approach: +1 / -1, or as instruments write it   -
                        (``+``/``-``, ``up``/``down``, ``fwd``/``bwd``,
                        ``forward``/``backward``, ``↑``/``↓``)
``run``                 run j: a number or a name                       -
``temperature``         the material (scale) temperature                temperature
======================  ==============================================  ==========

A header names its unit as the survey map's units do: ``target_mm``, ``target [mm]``,
``Target (mm)``, ``deviation_µm``, ``temperature [degF]`` (or a units row under the
header, or ``--col ROLE=COLUMN:UNIT``). A length or temperature column whose unit none of
these gives is refused, naming the column and how to give it: no unit is assumed.
Targets that span an implausible travel (under 1 mm: metres written as mm) and deviations
of an implausible size or spread (under 10 nm over the run: millimetres written as µm)
are refused naming the unit they look like (:mod:`~..core.inputs.plausibility`).

A row whose cell in a read column is not a finite number (``nan``, ``inf``, text,
empty), or whose direction is no direction, is refused in one line naming its row as an
editor numbers it (the header is row 1), its column and its value: a positioning run
needs every reading. Runs are numbered as the file calls them (a numbered run column's
numbers; else 1, 2, ... in the order the file reaches them).

Without a direction column, each reading's approach is the sign of the move that
brought the axis to its target (a target read twice in a row at a turnaround: the
second reading is the way back). Without a run column, a run is one sweep each way (a new
one starts where the approach turns from down to up). Everything is converted to SI.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import re

from ..core.errors import InputDataError
from ..core.inputs.plausibility import check_plausible
from .column_map import UNIT_SPELLINGS, si_scale, unit_from_name
from .csv_table import csv_header, read_csv_table

#: Reasons the one-line rows note carries (``LaserRun.refused`` holds every one).
SUMMARY_REASONS = 3

ROLES = ("target", "measured", "deviation", "direction", "run", "temperature")
#: The unit a refusal proposes for a role's column (what laser software writes).
EXAMPLE_UNIT = {"target": "mm", "measured": "mm", "deviation": "um", "temperature": "degC"}
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
    run: np.ndarray                # as the file numbers them (1, 2, ... for named runs)
    temperature_c: np.ndarray | None
    columns: dict[str, str] = field(default_factory=dict)
    rows_note: str = ""
    #: Rows dropped for a cell in a column no role reads: "row N column C: why".
    refused: list[str] = field(default_factory=list)
    #: role -> the unit its column was read in (the flag's, the header's or a units row's).
    units: dict[str, str] = field(default_factory=dict)

    def units_note(self) -> str:
        """What the run was read in: ``units: target 'target_mm' in mm, ...``."""
        return "units: " + ", ".join(f"{role} {self.columns[role]!r} in {unit}"
                                     for role, unit in self.units.items())


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


def _quantity(role: str) -> str:
    return "temperature" if role == "temperature" else "length"


def _unit(role: str, column: str, unit: str, units_row: dict[str, str]) -> str:
    """The unit of ``role``'s column: the flag's, the header's (``target_mm``) or a units
    row's; refused naming the column when none gives one (none is assumed)."""
    unit = UNIT_SPELLINGS.get(unit, unit) or \
        UNIT_SPELLINGS.get(units_row.get(column, "").strip(), units_row.get(column, "").strip())
    if not unit:
        example = EXAMPLE_UNIT[role]
        raise InputDataError(f"{role} column {column!r} has no unit: give it in the header "
                             f"({column}_{example}, {column} [{example}]) or the flag (--col "
                             f"{role}={column}:{example})")
    si_scale(_quantity(role), unit, f"{role} column {column!r}")
    return unit


#: What a direction refusal lists as the accepted forms.
DIRECTION_FORMS = "+/-, up/down, fwd/bwd, forward/backward, ↑/↓, +1/-1"


def _refuse_bad_rows(path: Path, table, roles: dict[str, tuple[str, str]]) -> None:
    """One line for the first row (as an editor numbers it) whose cell in a read column
    is not a finite number or, in the direction column, no direction: a positioning run
    needs every reading, and a dropped one only surfaces later as a gap in some run."""
    read = [column for column, _ in roles.values()]
    bad = [(int(re.match(r"row (\d+)", reason).group(1)), reason)
           for reason in table.drop_reasons
           if any(f" column {column}: " in reason for column in read)]
    if "direction" in roles:
        column = roles["direction"][0]
        # data_rows count from the first data row: the file's row adds the header (and a
        # units row under it).
        first_row = 2 if table.units else 1
        bad += [(int(table.data_rows[k]) + first_row,
                 f"row {int(table.data_rows[k]) + first_row} column {column}: "
                 f"{str(cell)[:20]!r} is not a direction ({DIRECTION_FORMS})")
                for k, cell in enumerate(table.columns[column])
                if direction_of(str(cell)) is None][:1]
    if bad:
        raise InputDataError(f"{Path(path).name}: {min(bad)[1]}; a positioning run needs "
                             "every reading: correct or delete the row")


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


def run_numbers(labels: list[str]) -> np.ndarray:
    """Each reading's run as the file numbers it: whole numbers as written, names (or
    numbers that are not whole) 1, 2, ... in the order the file first reaches them."""
    try:
        numbers = [float(label) for label in labels]
        if all(n.is_integer() for n in numbers):
            return np.array(numbers, dtype=np.int64)
    except ValueError:
        pass
    order = {label: k + 1 for k, label in enumerate(dict.fromkeys(labels))}
    return np.array([order[label] for label in labels], dtype=np.int64)


def _mend(role: str, column: str) -> str:
    return f"give the column's unit (--col {role}={column}:UNIT, or {column}_UNIT in the header)"


def _refuse_implausible(roles: dict[str, tuple[str, str]], units: dict[str, str],
                        raw) -> None:
    """One line when targets, positions, deviations or temperatures are implausible in
    their declared unit (a 0.5 mm travel, a deviation of metres, 300 degC of steel)."""
    checks = {"target": ("position", "travel"), "measured": ("position",),
              "deviation": ("error",), "temperature": ("temperature",)}
    for role, quantities in checks.items():
        if role not in roles:
            continue
        for quantity in quantities:
            check_plausible(raw(role), quantity, units[role],
                            f"{role} column {roles[role][0]!r}", _mend(role, roles[role][0]),
                            error=InputDataError)


def read_laser_run(path: str | Path, flags: list[str] | None = None, *,
                   resolution_m: float = 1e-6) -> LaserRun:
    """Read ``path`` (see the module docstring); raises :class:`InputDataError` naming
    the column or role at fault."""
    names = csv_header(path)
    roles: dict[str, tuple[str, str]] = {}
    for flag in flags or []:
        role, column, unit = _split_flag(flag)
        roles[role] = (column, unit or (unit_from_name(column, _quantity(role))
                                        if role in EXAMPLE_UNIT else ""))
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
    units = {role: _unit(role, column, unit, table.units) for role, (column, unit)
             in roles.items() if role in EXAMPLE_UNIT}
    _refuse_bad_rows(path, table, roles)
    # Rows dropped for a column no role reads are named, not refused.
    refused = list(table.drop_reasons)
    table.drop_reasons = refused[:SUMMARY_REASONS]

    def raw(role):
        return np.asarray(table.columns[roles[role][0]], dtype=np.float64)

    def values(role):
        scale, offset = si_scale(_quantity(role), units[role], role)
        return raw(role) * scale + offset

    _refuse_implausible(roles, units, raw)
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
    which = "deviation" if "deviation" in roles else "measured"
    # The deviations' spread in the unit their column declares (measured - target
    # differences in the measured column's).
    check_plausible(deviation / si_scale("length", units[which], which)[0], "deviation_spread",
                    units[which], f"{which} column {roles[which][0]!r}",
                    _mend(which, roles[which][0]), error=InputDataError)
    if "direction" in roles:
        direction = np.array([direction_of(str(cell)) for cell in
                              table.columns[roles["direction"][0]]], dtype=np.float64)
    else:
        direction = infer_directions(target)
    if "run" in roles:
        run = run_numbers([str(cell).strip() for cell in table.columns[roles["run"][0]]])
    else:
        run = infer_runs(direction) + 1
    temperature = values("temperature") if "temperature" in roles else None
    return LaserRun(target, deviation, direction, np.asarray(run, dtype=np.int64), temperature,
                    {role: column for role, (column, _) in roles.items()}, table.summary(),
                    refused, units)
