"""Compensation tables for CNC volumetric-compensation packages (ISO 230-1 names).

One CSV per machine: for each axis a block of rows on a position grid with the
axis' six component errors, then the position-independent errors::

    # mt_accuracy_ros compensation table v1
    # machine: kidani_hmc
    # units: positions m (rotary rad), linear errors m, angular errors rad
    axis,position,EXX,EYX,EZX,EAX,EBX,ECX
    X,0.000000000000e+00,...
    ...
    location,value
    EC0Y,1.0e-05

Columns are named for the axis of each block (``EXY, EYY, ...`` for Y). The
``location`` block lists squareness and other location errors (EC0Y-style).
"""
from __future__ import annotations

import io
from dataclasses import dataclass, replace

import numpy as np

from ..kinematics.error_functions import ErrorFunction
from ..errors import MachineDescriptionError
from ..kinematics.machine import (COMPONENTS, Axis, MachineDescription, location_error_name,
                                  motion_error_name)

HEADER = "# mt_accuracy_ros compensation table v1"


@dataclass(frozen=True)
class CompensationTable:
    """Parsed table: per axis a grid and six columns; location errors by name.

    Parameters
    ----------
    machine : str
        Machine name.
    grids : dict of str to ndarray, shape (K,)
        Axis -> ascending positions [m] (rotary [rad]).
    errors : dict of str to dict of str to ndarray, shape (K,)
        Axis -> ISO name -> values on the grid [m] (translational) or [rad] (angular).
    location : dict of str to float
        Location error name (``EC0Y``) -> value [m] or [rad].
    """

    machine: str
    grids: dict[str, np.ndarray]
    errors: dict[str, dict[str, np.ndarray]]   # axis -> ISO name -> values on the grid
    location: dict[str, float]


def table_from_machine(machine: MachineDescription, points_per_axis: int = 41) -> CompensationTable:
    """Sample every axis' error functions on a uniform grid over its stroke.

    Parameters
    ----------
    machine : MachineDescription
        The machine.
    points_per_axis : int, optional
        Grid points per axis (>= 2).

    Returns
    -------
    CompensationTable
        Grids [m] / [rad], component errors and location errors [m] / [rad].

    Raises
    ------
    MachineDescriptionError
        ``points_per_axis`` below 2.
    """
    if points_per_axis < 2:
        raise MachineDescriptionError("points_per_axis must be >= 2")
    grids, errors, location = {}, {}, {}
    for name in machine.axis_order:
        axis = machine.axes[name]
        grid = np.linspace(axis.stroke[0], axis.stroke[1], points_per_axis)
        grids[name] = grid
        errors[name] = {motion_error_name(c, name): axis.motion_errors[c](grid) for c in COMPONENTS}
        for component, value in axis.location_errors.items():
            location[location_error_name(component, name)] = value
    return CompensationTable(machine=machine.name, grids=grids, errors=errors, location=location)


def write_csv(table: CompensationTable) -> str:
    """CSV text of a table (17 significant digits: reading it back is exact).

    Parameters
    ----------
    table : CompensationTable
        The table, SI units.

    Returns
    -------
    str
        CSV text in SI units (positions [m] / [rad], errors [m] / [rad]).
    """
    out = io.StringIO()
    out.write(f"{HEADER}\n# machine: {table.machine}\n")
    out.write("# units: positions m (rotary rad), linear errors m, angular errors rad\n")
    for name, grid in table.grids.items():
        columns = [motion_error_name(c, name) for c in COMPONENTS]
        out.write("axis,position," + ",".join(columns) + "\n")
        for i, position in enumerate(grid):
            values = [table.errors[name][c][i] for c in columns]
            out.write(f"{name},{position:.17g}," + ",".join(f"{v:.17g}" for v in values) + "\n")
    out.write("location,value\n")
    for name, value in table.location.items():
        out.write(f"{name},{value:.17g}\n")
    return out.getvalue()


def read_csv(text: str) -> CompensationTable:
    """Parse the CSV written by :func:`write_csv`; errors name the line.

    Parameters
    ----------
    text : str
        CSV text in SI units.

    Returns
    -------
    CompensationTable
        The parsed table.

    Raises
    ------
    MachineDescriptionError
        A wrong header line, a non-number or non-finite value, or a row of the
        wrong length.
    """
    lines = text.splitlines()
    if not lines or lines[0].strip() != HEADER:
        raise MachineDescriptionError(f"line 1: expected {HEADER!r}")
    machine = ""
    grids: dict[str, list[float]] = {}
    errors: dict[str, dict[str, list[float]]] = {}
    location: dict[str, float] = {}
    columns: list[str] = []
    in_location = False
    for number, raw in enumerate(lines[1:], start=2):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("# machine:"):
            machine = line.split(":", 1)[1].strip()
            continue
        if line.startswith("#"):
            continue
        fields = line.split(",")
        if fields[0] == "axis":
            columns, in_location = fields[2:], False
            continue
        if fields[0] == "location":
            in_location = True
            continue
        try:
            numbers = [float(f) for f in fields[1:]]
        except ValueError as exc:
            raise MachineDescriptionError(f"line {number}: not a number ({exc})") from exc
        if not all(np.isfinite(numbers)):
            raise MachineDescriptionError(f"line {number}: non-finite value")
        if in_location:
            if len(numbers) != 1:
                raise MachineDescriptionError(f"line {number}: expected 'name,value'")
            location[fields[0]] = numbers[0]
            continue
        if len(numbers) != 1 + len(columns):
            raise MachineDescriptionError(
                f"line {number}: expected {1 + len(columns)} numbers, got {len(numbers)}")
        axis = fields[0]
        grids.setdefault(axis, []).append(numbers[0])
        block = errors.setdefault(axis, {c: [] for c in columns})
        for column, value in zip(columns, numbers[1:]):
            block[column].append(value)
    return CompensationTable(
        machine=machine, grids={a: np.asarray(g) for a, g in grids.items()},
        errors={a: {c: np.asarray(v) for c, v in cols.items()} for a, cols in errors.items()},
        location=location)


def machine_with_table(machine: MachineDescription, table: CompensationTable) -> MachineDescription:
    """The machine with its error functions replaced by the table's (piecewise linear).

    An axis without a grid in the table (a rotary axis of a linear-axis table)
    keeps its own error motions; the table's location errors of that axis, if
    it lists any, replace the machine's.

    Parameters
    ----------
    machine : MachineDescription
        The nominal machine.
    table : CompensationTable
        The table applied.

    Returns
    -------
    MachineDescription
        A copy with tabled error motions and location errors.
    """
    axes = {}
    for name, axis in machine.axes.items():
        if name not in table.grids:
            listed = {c: table.location[location_error_name(c, name)] for c in COMPONENTS
                      if location_error_name(c, name) in table.location}
            axes[name] = replace(axis, location_errors=listed) if listed else axis
            continue
        grid = table.grids[name]
        motion = {c: ErrorFunction(kind="table", positions=grid,
                                   values=table.errors[name][motion_error_name(c, name)])
                  for c in COMPONENTS}
        location = {c: table.location[location_error_name(c, name)] for c in COMPONENTS
                    if location_error_name(c, name) in table.location}
        axes[name] = Axis(name=axis.name, stroke=axis.stroke, offset=axis.offset, sign=axis.sign,
                          motion_errors=motion, location_errors=location)
    return replace(machine, axes=axes)
