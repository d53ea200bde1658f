"""Read a numeric CSV table (a data logger's export) and account for every row.

Header row of column names, then one row per reading. A row with the wrong
number of fields is an error naming the row (the file is damaged or not
what it is said to be); a row with a non-numeric, NaN or infinite cell is
dropped and *counted*, with the first few reasons, so a user sees what
was left out.

The separator, decimal mark and encoding are the logger's (:mod:`.csv_dialect`): a
``;``-separated export with decimal commas reads as a comma-separated one. A time
column may hold date-times (read as seconds).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import InputDataError
from .csv_dialect import (CsvDialect, across_midnights, cell_kind, header_row, sniff_dialect,
                          table_rows, time_of_day, to_number, to_seconds)

#: Reasons kept for the report (the count covers all of them).
KEPT_REASONS = 5


@dataclass
class CsvTable:
    """Columns of the kept rows, and what was dropped."""

    path: Path
    columns: dict[str, np.ndarray]
    rows_read: int
    rows_dropped: int = 0
    drop_reasons: list[str] = field(default_factory=list)
    #: (N,) the data row (1-based, the header not counted) of each kept row.
    data_rows: np.ndarray | None = None
    #: Missing values kept as NaN per gap column (see :func:`read_csv_table`).
    gaps: dict[str, int] = field(default_factory=dict)
    #: (kept row index, column, reason) of each missing value of a gap column.
    gap_reasons: list[tuple[int, str, str]] = field(default_factory=list)
    #: How the file was written (separator, decimal mark, encoding).
    dialect: CsvDialect = field(default_factory=CsvDialect)
    #: Time columns whose cells were date-times (their values are POSIX seconds), or
    #: times of day without a date (seconds since the first midnight: ``clock_columns``).
    date_time_columns: tuple[str, ...] = ()
    clock_columns: tuple[str, ...] = ()
    #: Column -> unit, from a row of units under the header (a logger's export), if any.
    units: dict[str, str] = field(default_factory=dict)
    #: Dropped rows a reason of :attr:`drop_reasons` names: the others are the "..." the
    #: summary says (None: one row a reason).
    rows_explained: int | None = None

    def drop_rows(self, count: int, reason: str) -> None:
        """Count ``count`` more rows as dropped, all for ``reason`` (the caller leaves them
        out)."""
        explained = len(self.drop_reasons) if self.rows_explained is None \
            else self.rows_explained
        self.rows_dropped += int(count)
        self.drop_reasons.append(reason)
        self.rows_explained = explained + int(count)

    def drop_gaps_of(self, columns: set[str]) -> None:
        """Count the rows with a missing value in ``columns`` as dropped, with reasons (the
        caller leaves them out)."""
        rows: dict[int, str] = {}
        for row, column, reason in self.gap_reasons:
            if column in columns:
                rows.setdefault(row, reason)
        self.rows_dropped += len(rows)
        kept = sorted(rows)[:max(0, KEPT_REASONS - len(self.drop_reasons))]
        if self.rows_explained is not None:
            self.rows_explained += len(kept)
        for row in kept:
            self.drop_reasons.append(rows[row])

    @property
    def names(self) -> list[str]:
        return list(self.columns)

    def summary(self) -> str:
        """One line: rows kept, and why any were dropped."""
        kept = self.rows_read - self.rows_dropped
        text = f"{self.path.name}: {kept} of {self.rows_read} rows used"
        if self.dialect.note():
            text += f" ({self.dialect.note()})"
        if self.rows_dropped:
            text += f"; {self.rows_dropped} dropped ({'; '.join(self.drop_reasons)}"
            explained = len(self.drop_reasons) if self.rows_explained is None \
                else self.rows_explained
            text += ", ...)" if self.rows_dropped > explained else ")"
        return text


def joined_columns(name: str, header: list[str]) -> list[str]:
    """The columns a time column named ``DATE+TIME`` joins (each in ``header``), or []
    when ``name`` is a column itself or names no such pair."""
    parts = [p.strip() for p in name.split("+")]
    if name in header or len(parts) < 2 or not all(p in header for p in parts):
        return []
    return parts


def read_csv_table(path: str | Path, *, min_rows: int = 2,
                   text_columns: tuple[str, ...] = (),
                   gap_columns: tuple[str, ...] = (),
                   time_columns: tuple[str, ...] = (),
                   keep_reasons: int = KEPT_REASONS) -> CsvTable:
    """Read ``path``; raises :class:`InputDataError` naming the row or column at fault.

    ``text_columns`` are kept as text (a run's name: ``day3``, ``2024-05-01``); an empty
    cell there drops its row like a missing number. ``gap_columns`` keep their rows when a
    cell is missing, non-numeric or not finite (a dead thermocouple): the value is NaN,
    and the caller decides (``CsvTable.gaps`` counts them per column). Every column
    carries the data row (``CsvTable.data_rows``, 1-based after the header) its values
    came from. ``time_columns`` take numbers or date-times (POSIX seconds), not a mix; a
    name ``DATE+TIME`` of two columns joins their cells into one date-time column (the
    two kept as text)."""
    path = Path(path)
    dialect = sniff_dialect(path)
    rows = list(table_rows(path, dialect))
    if not rows:
        raise InputDataError(f"{path}: empty file")
    header = [name.strip() for name in rows[0]]
    if len(set(header)) != len(header) or any(not name for name in header):
        raise InputDataError(f"{path}: the header needs unique, non-empty column names")
    missing = [name for name in text_columns if name not in header]
    if missing:
        raise InputDataError(f"{path}: no column {missing[0]!r}; have {', '.join(header)}")
    values, dropped, reasons, kept_rows, gaps, gap_reasons = [], 0, [], [], {}, []
    units = _units_row(rows[1], header, text_columns, dialect) if len(rows) > 1 else {}
    start = 3 if units else 2          # the file's row number of the first data row
    # A time column is read as numbers or, when its first cell is none, as date-times.
    first = rows[start - 1] if len(rows) > start - 1 and \
        len(rows[start - 1]) == len(header) else None
    kinds = {name: cell_kind(first[header.index(name)], dialect) for name in time_columns
             if name in header and first is not None}
    dated = tuple(name for name, kind in kinds.items() if kind in ("date-time", "clock"))
    # A clock without a date (HH:MM:SS): seconds since midnight, days counted below.
    clocked = tuple(name for name, kind in kinds.items() if kind == "clock")
    # A date and a time of day in two columns ("Datum+Uhrzeit"): one date-time column.
    joined = {name: [header.index(p) for p in joined_columns(name, header)]
              for name in time_columns if joined_columns(name, header)}
    parts = {header[j] for indices in joined.values() for j in indices}
    for number, row in enumerate(rows[start - 1:], start=start):
        if len(row) != len(header):
            raise InputDataError(f"{path}: row {number} has {len(row)} fields, the header "
                                 f"{len(header)}")
        parsed, problem = [], ""
        for name, indices in joined.items():
            cell = " ".join(row[j].strip() for j in indices)
            try:
                parsed.append(to_seconds(cell))
            except ValueError:
                problem = f"row {number} column {name}: {cell[:30]!r} is not a date-time"
                break
        for name, cell in zip(header, row):
            if problem:
                break
            if name in text_columns or name in parts:
                if not cell.strip():
                    problem = f"row {number} column {name}: empty"
                    break
                parsed.append(cell.strip())
                continue
            if name in dated:
                try:
                    parsed.append(time_of_day(cell) if name in clocked else to_seconds(cell))
                except ValueError:
                    problem = f"row {number} column {name}: {cell.strip()[:30]!r} is not a " \
                        "date-time like the first row's"
                    break
                continue
            if name in gap_columns:
                try:
                    value = to_number(cell, dialect)
                except ValueError:
                    value = math.nan
                if not math.isfinite(value):
                    gaps[name] = gaps.get(name, 0) + 1
                    why = "is not a number" if math.isnan(value) and \
                        cell.strip().lower() != "nan" else "is not finite"
                    gap_reasons.append((len(values), name, f"row {number} column {name}: "
                                        f"{cell.strip()[:20]!r} {why}" if why.endswith("number")
                                        else f"row {number} column {name}: {cell.strip()} {why}"))
                    value = math.nan
                parsed.append(value)
                continue
            try:
                value = to_number(cell, dialect)
            except ValueError:
                problem = f"row {number} column {name}: {cell.strip()[:20]!r} is not a number"
                break
            if not math.isfinite(value):
                problem = f"row {number} column {name}: {cell.strip()} is not finite"
                break
            parsed.append(value)
        if problem:
            dropped += 1
            if len(reasons) < keep_reasons:
                reasons.append(problem)
            continue
        values.append(parsed)
        kept_rows.append(number - start + 1)
    if len(values) < min_rows:
        raise InputDataError(f"{path}: {len(values)} usable rows; at least {min_rows} needed"
                             + (f" ({reasons[0]})" if reasons else ""))
    columns = {}
    for k, name in enumerate(joined):
        columns[name] = np.asarray([row[k] for row in values], dtype=np.float64)
    for j, name in enumerate(header, start=len(joined)):
        cells = [row[j] for row in values]
        columns[name] = np.asarray(cells, dtype=object if name in text_columns or
                                   name in parts else np.float64)
        if name in clocked:
            columns[name] = across_midnights(columns[name])
    return CsvTable(path, columns, rows_read=len(rows) - start + 1, rows_dropped=dropped,
                    drop_reasons=reasons, data_rows=np.asarray(kept_rows, dtype=np.intp),
                    gaps=gaps, gap_reasons=gap_reasons, dialect=dialect,
                    date_time_columns=dated + tuple(joined), clock_columns=clocked,
                    units=units)


def _units_row(row: list[str], header: list[str], text_columns: tuple[str, ...],
               dialect: CsvDialect) -> dict[str, str]:
    """Column -> unit when ``row`` (the one under the header) is a row of units: no cell a
    number or a date-time, and one at least a unit this package knows. Else {}."""
    from .column_map import TEMPERATURE, UNIT_SPELLINGS, UNITS

    if len(row) != len(header):
        return {}
    known = set(TEMPERATURE) | set(UNIT_SPELLINGS) | {u for table in UNITS.values()
                                                      for u in table if u}
    cells = {name: cell.strip().strip("[]()").strip() for name, cell in zip(header, row)
             if name not in text_columns}
    if any(cell_kind(cell, dialect) for cell in cells.values() if cell):
        return {}
    if not any(cell in known for cell in cells.values()):
        return {}
    return {name: cell for name, cell in cells.items() if cell}


def csv_header(path: str | Path) -> list[str]:
    """The column names of a CSV's first non-empty row (errors as :func:`read_csv_table`)."""
    return header_row(path)
