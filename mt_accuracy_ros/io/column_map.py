"""Reference surveys from any data logger's CSV: which column is what, in which unit.

A **column map** (YAML, or ``--col ROLE=COLUMN[:UNIT]`` flags) says::

    time: {column: t, unit: min}            # optional: without it, row order is time,
    row_period_s: 15                        #   one row every row_period_s (default 1 s)
    positions: {X: {column: x_mm, unit: mm}, Y: {column: y_mm, unit: mm}, ...}
    errors: {x: {column: dev_x, unit: um}, z: {column: dev_z, unit: um}}   # TCP error
    temperatures: {column: {column: T3, unit: degC}, bed: {column: T7, unit: K}}
    velocities: {X: {column: feed_x, unit: mm/min}}        # optional
    accelerations: {X: {column: acc_x, unit: m/s^2}}       # optional
    directions: {X: {column: dir_x}}                       # optional, +-1
    spindle_speed: {column: S, unit: rpm}                  # optional
    uncertainty: {value: 1.4, unit: um}                    # the instrument's k = 2 figure
    tool_offset: {value: -150, unit: mm}                   # optional: z of the tool tip
                                                           #   from the last axis (Abbe arm)
    machine: trunnion.yaml                                 # optional: the machine (a YAML
                                                           #   beside the map, or a bundled name)
    setup_pose: {A: {value: 0, unit: deg}, C: {value: 0, unit: deg}}   # where the work
                                                           #   (sphere, part) was set up
    target_point: {value: [50, 0, 20], unit: mm}           # a fixed sphere, work coordinates
                                                           #   (from the work offset, as a
                                                           #   CNC program gives it);
    # or per row (several spheres): {columns: {x: sx, y: sy, z: sz}, unit: mm}
    direction_errors: {x: {column: dux, unit: urad}, ...}  # the tool direction's change
                                                           #   (a two-sphere R-test)
    error_convention: {of: tool, as: deviation, frame: machine}   # optional: what the
                                                           #   error columns mean (below)
    work_axes: [Y, X]                                      # optional: the axes carrying the
                                                           #   workpiece, bed outwards
    run: {column: day}                                     # optional: a survey of many runs
                                                           #   (rows of one run share a value)

Flags: ``time``, ``pos.X``, ``err.x``, ``temp.<sensor>``, ``vel.X``, ``acc.X``,
``dir.X``, ``spindle``, ``run``, ``tdir.x`` (tool direction error), ``target.x`` (a
per-row target) as ROLE, e.g. ``--col pos.X=x_mm:mm --col err.x=dev_x:um``.

A rotary position column (A, B, C) is an angle in a unit the map or the column's name
gives; a direction error is the change of the tool axis' unit vector relative to the
work, actual minus nominal, in the machine frame (what a two-sphere R-test measures
across the tool axis), as a small angle - unless ``error_convention`` says otherwise.

The error columns are read, unless ``error_convention`` says otherwise, as the tool
relative to the work (``of: tool``; ``of: work`` - the sphere seen from the tool's nest),
actual minus nominal (``as: deviation``; ``as: correction`` - nominal minus actual, what
a compensation adds), along the machine's axes (``frame: machine``; ``frame: work`` - an
instrument turning with the table, ``frame: tool`` - with the head, whose axes are the
machine's with every rotary axis at 0, or at the set-up pose with ``aligned_at: setup``).
The check says which it took (:meth:`ErrorConvention.note`).

A ``run`` column (text or numbers) cuts the survey into runs: each run's rows lie
together, its time may restart, lags restart at its first reading and whole runs are
the validation folds (:mod:`~..core.workbench.log_runs`).

Every quantity is read in a stated unit or refused: a column's unit comes from the map,
the flag (``:UNIT``) or the end of its name (``dev_x_um``, ``T3 [°C]``); a column with
none, a bare ``uncertainty: 1.4`` or ``tool_offset: -150`` is refused in one line that
says how to give it (no unit defaults to SI). Values implausible in their stated unit
(errors of metres, travels of hundreds of metres, temperatures of 293 °C) are refused
naming the unit they look like (:mod:`~..core.inputs.plausibility`), before any search.
A survey that states no uncertainty takes the 1 µm default, announced
(:meth:`ColumnMap.uncertainty_note`).

Everything is converted to SI (REP-103; temperatures stay in degC). A
missing column, an unknown role or unit, a column that is not numeric, too few
rows, or times that go backwards give one error that
names the column or row; a row with a bad cell in a mapped column is
dropped and counted (:class:`~.csv_table.CsvTable` style).
"""
from __future__ import annotations

import contextlib
import itertools
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import InputDataError, ParameterError
from ..core.inputs.plausibility import (ANGLE, LENGTH, TEMPERATURE, UNITS, check_plausible,
                                        temperature_quantity)
from ..core.kinematics.machine import angle_with_unit
from .csv_dialect import CsvDialect, cell_kind, sniff_dialect, table_rows, to_seconds

