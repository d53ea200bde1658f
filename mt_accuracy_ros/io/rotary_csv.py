"""CSV files of rotary-axis calibrations: ball-bar runs and probing cycles.

Ball bar (one file, both setups)::

    bar_mm,repetition,angle_deg,change_um
    90.850,1,0,0.412
    ...

``bar_mm`` the bar's calibrated length (two distinct values: the short and the
long bar), ``repetition`` 1..r, ``angle_deg`` the table angle in the order it
was indexed, ``change_um`` the bar's length change.

Probing (one row per touch point)::

    cycle,X_mm,Y_mm,Z_mm,A_deg,B_deg,px_mm,py_mm,pz_mm

``cycle`` groups the touches of one probing; the axis columns (``<axis>_mm`` for
linear, ``<axis>_deg`` for rotary axes) are the commanded positions; ``px/py/pz``
the touch point relative to where the CNC expected the sphere's centre, in
machine axes.

The units are the formats': each column's name states its unit (``bar_mm``,
``angle_deg``, ``change_um``, ``<axis>_mm`` / ``<axis>_deg``, ``px_mm``), and a file
without those columns is refused. Values implausible in that unit (a bar of 0.1 mm: metres
written in the mm column) are refused naming the unit they look like
(:mod:`~..core.inputs.plausibility`); the commands print the units they read.

Every error names the file and the line.
"""
from __future__ import annotations

import csv
import os
import tempfile
from pathlib import Path

import numpy as np

from ..core.errors import InputDataError, reraise_as
from ..core.inputs.plausibility import check_plausible
from ..core.rotary.ballbar import BallBarRun, BallBarSetup

BALLBAR_COLUMNS = ("bar_mm", "repetition", "angle_deg", "change_um")
#: What a ball-bar command says of the units it read (the format defines them).
BALLBAR_UNITS_NOTE = ("units as the ball-bar format defines them: bar_mm in mm, angle_deg "
                      "in deg, change_um in um")


def probing_units_note(axes: tuple[str, ...], rotary: set[str]) -> str:
    """What a probing command says of the units it read (the format defines them)."""
    axis_units = ", ".join(f"{a}_{'deg in deg' if a in rotary else 'mm in mm'}" for a in axes)
    return f"units as the probing format defines them: {axis_units}, px/py/pz_mm in mm"


def _refuse_implausible(path: Path, values, quantity: str, unit: str, column: str) -> None:
    """One line when a column's values are implausible in the unit its name states."""
    check_plausible(np.asarray(values, dtype=np.float64), quantity, unit,
                    f"{path}: column {column}", f"the format reads {column} in {unit}: "
                    "convert the file's values", error=InputDataError)


def _rows(path: Path, required: tuple[str, ...]) -> tuple[list[str], list[tuple[int, dict]]]:
    try:
        with open(path, newline="", encoding="utf-8") as handle:
            reader = csv.DictReader(handle)
            header = reader.fieldnames or []
            missing = [c for c in required if c not in header]
            if missing:
                raise InputDataError(f"{path}: missing column(s) {', '.join(missing)} "
                                     f"(has {', '.join(header) or 'none'})")
            rows = [(reader.line_num, row) for row in reader]
    except UnicodeDecodeError as exc:
        raise InputDataError(f"{path}: not a text CSV file ({exc.reason})") from exc
    if not rows:
        raise InputDataError(f"{path}: no data rows")
    return header, rows


def _number(path: Path, line: int, row: dict, column: str) -> float:
    text = (row.get(column) or "").strip()
    try:
        value = float(text)
    except ValueError:
        raise InputDataError(f"{path}, line {line}: {column} {text!r} is not a number") from None
    if not np.isfinite(value):
        raise InputDataError(f"{path}, line {line}: {column} is {text}, not a finite number")
    return value


