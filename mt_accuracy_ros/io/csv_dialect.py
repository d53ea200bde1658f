"""How a data logger wrote its CSV: the separator, the decimal mark, the encoding.

Shops export logs from spreadsheets and loggers set up in their own language: a
German or French export separates fields with ``;`` and writes ``20,35`` for
20.35; a logger may separate with tabs, start with a byte-order mark, or write
``°C`` in Windows-1252, or write a preamble (title, serial number) before the header.
Excel's "Unicode text" export is UTF-16 with a byte-order mark: it is read by that
mark (and said); UTF-16 without one is refused with the mend (save as UTF-8).
:func:`sniff_dialect` reads the first lines and says which; :func:`table_rows` then
yields the rows from the header on, and :func:`to_number` reads a cell.

Date-times in a time column (``2026-11-20 07:00:00``, ``2026-11-20T07:00:00Z``,
``20.11.2026 07:00:00``) are read by :func:`to_seconds` as seconds since the epoch
(a stamp without a zone is taken as UTC: only differences matter here).
"""
from __future__ import annotations

import csv
import re
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Iterator

import numpy as np

from ..core.errors import InputDataError
from ..core.inputs.file_kinds import bom_encoding, signature_kind

#: Bytes read to decide the dialect.
SNIFF_BYTES = 64 * 1024
#: Lines (after blank ones are skipped) whose field counts must agree.
SNIFF_LINES = 20
#: Lines a logger may write before the header (title, serial number, start time, ...).
MAX_PREAMBLE_LINES = 30
#: Separators tried, the usual first (it wins a tie).
SEPARATORS = (",", ";", "\t")
#: A number written with a decimal comma, nothing else in the cell.
DECIMAL_COMMA = re.compile(r"^\s*[+-]?\d*,\d+([eE][+-]?\d+)?\s*$")
#: What :meth:`CsvDialect.note` says of an encoding other than UTF-8.
ENCODING_NOTES = {"cp1252": "in Windows-1252 (not UTF-8)", "utf-16": "UTF-16 (BOM)",
                  "utf-32": "UTF-32 (BOM)"}
#: Date-time layouts beyond ISO 8601 (which :meth:`datetime.fromisoformat` reads).
#: (A date and a time joined by a dash is a printer's and a logger's script's way.)
DATE_TIME_LAYOUTS = ("%d.%m.%Y %H:%M:%S", "%d.%m.%Y %H:%M:%S.%f", "%d.%m.%Y %H:%M:%S,%f",
                     "%d.%m.%Y %H:%M", "%Y/%m/%d %H:%M:%S", "%Y/%m/%d %H:%M",
                     "%Y/%m/%d %H:%M:%S.%f", "%Y/%m/%d-%H:%M:%S", "%Y/%m/%d-%H:%M:%S.%f",
                     "%Y-%m-%d-%H:%M:%S", "%Y-%m-%d-%H:%M:%S.%f")


@dataclass(frozen=True)
class CsvDialect:
    """``delimiter`` between fields; ``decimal_comma``: numbers are written ``20,35``;
    ``encoding`` of the text (``utf-8-sig`` also reads a UTF-8 byte-order mark)."""

    delimiter: str = ","
    decimal_comma: bool = False
    encoding: str = "utf-8-sig"
    #: Non-empty lines before the header (a logger's preamble: title, serial number, ...).
    preamble_lines: int = 0

    def note(self) -> str:
        """One line for the output when the file is not a plain UTF-8, comma-separated CSV
        ("" when it is)."""
        parts = []
        if self.delimiter != ",":
            parts.append({";": "semicolon", "\t": "tab"}[self.delimiter] + "-separated")
        if self.decimal_comma:
            parts.append("with decimal commas")
        if self.encoding in ENCODING_NOTES:
            parts.append(ENCODING_NOTES[self.encoding])
        said = ["read as " + ", ".join(parts)] if parts else []
        if self.preamble_lines:
            said.append(f"{self.preamble_lines} line{'s' if self.preamble_lines > 1 else ''} "
                        "before the header skipped")
        return "; ".join(said)


def _decode_by_mark(path: Path, data: bytes, encoding: str, cut: bool) -> str:
    """``data`` decoded in the ``encoding`` its byte-order mark declares; ``cut``: the bytes
    are the file's first ones only (the last character may be incomplete)."""
    if cut and encoding != "utf-8-sig":
        unit = 4 if encoding == "utf-32" else 2
        data = data[:len(data) - len(data) % unit]
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        if cut and exc.start >= len(data) - 4:
            return data[:exc.start].decode(encoding)
        raise InputDataError(f"{path}: starts with a {ENCODING_NOTES.get(encoding, 'UTF-8')} "
                             f"byte-order mark but is not such text (byte {exc.start}); "
                             "save it as UTF-8 CSV") from exc