# The unit tables live with the plausibility bounds (one table of each, in the core).
_LENGTH, _ANGLE = LENGTH, ANGLE
#: A unit a message proposes for a role's column when none is given (what a logger's
#: column of that kind usually holds).
EXAMPLE_UNITS = {"time": "s", "length": "mm", "angle": "deg", "velocity": "mm/min",
                 "acceleration": "m/s^2", "speed": "rpm", "temperature": "degC"}
#: The column roles (``KIND.KEY``), as a refusal of an unknown one lists them.
ROLES_HELP = ("time, pos.X, err.x, temp.<sensor>, vel.X, acc.X, dir.X, spindle, run, "
              "tdir.x, target.x")


#: ``error_convention`` keys -> their words; the first of each is the default.
ERROR_CONVENTION_WORDS = {"of": ("tool", "work"), "as": ("deviation", "correction"),
                          "frame": ("machine", "work", "tool"), "aligned_at": ("zero", "setup")}


@dataclass(frozen=True)
class ErrorConvention:
    """What a survey's error columns (and tool-direction columns) mean.

    ``of``: ``tool`` - the tool relative to the work (the package's convention) or
    ``work`` - the work (a sphere) relative to the tool; ``as``: ``deviation`` (actual
    minus nominal) or ``correction`` (nominal minus actual); ``frame``: the axes the
    components lie along - ``machine`` (the bed's), ``work`` (the workpiece frame's, an
    instrument turning with the table) or ``tool`` (the spindle frame's); ``aligned_at``:
    where a turning frame's axes are the machine's - ``zero`` (every rotary axis at 0: the
    machine description's workpiece or spindle frame) or ``setup`` (at the set-up pose:
    an instrument aligned with the machine's axes where the work was set up).
    """

    of: str = "tool"
    sense: str = "deviation"
    frame: str = "machine"
    aligned_at: str = "zero"
    #: Whether the map stated it (the note says so either way).
    stated: bool = False

    @property
    def sign(self) -> float:
        """+1 or -1: what turns the columns into the tool relative to the work, actual
        minus nominal (each of ``of: work`` and ``as: correction`` turns the sign)."""
        flips = (self.of == "work") + (self.sense == "correction")
        return -1.0 if flips % 2 else 1.0

    def note(self) -> str:
        """The sentence the check prints about how it read the error columns."""
        words = {"tool": "the tool relative to the work", "work": "the work relative to the "
                 "tool (turned to the tool relative to the work)"}[self.of]
        sense = {"deviation": "actual minus nominal", "correction": "nominal minus actual "
                 "(a correction; turned to actual minus nominal)"}[self.sense]
        aligned = {"zero": "every rotary axis at 0",
                   "setup": "the set-up pose"}[self.aligned_at]
        frame = {"machine": "along the machine's axes",
                 "work": f"along the workpiece frame's axes (the machine's at {aligned}; "
                         "turned to the machine's at each reading's nominal pose)",
                 "tool": f"along the spindle frame's axes (the machine's at {aligned}; "
                         "turned to the machine's at each reading's nominal pose)"}[self.frame]
        given = "the column map's error_convention" if self.stated else \
            "the default; a column map (--columns MAP.yaml) says otherwise with " \
            "error_convention: {of: work|tool, as: deviation|correction, frame: " \
            "machine|work|tool, aligned_at: zero|setup}"
        return f"errors read as {words}, {sense}, {frame} ({given})"

    def as_dict(self) -> dict:
        """The convention in the map's words, and whether the map stated it (the JSON's)."""
        return {"of": self.of, "as": self.sense, "frame": self.frame,
                "aligned_at": self.aligned_at, "stated": self.stated}


def _error_convention(spec, where: str) -> ErrorConvention:
    """The map's ``error_convention`` block; an unknown key or word is refused."""
    if not isinstance(spec, dict):
        raise ParameterError(f"{where}: expected {{of: tool, as: deviation, frame: machine}}")
    unknown = set(spec) - set(ERROR_CONVENTION_WORDS)
    if unknown:
        raise ParameterError(f"{where}: unknown key(s) {', '.join(sorted(map(str, unknown)))}; "
                             f"known: {', '.join(ERROR_CONVENTION_WORDS)}")
    chosen = {}
    for key, words in ERROR_CONVENTION_WORDS.items():
        word = str(spec.get(key, words[0])).strip().lower()
        if word not in words:
            raise ParameterError(f"{where}.{key}: {spec[key]!r} is not one of "
                                 f"{', '.join(words)}")
        chosen[key] = word
    return ErrorConvention(chosen["of"], chosen["as"], chosen["frame"], chosen["aligned_at"],
                           stated=True)