@reraise_as(InputDataError, "ball-bar file")
def read_ballbar_csv(path, radius_m: float, socket_height_m: float = 0.0
                     ) -> tuple[BallBarRun, BallBarRun]:
    """The short- and the long-bar run of a ball-bar file (see the module docstring)."""
    path = Path(path)
    _, rows = _rows(path, BALLBAR_COLUMNS)
    runs: dict[float, dict[int, list[tuple[float, float]]]] = {}
    for line, row in rows:
        bar = _number(path, line, row, "bar_mm")
        rep = int(_number(path, line, row, "repetition"))
        runs.setdefault(bar, {}).setdefault(rep, []).append(
            (_number(path, line, row, "angle_deg"), _number(path, line, row, "change_um")))
    _refuse_implausible(path, [b for b in runs], "bar_length", "mm", "bar_mm")
    changes = [c for repetitions in runs.values() for values in repetitions.values()
               for _, c in values]
    _refuse_implausible(path, changes, "error", "um", "change_um")
    _refuse_implausible(path, changes, "deviation_spread", "um", "change_um")
    if len(runs) != 2:
        raise InputDataError(f"{path}: {len(runs)} bar length(s) "
                             f"({', '.join(f'{b:g}' for b in runs)} mm); the two-setup method "
                             "needs a short and a long bar")
    out = []
    for bar, repetitions in sorted(runs.items()):
        angle_sets = {rep: [a for a, _ in values] for rep, values in repetitions.items()}
        first = min(angle_sets)
        for rep, angles in angle_sets.items():
            if len(angles) != len(angle_sets[first]) or \
                    not np.allclose(angles, angle_sets[first], atol=1e-6):
                have = set(np.round(angles, 6))
                missing = [a for a in angle_sets[first] if round(a, 6) not in have]
                raise InputDataError(
                    f"{path}: the {bar:g} mm bar's repetition {rep} indexes other positions than "
                    f"repetition {first}"
                    + (f" (no reading at {', '.join(f'{a:g}' for a in missing[:5])}"
                       " deg)" if missing else ""))
        readings = np.array([[c for _, c in repetitions[rep]] for rep in sorted(repetitions)])
        out.append(BallBarRun(BallBarSetup(bar / 1e3, radius_m, socket_height_m),
                              np.radians(angle_sets[first]), readings * 1e-6,
                              label=f"{bar:g} mm bar"))
    return out[0], out[1]


def atomic_write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file and a rename: a reader sees
    the old file or the whole new one, never half of it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as stream:
            stream.write(text)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return path


def ballbar_csv_text(angles_deg, short_m, long_m, short_bar_m: float, long_bar_m: float) -> str:
    """A ball-bar file's text from readings (repetitions, positions) [m] of each bar."""
    lines = [",".join(BALLBAR_COLUMNS)]
    for bar_m, readings in ((short_bar_m, short_m), (long_bar_m, long_m)):
        for rep, row in enumerate(np.atleast_2d(readings), start=1):
            for angle, value in zip(angles_deg, row):
                lines.append(f"{bar_m * 1e3:.3f},{rep},{angle:g},{value * 1e6:.4f}")
    return "\n".join(lines) + "\n"


@reraise_as(InputDataError, "probing file")
def read_probing_csv(path, axes: tuple[str, ...], rotary: set[str]
                     ) -> tuple[dict[str, np.ndarray], list[np.ndarray]]:
    """(axis -> (N,) positions [m or rad], N arrays (m, 3) of touch points [m]), per cycle."""
    path = Path(path)
    columns = tuple(f"{a}_{'deg' if a in rotary else 'mm'}" for a in axes)
    _, rows = _rows(path, ("cycle",) + columns + ("px_mm", "py_mm", "pz_mm"))
    cycles: dict[str, dict] = {}
    for line, row in rows:
        key = (row.get("cycle") or "").strip()
        if not key:
            raise InputDataError(f"{path}, line {line}: empty cycle")
        q = tuple(_number(path, line, row, c) for c in columns)
        entry = cycles.setdefault(key, {"q": q, "points": [], "line": line})
        if not np.allclose(entry["q"], q, atol=1e-9):
            raise InputDataError(f"{path}, line {line}: cycle {key} changes its axis positions "
                                 f"(first at line {entry['line']})")
        entry["points"].append([_number(path, line, row, c) * 1e-3
                                for c in ("px_mm", "py_mm", "pz_mm")])
    for i, (axis, column) in enumerate(zip(axes, columns)):
        _refuse_implausible(path, [c["q"][i] for c in cycles.values()],
                            "angle" if axis in rotary else "position",
                            "deg" if axis in rotary else "mm", column)
    _refuse_implausible(path, np.concatenate([1e3 * np.asarray(c["points"]).ravel()
                                              for c in cycles.values()]),
                        "position", "mm", "px/py/pz_mm")
    positions = {a: np.array([c["q"][i] for c in cycles.values()], float) *
                 (np.pi / 180 if a in rotary else 1e-3) for i, a in enumerate(axes)}
    return positions, [np.array(c["points"]) for c in cycles.values()]


def probing_csv_text(positions: dict[str, np.ndarray], touch_points_m: np.ndarray,
                     rotary: set[str]) -> str:
    """A probing file's text (see the module docstring)."""
    axes = list(positions)
    header = ["cycle"] + [f"{a}_{'deg' if a in rotary else 'mm'}" for a in axes] + \
        ["px_mm", "py_mm", "pz_mm"]
    lines = [",".join(header)]
    for i, points in enumerate(touch_points_m):
        q = [np.degrees(positions[a][i]) if a in rotary else positions[a][i] * 1e3 for a in axes]
        for p in points:
            lines.append(",".join([str(i + 1)] + [f"{v:.6f}" for v in q] +
                                  [f"{v * 1e3:.6f}" for v in p]))
    return "\n".join(lines) + "\n"