def _text(path: Path, size: int | None) -> tuple[str, str]:
    """The file's text (its first ``size`` bytes, or all) and the encoding that read it."""
    try:
        with open(path, "rb") as stream:
            data = stream.read() if size is None else stream.read(size)
    except OSError as exc:
        raise InputDataError(f"{path}: cannot read ({exc.strerror})") from exc
    kind = signature_kind(data)
    if kind:
        reader = "; `mt-accuracy check FILE` reads a bag (no --target, no column map)" \
            if kind == "an MCAP bag" else ""
        raise InputDataError(f"{path} is {kind}, not a CSV{reader}")
    # Only a read that filled its size may have stopped inside a character.
    cut = size is not None and len(data) >= size
    marked = bom_encoding(data)
    if marked:
        return _decode_by_mark(path, data, marked, cut), marked
    if b"\x00" in data:
        # UTF-16 without its mark shows as every other byte NUL: the mend is the same.
        raise InputDataError(f"{path}: not a text CSV file (it holds NUL bytes); a UTF-16 "
                             "export without a byte-order mark? save it as UTF-8 CSV")
    try:
        return data.decode("utf-8-sig"), "utf-8-sig"
    except UnicodeDecodeError as exc:
        if cut and exc.start >= len(data) - 4:
            # The sniffed bytes may end inside a character: decide on what came before.
            return data[:exc.start].decode("utf-8-sig"), "utf-8-sig"
    # Not UTF-8: a spreadsheet's Windows export. Every byte is a character in it, so a
    # file that is no text at all shows as such later, in its rows.
    return data.decode("cp1252", errors="replace"), "cp1252"


def sniff_dialect(path: str | Path) -> CsvDialect:
    """The dialect of ``path`` from its first lines: the header is the first line from
    which it and the next lines split into the same number (> 1) of fields (lines before
    it are a logger's preamble), by the separator that gives the most of them; decimal
    commas when the separator is not a comma and a data cell is a number written so."""
    path = Path(path)
    text, encoding = _text(path, SNIFF_BYTES)
    lines = [line for line in text.splitlines() if line.strip()]
    if len(text) >= SNIFF_BYTES and len(lines) > 1:
        lines = lines[:-1]          # the last line read may be cut short
    best, best_fields, start = ",", 1, 0
    for first in range(min(MAX_PREAMBLE_LINES + 1, max(1, len(lines) - 1))):
        window = lines[first:first + SNIFF_LINES]
        for separator in SEPARATORS:
            counts = {len(row) for row in csv.reader(window, delimiter=separator)}
            if len(counts) != 1 or (fields := counts.pop()) <= best_fields:
                continue
            if first and not _preamble(lines[:first + 1], separator, fields):
                continue
            best, best_fields, start = separator, fields, first
        if best_fields > 1:
            break
    if best_fields == 1:
        # No header matches its data: the separator the data rows agree on, so that the
        # error names the header's fields against theirs.
        # (A tie - decimal commas split a row as a comma would - goes to the separator
        # that splits the header more.)
        ranked = []
        for separator in SEPARATORS:
            counts = {len(row) for row in csv.reader(lines[1:SNIFF_LINES],
                                                     delimiter=separator)}
            if len(counts) == 1 and (fields := counts.pop()) > 1:
                header = next(csv.reader(lines[:1], delimiter=separator), [])
                ranked.append((fields, len(header), separator))
        if ranked:
            best = max(ranked, key=lambda r: (r[0], r[1]))[2]
    window = lines[start + 1:start + SNIFF_LINES]
    decimal_comma = best != "," and any(
        DECIMAL_COMMA.match(cell) for row in csv.reader(window, delimiter=best)
        for cell in row)
    return CsvDialect(best, decimal_comma, encoding, start)


def _preamble(lines: list[str], separator: str, fields: int) -> bool:
    """Whether ``lines[:-1]`` are a preamble to the header ``lines[-1]``: each splits into
    fewer fields than the header, and no header cell is a number (else a damaged row in
    the data, not a preamble, broke the field counts)."""
    rows = list(csv.reader(lines, delimiter=separator))
    if any(len(row) >= fields for row in rows[:-1]):
        return False
    for cell in rows[-1]:
        try:
            float(cell.replace(",", "."))
            return False
        except ValueError:
            continue
    return True