@dataclass
class ColumnMap:
    """Role -> (column, unit). Roles as in the module docstring."""

    roles: dict[str, tuple[str, str]] = field(default_factory=dict)
    row_period_s: float = 1.0
    #: The instrument's k = 2 uncertainty the map (``uncertainty:``) or a flag stated [m];
    #: None: not stated (:attr:`uncertainty_m` is then the documented default, announced).
    stated_uncertainty_m: float | None = None
    #: z of the tool tip relative to the last linear axis' reference point [m], negative
    #: when it points down (None: not given): without a machine, the generic machine's
    #: tool, so angular errors act through the real arm.
    tool_offset_m: float | None = None
    #: The axes that carry the workpiece, from the bed outwards (the rest carry the tool).
    work_axes: tuple[str, ...] = ()
    #: The machine the survey was taken on (``machine:``): a machine YAML's path (relative
    #: ones resolved against the map's folder) or a bundled name; None: not given.
    machine: str | None = None
    #: Where the work was set up (``setup_pose:``), rotary axis -> command [rad].
    setup_pose: dict[str, float] = field(default_factory=dict)
    #: A fixed target on the workpiece side (3,) [m], in work coordinates: from the work
    #: offset (the machine's ``workpiece`` point) along the workpiece frame's axes
    #: (``target_point:`` with ``value``); per-row targets are the roles ``target.x/y/z``.
    target_point_m: np.ndarray | None = None
    #: What the error columns mean (``error_convention:``; default the package's own).
    error_convention: ErrorConvention = field(default_factory=ErrorConvention)

    @property
    def uncertainty_m(self) -> float:
        """The k = 2 uncertainty [m]: the stated one, else the documented default."""
        from ..core.workbench.statistics import DEFAULT_POSITION_UNCERTAINTY_M

        return DEFAULT_POSITION_UNCERTAINTY_M if self.stated_uncertainty_m is None else \
            self.stated_uncertainty_m

    @uncertainty_m.setter
    def uncertainty_m(self, value: float) -> None:
        self.stated_uncertainty_m = float(value)

    def uncertainty_note(self) -> str:
        """The sentence announcing the default uncertainty ("" when one was stated)."""
        if self.stated_uncertainty_m is not None:
            return ""
        return (f"uncertainty: the column map states none; {self.uncertainty_m * 1e6:g} um "
                "(k = 2) assumed - give the instrument's as uncertainty: {value: V, unit: um} "
                "or --uncertainty-um")

    def plausible_as(self, role: str) -> str | None:
        """The quantity of :data:`~..core.inputs.plausibility.BOUNDS` a role's values are
        judged as (None: not judged - directions, runs, a rotary axis' acceleration)."""
        kind, _, key = role.partition(".")
        rotary = len(key) == 1 and key in "ABC"
        if kind == "temp":
            return temperature_quantity(key)
        if kind == "acc" and rotary:
            return None
        return {"time": "duration", "spindle": "spindle_speed", "err": "error",
                "tdir": "angle_error", "target": "position",
                "pos": "angle" if rotary else "position",
                "vel": "angular_velocity" if rotary else "velocity",
                "acc": "acceleration"}.get(kind)

    def quantity(self, role: str) -> str:
        kind, _, axis = role.partition(".")
        if kind == "time":
            return "time"
        if kind == "spindle":
            return "speed"
        if kind == "temp":
            return "temperature"
        if kind in ("dir", "run"):
            return "unitless"
        if kind == "tdir":
            return "angle"
        if kind == "target":
            return "length"
        rotary = axis.upper() in "ABC" and kind != "err"
        return {"pos": "angle" if rotary else "length", "err": "length",
                "vel": "velocity", "acc": "acceleration"}.get(kind, "")


def _role_from_yaml(section: str, key: str) -> str:
    return {"positions": f"pos.{key}", "errors": f"err.{key}", "temperatures": f"temp.{key}",
            "velocities": f"vel.{key}", "accelerations": f"acc.{key}",
            "directions": f"dir.{key}", "direction_errors": f"tdir.{key}"}[section]


def column_map_from_dict(data: dict, source: str = "column map") -> ColumnMap:
    if not isinstance(data, dict):
        raise ParameterError(f"{source}: expected a mapping (time, positions, errors, ...)")
    known = {"time", "row_period_s", "positions", "errors", "temperatures", "velocities",
             "accelerations", "directions", "spindle_speed", "uncertainty", "machine",
             "tool_offset", "work_axes", "run", "setup_pose", "target_point",
             "direction_errors", "error_convention"}
    unknown = set(data) - known
    if unknown:
        raise ParameterError(f"{source}: unknown key(s) {', '.join(sorted(unknown))}; known: "
                             f"{', '.join(sorted(known))}")
    out = ColumnMap()

    def entry(value, where):
        if isinstance(value, str):
            return value, ""
        if not isinstance(value, dict) or "column" not in value:
            raise ParameterError(f"{source}: {where} needs {{column: NAME, unit: UNIT}}")
        return str(value["column"]), str(value.get("unit", ""))

    for section in ("positions", "errors", "temperatures", "velocities", "accelerations",
                    "directions", "direction_errors"):
        block = data.get(section) or {}
        if not isinstance(block, dict):
            raise ParameterError(f"{source}: {section} must map names to columns")
        for key, value in block.items():
            out.roles[_role_from_yaml(section, str(key))] = entry(value, f"{section}.{key}")
    if "time" in data:
        out.roles["time"] = entry(data["time"], "time")
    if "spindle_speed" in data:
        out.roles["spindle"] = entry(data["spindle_speed"], "spindle_speed")
    if "run" in data:
        out.roles["run"] = entry(data["run"], "run")
    if "row_period_s" in data:
        out.row_period_s = float(data["row_period_s"])
        if not (out.row_period_s > 0 and math.isfinite(out.row_period_s)):
            raise ParameterError(f"{source}: row_period_s must be a positive number of seconds")
    if "uncertainty" in data:
        value, unit = _value_with_unit(data["uncertainty"], f"{source}: uncertainty", "um")
        out.uncertainty_m = _convert_scalar(value, unit, "length", f"{source}: uncertainty")
        check_plausible(np.array([value]), "uncertainty", unit, f"{source}: uncertainty",
                        "the instrument's k = 2 figure: {value: V, unit: um}")
    if "work_axes" in data:
        work = data["work_axes"]
        if not isinstance(work, list) or not all(isinstance(a, str) and a.upper() in "XYZ"
                                                 and len(a) == 1 for a in work) or \
                len({a.upper() for a in work}) != len(work):
            raise ParameterError(f"{source}: work_axes must list axis letters (X, Y, Z), each "
                                 "once, from the bed outwards, e.g. [Y, X]")
        out.work_axes = tuple(a.upper() for a in work)
    if "tool_offset" in data:
        out.tool_offset_m = _tool_offset(data["tool_offset"], f"{source}: tool_offset")
    if "machine" in data:
        out.machine = _machine_reference(data["machine"], source)
    if "setup_pose" in data:
        out.setup_pose = _setup_pose(data["setup_pose"], f"{source}: setup_pose")
    if "target_point" in data:
        _target_point(out, data["target_point"], f"{source}: target_point")
    if "error_convention" in data:
        out.error_convention = _error_convention(data["error_convention"],
                                                 f"{source}: error_convention")
    return out


def _value_with_unit(spec, where: str, example_unit: str) -> tuple[object, str]:
    """(value, unit) of ``{value: V, unit: U}``: a bare number, or one without its unit, is
    refused - no quantity defaults to SI silently."""
    if isinstance(spec, dict) and "value" in spec and str(spec.get("unit", "")).strip():
        return spec["value"], UNIT_SPELLINGS.get(str(spec["unit"]).strip(),
                                                 str(spec["unit"]).strip())
    value = spec.get("value", "V") if isinstance(spec, dict) else spec
    key = where.rsplit(": ", 1)[-1]
    raise ParameterError(f"{where}: {value!r} has no unit; give it as {key}: "
                         f"{{value: {value}, unit: {example_unit}}}")


def _tool_offset(spec, where: str) -> float:
    """The map's signed tool offset [m] (a bare 0 is zero in any unit)."""
    if spec == 0 and not isinstance(spec, bool):
        return 0.0
    value, unit = _value_with_unit(spec, where, "mm")
    if isinstance(value, bool) or not isinstance(value, (int, float)) or \
            not math.isfinite(value):
        raise ParameterError(f"{where}: expected a number, got {value!r}")
    if value == 0:
        return 0.0
    # Signed: the magnitude is checked like any length, the sign kept.
    magnitude = _convert_scalar(abs(value), unit, "length", where)
    check_plausible(np.array([value]), "tool_offset", unit, where,
                    "the tool tip's z from the last axis: {value: -150, unit: mm}")
    return math.copysign(magnitude, value)


def _machine_reference(value, source: str) -> str:
    """The map's ``machine:``: a bundled name as it is, a YAML path resolved against the
    map's folder (the map is usually kept beside the machine it was taken on)."""
    if not isinstance(value, str) or not value.strip():
        raise ParameterError(f"{source}: machine: expected a machine YAML's path or a bundled "
                             f"name, got {value!r}")
    value = value.strip()
    if Path(value).suffix and not Path(value).is_absolute() and Path(source).is_file():
        return str(Path(source).resolve().parent / value)
    return value


def _setup_pose(spec, where: str) -> dict[str, float]:
    """Rotary axis -> set-up command [rad]; every angle with its unit."""
    if not isinstance(spec, dict):
        raise ParameterError(f"{where}: expected {{A: {{value: 0, unit: deg}}, ...}}")
    pose = {}
    for axis, value in spec.items():
        axis = str(axis).upper()
        if axis not in ("A", "B", "C"):
            raise ParameterError(f"{where}.{axis}: the set-up pose names rotary axes (A, B, C)")
        pose[axis] = angle_with_unit(value, f"{where}.{axis}", ParameterError, _ANGLE)
    return pose