def csv_rows(path: str | Path, dialect: CsvDialect) -> Iterator[list[str]]:
    """Every row of ``path`` as cells (blank rows included), read in ``dialect``."""
    path = Path(path)
    try:
        stream = open(path, newline="", encoding=dialect.encoding,
                      errors="replace" if dialect.encoding == "cp1252" else "strict")
    except OSError as exc:
        raise InputDataError(f"{path}: cannot read ({exc.strerror})") from exc
    with stream:
        try:
            yield from csv.reader(stream, delimiter=dialect.delimiter)
        except (UnicodeDecodeError, csv.Error) as exc:
            raise InputDataError(f"{path}: not a text CSV file ({exc})") from exc


def table_rows(path: str | Path, dialect: CsvDialect) -> Iterator[list[str]]:
    """The non-empty rows of ``path`` from its header on (a preamble skipped)."""
    skipped = 0
    for row in csv_rows(path, dialect):
        if not any(cell.strip() for cell in row):
            continue
        if skipped < dialect.preamble_lines:
            skipped += 1
            continue
        yield row


def header_row(path: str | Path, dialect: CsvDialect | None = None) -> list[str]:
    """The column names of the header row."""
    dialect = dialect or sniff_dialect(path)
    rows = table_rows(path, dialect)
    try:
        for row in rows:
            return [name.strip() for name in row]
    finally:
        rows.close()
    raise InputDataError(f"{path}: empty file")


def to_number(cell: str, dialect: CsvDialect) -> float:
    """The cell as a float (``ValueError`` when it is none); a decimal comma is read as a
    point in a dialect that uses it."""
    if dialect.decimal_comma:
        cell = cell.replace(",", ".")
    return float(cell)


#: A time of day without a date (a logger that writes only the clock).
TIME_OF_DAY = re.compile(r"^\s*(\d{1,2}):(\d{2})(?::(\d{2})(?:[.,](\d+))?)?\s*$")
#: A day in seconds, and the backward step of a clock of the day read as midnight passing.
DAY_S = 86400.0
MIDNIGHT_STEP_S = -DAY_S / 2


def time_of_day(cell: str) -> float:
    """``HH:MM[:SS[.fff]]`` as seconds since midnight (``ValueError`` when it is none)."""
    found = TIME_OF_DAY.match(cell)
    if not found:
        raise ValueError(f"{cell.strip()[:30]!r} is no time of day")
    hours, minutes, seconds, fraction = found.groups()
    if int(hours) > 23 or int(minutes) > 59 or int(seconds or 0) > 59:
        raise ValueError(f"{cell.strip()[:30]!r} is no time of day")
    return int(hours) * 3600.0 + int(minutes) * 60.0 + int(seconds or 0) + \
        (float("0." + fraction) if fraction else 0.0)


def across_midnights(seconds_of_day):
    """Times of day (seconds since midnight, in file order) as seconds since the first
    midnight: a step back of more than half a day is the next day's clock."""
    values = np.asarray(seconds_of_day, dtype=np.float64)
    days = np.concatenate(([0.0], np.cumsum(np.diff(values) < MIDNIGHT_STEP_S)))
    return values + DAY_S * days


def to_seconds(cell: str) -> float:
    """A date-time cell as POSIX seconds (``ValueError`` when it is none)."""
    text = cell.strip()
    stamp = None
    try:
        stamp = datetime.fromisoformat(text[:-1] + "+00:00" if text.endswith("Z") else text)
    except ValueError:
        for layout in DATE_TIME_LAYOUTS:
            try:
                stamp = datetime.strptime(text, layout)
                break
            except ValueError:
                continue
    if stamp is None:
        raise ValueError(f"{text[:30]!r} is neither a number nor a date-time")
    if stamp.tzinfo is None:
        stamp = stamp.replace(tzinfo=timezone.utc)
    return stamp.timestamp()



def cell_kind(cell: str, dialect: CsvDialect) -> str:
    """What a cell holds: "number", "date-time", "clock" (a time of day without a date)
    or "" (none of them)."""
    for kind, read in (("number", lambda c: to_number(c, dialect)), ("date-time", to_seconds),
                       ("clock", time_of_day)):
        try:
            read(cell)
            return kind
        except ValueError:
            continue
    return ""