def _target_point(out: ColumnMap, spec, where: str) -> None:
    """``{value: [x, y, z], unit: mm}`` (one fixed target) or ``{columns: {x: .., y: ..,
    z: ..}, unit: mm}`` (a target per row: several spheres)."""
    if not isinstance(spec, dict) or "unit" not in spec or \
            len({"value", "columns"} & set(spec)) != 1:
        raise ParameterError(f"{where}: expected {{value: [x, y, z], unit: mm}} or "
                             "{columns: {x: COLUMN, y: COLUMN, z: COLUMN}, unit: mm}")
    unit = str(spec["unit"])
    if unit not in _LENGTH:
        raise ParameterError(f"{where}: unknown unit {unit!r}; known: {', '.join(_LENGTH)}")
    if "columns" in spec:
        columns = spec["columns"]
        if not isinstance(columns, dict) or set(columns) != {"x", "y", "z"}:
            raise ParameterError(f"{where}.columns: name the x, y and z columns")
        for axis, column in columns.items():
            out.roles[f"target.{axis}"] = (str(column), unit)
        return
    value = spec["value"]
    if not (isinstance(value, list) and len(value) == 3 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in value)):
        raise ParameterError(f"{where}.value: expected three numbers [x, y, z]")
    out.target_point_m = np.asarray(value, dtype=np.float64) * _LENGTH[unit]


def _convert_scalar(value, unit: str, quantity: str, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or \
            not math.isfinite(value) or value <= 0:
        raise ParameterError(f"{where}: expected a positive number, got {value!r}")
    table = UNITS[quantity]
    if unit not in table:
        raise ParameterError(f"{where}: unknown unit {unit!r}; known: {', '.join(table)}")
    return float(value) * table[unit]


#: Role kind -> the keys it takes: axis letters, components, any sensor name (None), or
#: no key ("").
_ROLE_KEYS = {"pos": "XYZABC", "vel": "XYZABC", "acc": "XYZABC", "dir": "XYZABC",
              "err": "xyz", "tdir": "xyz", "target": "xyz", "temp": None, "time": "",
              "spindle": "", "run": ""}


def refuse_unknown_role(role: str, where: str = "column map") -> None:
    """One line naming ``role`` when it is no column role (listing the known ones) or its
    key is not one the role takes."""
    kind, dot, key = role.partition(".")
    if kind not in _ROLE_KEYS:
        raise ParameterError(f"{where}: unknown role {role!r}; known roles: {ROLES_HELP}")
    keys = _ROLE_KEYS[kind]
    if keys == "" and dot:
        raise ParameterError(f"{where}: role {role!r}: {kind} takes no .KEY; known roles: "
                             f"{ROLES_HELP}")
    if keys is None and not key:
        raise ParameterError(f"{where}: role {role!r}: name the sensor (temp.<sensor>)")
    if kind in ("err", "tdir", "target") and key not in ("x", "y", "z"):
        raise ParameterError(f"{role}: the components are {kind}.x, {kind}.y, {kind}.z")
    if keys and (len(key) != 1 or key not in keys):
        raise ParameterError(f"{role}: name the axis with its letter (X Y Z A B C)")


def parse_col_flags(flags: list[str], base: ColumnMap | None = None) -> ColumnMap:
    """``ROLE=COLUMN[:UNIT]`` flags on top of ``base``; an unknown role or unit is refused
    naming it and what is known."""
    out = base or ColumnMap()
    for flag in flags:
        role, sep, rest = flag.partition("=")
        if not sep or not rest:
            raise ParameterError(f"--col {flag!r}: expected ROLE=COLUMN[:UNIT], e.g. "
                                 "pos.X=x_mm:mm")
        column, _, unit = rest.rpartition(":") if ":" in rest else (rest, "", "")
        role, unit = role.strip(), UNIT_SPELLINGS.get(unit.strip(), unit.strip())
        refuse_unknown_role(role, f"--col {flag!r}")
        quantity = out.quantity(role)
        if unit and quantity != "unitless":
            si_scale(quantity, unit, f"--col {flag!r}")
        out.roles[role] = (column.strip(), unit)
    return out


def si_scale(quantity: str, unit: str, what: str) -> tuple[float, float]:
    """(scale, offset) that take ``unit`` of ``quantity`` to SI (temperatures to degC);
    raises naming ``what`` and the known units (an empty unit too: none is assumed)."""
    table = TEMPERATURE if quantity == "temperature" else UNITS[quantity]
    if unit not in table or not unit:
        raise ParameterError(f"{what}: unknown {quantity} unit {unit!r}; known: "
                             f"{', '.join(u for u in table if u)}")
    return TEMPERATURE[unit] if quantity == "temperature" else (table[unit], 0.0)


#: Units as spreadsheets write them in a header, and the names this module knows them by.
UNIT_SPELLINGS = {"°C": "degC", "℃": "degC", "°F": "degF", "μm": "µm"}


def unit_from_name(column: str, quantity: str) -> str:
    """The unit a column's name ends in (``x_mm``, ``dev_um``, ``T3_degC``) or gives in
    brackets at its end (``dial [µm]``, ``T1 (°C)``) if it is one of ``quantity``'s, else
    "" (the quantity's default then applies)."""
    bracketed = re.search(r"[\[(]\s*([^\])]+?)\s*[\])]\s*$", column)
    suffix = bracketed.group(1) if bracketed else \
        (column.rsplit("_", 1)[-1] if "_" in column else "")
    return _known_unit(suffix, quantity)


def _known_unit(unit: str, quantity: str) -> str:
    """``unit`` as this module names it, if it is one of ``quantity``'s, else ""."""
    unit = UNIT_SPELLINGS.get(unit, unit)
    known = TEMPERATURE if quantity == "temperature" else UNITS.get(quantity, {})
    return unit if unit and unit in known else ""


def column_unit(column: str, quantity: str, units: dict[str, str] | None = None) -> str:
    """The unit of ``column`` a file gives, if it is one of ``quantity``'s: from a units row
    under the header (``units``: column -> unit as written), else from the column's name
    (:func:`unit_from_name`); "" when neither does."""
    return _known_unit((units or {}).get(column, ""), quantity) or \
        unit_from_name(column, quantity)


def role_unit(column_map: ColumnMap, role: str) -> str:
    """The unit of ``role``'s column: the map's or flag's, else the one its name ends in
    (``x_mm``); refused in one line when neither gives one - a millimetre column is never
    read as metres, nor any column in a unit nobody stated ("" for directions and runs)."""
    column, unit = column_map.roles[role]
    quantity = column_map.quantity(role)
    if quantity == "unitless":
        return ""
    unit = UNIT_SPELLINGS.get(unit, unit) or unit_from_name(column, quantity)
    if not unit:
        kind = role.partition(".")[0]
        example = {"err": "um", "tdir": "urad"}.get(kind, EXAMPLE_UNITS[quantity])
        raise ParameterError(
            f"column {column} ({role}) has no unit: give it in the map ({{column: {column}, "
            f"unit: {example}}}), the flag (--col {role}={column}:{example}) or the name "
            f"({column}_{example})")
    si_scale(quantity, unit, role)
    return unit


def _scale(column_map: ColumnMap, role: str) -> tuple[float, float]:
    """(scale, offset) that take ``role``'s column to SI (:func:`role_unit`)."""
    quantity = column_map.quantity(role)
    if quantity == "unitless":
        return 1.0, 0.0
    return si_scale(quantity, role_unit(column_map, role), role)


def refuse_implausible(column_map: ColumnMap, values: dict[str, list],
                       units: dict[str, str]) -> None:
    """One line when a column's values (in their declared unit) are implausible for what
    the role measures, naming the unit they look like (:mod:`~..core.inputs.plausibility`)
    - read before any search, so nothing runs on metres that are millimetres.

    A temperature column is refused only when most of its readings fit another unit
    (kelvin declared as degC); a dead stretch (-180, 0 from a row on) is a sensor problem,
    named and left out by the sensors' judge - the thermal logs' rule
    (:func:`~..core.inputs.sensor_health.refuse_wrong_temperature_unit`)."""
    from ..core.inputs.sensor_health import refuse_wrong_temperature_unit

    for role, unit in units.items():
        quantity = column_map.plausible_as(role)
        if quantity is None or not values.get(role):
            continue
        column = column_map.roles[role][0]
        where = f"column {column} ({role})"
        mend = (f"declare its unit ({{column: {column}, unit: UNIT}} in the map or "
                f"--col {role}={column}:UNIT)")
        if role.startswith("temp."):
            # The mend's braces are text, not the likely unit's placeholder.
            refuse_wrong_temperature_unit(role.split(".", 1)[1], values[role], unit, where,
                                          mend.replace("{", "{{").replace("}", "}}"),
                                          ParameterError)
            continue
        check_plausible(np.asarray(values[role], dtype=np.float64), quantity, unit,
                        where, mend)


@dataclass
class MappedSurvey:
    time_s: np.ndarray
    positions: dict[str, np.ndarray]
    errors: dict[str, np.ndarray]
    temperatures: dict[str, np.ndarray]
    velocities: dict[str, np.ndarray]
    accelerations: dict[str, np.ndarray]
    directions: dict[str, np.ndarray]
    spindle_speed_rad_s: np.ndarray | None
    rows_read: int
    rows_dropped: int
    drop_reasons: list[str]
    #: (N,) run index of each row and the runs' names (a survey of many runs), or None.
    run_of_row: np.ndarray | None = None
    run_names: list[str] | None = None
    #: How the file was written, when it is not a plain UTF-8 comma-separated CSV.
    dialect_note: str = ""
    #: component -> (N,) the tool direction's change [rad] (``tdir.x`` ...), if mapped.
    direction_errors: dict[str, np.ndarray] = field(default_factory=dict)
    #: component -> (N,) each row's target in the workpiece frame [m] (``target.x`` ...).
    targets: dict[str, np.ndarray] = field(default_factory=dict)
    #: (N,) each row's number in the file, as an editor shows it (the header is row 1).
    file_rows: np.ndarray | None = None

    def without_rows(self, drop: np.ndarray, reason: str) -> None:
        """Leave out the rows ``drop`` (N,) marks from every per-row column, counted in
        ``rows_dropped`` with ``reason`` ("3 with a bad sensor reading (see the notes)")."""
        drop = np.asarray(drop, dtype=bool)
        if not drop.any():
            return
        keep = ~drop
        for name in ("positions", "errors", "temperatures", "velocities", "accelerations",
                     "directions", "direction_errors", "targets"):
            setattr(self, name, {k: v[keep] for k, v in getattr(self, name).items()})
        for name in ("time_s", "spindle_speed_rad_s", "run_of_row", "file_rows"):
            if getattr(self, name) is not None:
                setattr(self, name, getattr(self, name)[keep])
        self.rows_dropped += int(drop.sum())
        self.drop_reasons.append(reason)

    def summary(self, name: str) -> str:
        kept = self.rows_read - self.rows_dropped
        text = f"{name}: {kept} of {self.rows_read} rows used"
        if self.dialect_note:
            text += f" ({self.dialect_note})"
        if self.rows_dropped:
            text += f"; {self.rows_dropped} dropped ({'; '.join(self.drop_reasons[:3])})"
        return text


#: Rows parsed at once: a chunk whose every mapped cell is a finite number is converted
#: column by column; one with a bad row is parsed row by row (the same values, and each
#: bad row named).
CSV_CHUNK_ROWS = 4096


def _parse_clean_chunk(chunk: list[list[str]], header: list[str], index: dict[str, int],
                       values: dict[str, list], decimal_comma: bool = False,
                       dated: bool = False) -> bool:
    """Append ``chunk``'s mapped cells to ``values`` column by column and return True -
    or append nothing and return False when a row has the wrong number of fields, a
    numeric cell is not a finite number or a run cell is empty (then
    :func:`_parse_row` takes each row)."""
    width = len(header)
    if any(len(r) != width for r in chunk):
        return False
    parsed = {}
    for role, j in index.items():
        cells = [r[j] for r in chunk]
        if role == "run":
            cells = [c.strip() for c in cells]
            if not all(cells):
                return False
            parsed[role] = cells
            continue
        if role == "time" and dated:
            try:
                parsed[role] = [to_seconds(c) for c in cells]
            except ValueError:
                return False
            continue
        if decimal_comma:
            cells = [c.replace(",", ".") for c in cells]
        try:
            column = np.array(cells, dtype=np.float64)
        except ValueError:
            return False
        if not np.all(np.isfinite(column)):
            return False
        parsed[role] = column.tolist()
    for role, column in parsed.items():
        values[role].extend(column)
    return True


def _dated(row: list[str], column: int, dialect: CsvDialect) -> bool:
    """Whether a survey's time cell is a date-time rather than a number."""
    return column < len(row) and cell_kind(row[column], dialect) == "date-time"


def _parse_row(path: Path, row: list[str], number: int, header: list[str],
               index: dict[str, int], values: dict[str, list], bad_in_column: dict[str, int],
               first_bad: dict, decimal_comma: bool = False, dated: bool = False) -> str:
    """Append row ``number``'s mapped cells to ``values`` (SI scaling comes later); the
    reason it is dropped instead ("" when kept: then every role got its value)."""
    if len(row) != len(header):
        raise InputDataError(f"{path}: row {number} has {len(row)} fields, the header "
                             f"{len(header)}")
    parsed, problem = {}, ""
    for role, j in index.items():
        cell = row[j].strip()
        if role == "run":
            if not cell:
                problem = problem or f"row {number} column {header[j]}: empty run"
            parsed[role] = cell
            continue
        number_read = True
        try:
            value = to_seconds(cell) if role == "time" and dated else \
                float(cell.replace(",", ".") if decimal_comma else cell)
        except ValueError:
            value, number_read = math.nan, False
        if role.startswith("temp.") and (not cell or number_read and not math.isfinite(value)):
            # A thermocouple's gap (empty, nan, inf): kept as NaN, the sensors' judge
            # decides (named with its rows; the sensor or those rows left out). A word
            # there is a bad cell like any other.
            parsed[role] = math.nan
            continue
        if not math.isfinite(value):
            bad_in_column[role] += 1
            first_bad.setdefault(role, (number, cell))
            problem = problem or f"row {number} column {header[j]}: {cell[:20]!r}"
        parsed[role] = value
    if not problem:
        for role, value in parsed.items():
            values[role].append(value)
    return problem


def read_mapped_csv(path: str | Path, column_map: ColumnMap, *, min_rows: int = 20
                    ) -> MappedSurvey:
    """The mapped columns of ``path`` in SI units, rows with a bad mapped cell dropped."""
    path = Path(path)
    if not any(r.startswith("pos.") for r in column_map.roles):
        raise ParameterError("column map: no axis position column (pos.X=COLUMN)")
    if not any(r.startswith("err.") for r in column_map.roles):
        raise ParameterError("column map: no error column (err.x=COLUMN)")
    for role in column_map.roles:
        refuse_unknown_role(role)
    # Every unit before a row is read (a time of date-times needs none: when its first
    # cell is read).
    units = {role: role_unit(column_map, role) for role in column_map.roles
             if role not in ("run", "time")}
    scales = {role: si_scale(column_map.quantity(role), unit, role) if unit else (1.0, 0.0)
              for role, unit in units.items()}
    values = {role: [] for role in column_map.roles}
    bad_in_column = {role: 0 for role in column_map.roles}
    first_bad = {}
    dropped, reasons, kept_rows = 0, [], []
    # In chunks, never the whole file as strings: a survey of 100,000 rows held as lists
    # of cells took ~100 MB before the first number was parsed. Blank lines are skipped
    # and not counted: "row N" is the N-th non-blank row, the header being row 1.
    header, index, number = None, {}, 0
    dialect = sniff_dialect(path)
    comma, dated = dialect.decimal_comma, False
    with contextlib.closing(table_rows(path, dialect)) as reader:
        for row in reader:
            if "".join(row).strip():
                header = [h.strip() for h in row]
                number = 1
                break
        if header is not None:
            for role, (column, _) in column_map.roles.items():
                if column not in header:
                    raise InputDataError(f"{path}: no column {column!r} (for {role}); "
                                         f"columns: {', '.join(header)}")
                index[role] = header.index(column)
        while header is not None:
            chunk = [r for r in itertools.islice(reader, CSV_CHUNK_ROWS)
                     if "".join(r).strip()]
            if not chunk:
                break
            if number == 1 and "time" in index:
                dated = _dated(chunk[0], index["time"], dialect)
                units["time"] = "s" if dated else role_unit(column_map, "time")
                scales["time"] = si_scale("time", units["time"], "time")
            first = number + 1
            number += len(chunk)
            if _parse_clean_chunk(chunk, header, index, values, comma, dated):
                kept_rows.extend(range(first - 1, number))
                continue
            # A chunk with a bad row: row by row, each row's reason kept.
            for offset, row in enumerate(chunk):
                problem = _parse_row(path, row, first + offset, header, index, values,
                                     bad_in_column, first_bad, comma, dated)
                if problem:
                    dropped += 1
                    if len(reasons) < 5:
                        reasons.append(problem)
                    continue
                kept_rows.append(first + offset - 1)
    if header is None:
        raise InputDataError(f"{path}: empty file")
    total = number - 1
    for role, bad in bad_in_column.items():
        if total and bad > total / 2:
            number, cell = first_bad[role]
            raise InputDataError(f"{path}: column {column_map.roles[role][0]!r} ({role}) is not "
                                 f"numeric ({bad} of {total} rows; row {number}: {cell[:20]!r})")
    kept = total - dropped
    if kept < min_rows:
        raise InputDataError(f"{path}: {kept} usable rows; at least {min_rows} needed"
                             + (f" ({reasons[0]})" if reasons else ""))
    refuse_implausible(column_map, values, units)
    if dated:
        # Date-times are seconds already (the map's unit is for numbers); since the first.
        scales["time"] = (1.0, -values["time"][0] if values["time"] else 0.0)
    si = {role: np.asarray(v) * scales[role][0] + scales[role][1] for role, v in values.items()
          if role != "run"}
    run_of_row = run_names = None
    if "run" in values:
        from ..core.workbench.log_runs import run_labels, stitched_time

        data_rows = np.asarray(kept_rows, dtype=np.intp)
        run_of_row, run_names = run_labels(values["run"], data_rows, column_map.roles["run"][0])
        if "time" in si:
            si["time"] = stitched_time(si["time"], run_of_row, run_names, data_rows)
    if "time" in si:
        time_s = si["time"]
        # Equal stamps are a logger's resolution; only a stamp that goes back is refused.
        backwards = np.flatnonzero(np.diff(time_s) < 0)
        if backwards.size:
            raise InputDataError(f"{path}: the time column {column_map.roles['time'][0]!r} goes "
                                 f"back at data row {int(backwards[0]) + 2} (sort the file or "
                                 "fix the stamps; equal stamps are fine)")
    else:
        time_s = np.arange(kept) * column_map.row_period_s
    pick = lambda kind: {r.split(".", 1)[1].upper() if kind != "temp" else r.split(".", 1)[1]:  # noqa: E731
                         v for r, v in si.items() if r.startswith(kind + ".")}
    components = lambda kind: {r.split(".", 1)[1]: v for r, v in si.items()  # noqa: E731
                               if r.startswith(kind + ".")}
    return MappedSurvey(time_s, pick("pos"), components("err"), pick("temp"), pick("vel"),
                        pick("acc"), pick("dir"), si.get("spindle"), total, dropped, reasons,
                        run_of_row, run_names, dialect.note(), components("tdir"),
                        components("target"), np.asarray(kept_rows, dtype=np.intp) + 1)
