"""Compensation tables a CNC loads: per-axis bilateral tables and a volumetric parameter file.

Two exports of an :class:`~.error_model.ErrorModel`'s geometric part, each
with a reader, so that what was written can be read back, applied and
compared with the model (:func:`round_trip`):

* **Per-axis bilateral tables** (:func:`bilateral_tables`, the way laser
  software such as Renishaw CARTO exports a linear-axis run, and as an ISG
  ``kw.ssfk`` bilateral table holds it): for each linear axis, positions at a
  chosen spacing over the stroke, and for each of its six ISO 230-1 component
  errors a forward and a reverse column. The reverse column differs from the
  forward one by the axis' reversal value (the model's ``reversal`` effects):
  forward = E - b/2, reverse = E + b/2 on the positioning error.
* **A volumetric parameter file in the ISG CSV style** that Beckhoff's TF5280
  volumetric compensation reads (:func:`write_isg_csv`): whitespace-separated
  columns named in a header line, ``//`` comments, ``#`` before each new
  block; a block of the location errors (one row), then one block per axis
  with the axis position as the argument and its six component errors. The
  CNC's own kinematic model combines them, so the file carries parameters,
  not TCP errors.

Units in both files: positions and translational errors in millimetres
(rotary axes in degrees), rotational errors in microradians, stated in the
file's comments. Every value is written with 12 significant digits, so the
round trip is limited by the table spacing, not by the text.

Interpolation error (what :func:`round_trip` checks against): a CNC
interpolates linearly between table points; for a component error f with
spacing h the error is at most h^2/8 max|f''| (the linear-interpolation
remainder). :func:`interpolation_bound` evaluates it on the model.
"""
from __future__ import annotations

import io
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from ..errors import MachineDescriptionError, ParameterError
from ..kinematics.chain import KinematicModel
from ..kinematics.machine import MachineDescription
from .error_model import ErrorModel
from .tables import CompensationTable, machine_with_table
from .user_tables import refuse_untabled, user_tcp_error

MM_PER_M = 1e3
URAD_PER_RAD = 1e6


def _is_angle(name: str) -> bool:
    return name[1] in "ABC"


def _to_file(name: str, value_si):
    return np.asarray(value_si, float) * (URAD_PER_RAD if _is_angle(name) else MM_PER_M)


def _from_file(name: str, value_file):
    return np.asarray(value_file, float) / (URAD_PER_RAD if _is_angle(name) else MM_PER_M)


def table_grid(stroke: tuple[float, float], spacing: float, axis: str) -> NDArray[np.float64]:
    """Positions from the stroke's start at ``spacing``, the stroke's end always included.

    Parameters
    ----------
    stroke : tuple of float, (low, high)
        The axis' travel [m].
    spacing : float
        Table spacing [m].
    axis : str
        Axis letter, quoted in messages.

    Returns
    -------
    ndarray, shape (K,)
        Ascending positions [m], first ``low``, last exactly ``high``.

    Raises
    ------
    ParameterError
        A spacing that is not a positive number or exceeds the stroke.
    """
    length = stroke[1] - stroke[0]
    if not np.isfinite(spacing) or spacing <= 0:
        raise ParameterError(f"table spacing must be a positive number (got {spacing!r})")
    if spacing > length:
        unit, scale = ("mm", MM_PER_M)
        raise ParameterError(f"table spacing {spacing * scale:g} {unit} exceeds the {axis} stroke "
                             f"({length * scale:g} {unit})")
    count = int(np.floor(length / spacing + 1e-9))
    grid = stroke[0] + spacing * np.arange(count + 1)
    if stroke[1] - grid[-1] > 1e-9 * max(1.0, length):
        grid = np.append(grid, stroke[1])
    grid[-1] = stroke[1]     # exactly the stroke's end, not a sum of spacings
    return grid


@dataclass
class BilateralTable:
    """One linear axis: positions (n,) [m]; per ISO name, forward and reverse (n,) [m or rad].

    Parameters
    ----------
    axis : str
        Linear axis letter.
    positions_m : ndarray, shape (n,)
        Ascending table positions [m].
    forward, reverse : dict of str to ndarray, shape (n,)
        ISO 230-1 component error name -> values moving in the positive / negative
        direction [m] (translational) or [rad] (rotational).
    """

    axis: str
    positions_m: NDArray[np.float64]
    forward: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    reverse: dict[str, NDArray[np.float64]] = field(default_factory=dict)

    def at(self, position_m, direction: float) -> dict[str, NDArray[np.float64]]:
        """Linear interpolation of every column at ``position_m`` moving in ``direction``.

        Parameters
        ----------
        position_m : array_like, shape S
            Axis positions [m] (flat beyond the table's ends).
        direction : float
            Sign of the motion: >= 0 reads the forward columns, < 0 the reverse ones.

        Returns
        -------
        dict of str to ndarray, shape S
            ISO name -> interpolated error [m] or [rad].
        """
        columns = self.forward if direction >= 0 else self.reverse
        return {name: np.interp(position_m, self.positions_m, values)
                for name, values in columns.items()}


def bilateral_tables(model: ErrorModel, spacing_m: float) -> dict[str, BilateralTable]:
    """Per-axis bilateral tables of every linear axis (see module docstring).

    Parameters
    ----------
    model : ErrorModel
        The model whose geometric part and reversal values are exported.
    spacing_m : float
        Table spacing [m].

    Returns
    -------
    dict of str to BilateralTable
        Linear axis letter -> its table.

    Raises
    ------
    ParameterError
        A spacing that is not positive or exceeds an axis's stroke, or a fitted
        user effect no table can hold.
    """
    refuse_untabled(model)
    machine = model.machine
    linear = [a for a in machine.axis_order if not machine.axes[a].is_rotary]
    grids = {a: table_grid(machine.axes[a].stroke, spacing_m, a) for a in linear}
    out = {}
    for axis in linear:
        grid = grids[axis]
        errors = model.component_errors(axis, grid, strict=True)
        half = 0.5 * model.backlash_m(axis)
        positioning = f"E{axis}{axis}"
        forward = dict(errors)
        reverse = dict(errors)
        forward[positioning] = errors[positioning] - half
        reverse[positioning] = errors[positioning] + half
        out[axis] = BilateralTable(axis, grid, forward, reverse)
    return out


def write_bilateral_csv(table: BilateralTable, machine_name: str) -> str:
    """CSV text of one axis' bilateral table (header line of columns, ``#`` comments).

    Parameters
    ----------
    table : BilateralTable
        The table, in SI units.
    machine_name : str
        Machine name written in the header comment.

    Returns
    -------
    str
        CSV text: positions [mm], translational errors [mm], rotational errors [urad].
    """
    names = list(table.forward)
    text = io.StringIO()
    text.write(f"# mt_accuracy_ros bilateral axis table v1\n# machine: {machine_name}\n"
               f"# axis: {table.axis}\n# units: position mm; translational errors mm; "
               "rotational errors urad\n# forward: moving in the positive direction; reverse: "
               "in the negative direction\n")
    header = ["position_mm"] + [f"{n}_{way}" for n in names for way in ("forward", "reverse")]
    text.write(",".join(header) + "\n")
    for i, position in enumerate(table.positions_m):
        row = [position * MM_PER_M]
        for name in names:
            row += [_to_file(name, table.forward[name][i]), _to_file(name, table.reverse[name][i])]
        text.write(",".join(f"{float(v):.12g}" for v in row) + "\n")
    return text.getvalue()


def read_bilateral_csv(text: str) -> BilateralTable:
    """Parse :func:`write_bilateral_csv`'s text; errors name the line.

    Parameters
    ----------
    text : str
        The CSV text (positions [mm], errors [mm] / [urad]).

    Returns
    -------
    BilateralTable
        The table in SI units ([m], [rad]).

    Raises
    ------
    MachineDescriptionError
        A bad header, a row of the wrong length, a non-number or non-finite value,
        fewer than two rows, no ``# axis:`` line, or positions not increasing.
    """
    axis = ""
    header: list[str] = []
    rows: list[list[float]] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            if line.startswith("# axis:"):
                axis = line.split(":", 1)[1].strip()
            continue
        fields = line.split(",")
        if not header:
            header = fields
            if header[0] != "position_mm" or (len(header) - 1) % 2:
                raise MachineDescriptionError(f"line {number}: expected 'position_mm' and "
                                              "forward/reverse column pairs")
            continue
        if len(fields) != len(header):
            raise MachineDescriptionError(f"line {number}: {len(fields)} values for "
                                          f"{len(header)} columns")
        try:
            values = [float(f) for f in fields]
        except ValueError as exc:
            raise MachineDescriptionError(f"line {number}: not a number ({exc})") from exc
        if not np.all(np.isfinite(values)):
            raise MachineDescriptionError(f"line {number}: non-finite value")
        rows.append(values)
    if not axis or not header or len(rows) < 2:
        raise MachineDescriptionError("bilateral table: needs '# axis:', a header and 2 rows")
    data = np.asarray(rows)
    positions = data[:, 0] / MM_PER_M
    if np.any(np.diff(positions) <= 0):
        raise MachineDescriptionError("bilateral table: positions must increase")
    table = BilateralTable(axis, positions)
    for j in range(1, len(header), 2):
        name = header[j].rsplit("_", 1)[0]
        table.forward[name] = _from_file(name, data[:, j])
        table.reverse[name] = _from_file(name, data[:, j + 1])
    return table


# ------------------------------------------------------------ volumetric (ISG CSV)
def write_isg_csv(model: ErrorModel, spacing_m: float) -> str:
    """The model's geometric parameters as an ISG-CSV-style volumetric parameter file.

    Parameters
    ----------
    model : ErrorModel
        The model whose geometric part is exported.
    spacing_m : float
        Table spacing [m].

    Returns
    -------
    str
        The file's text: positions [mm], translational errors [mm], rotational errors [urad].

    Raises
    ------
    ParameterError
        A bad spacing, or a fitted user effect no table can hold.
    """
    refuse_untabled(model)
    machine = model.machine
    linear = [a for a in machine.axis_order if not machine.axes[a].is_rotary]
    grids = {a: table_grid(machine.axes[a].stroke, spacing_m, a) for a in linear}
    text = io.StringIO()
    text.write(f"// mt_accuracy_ros volumetric compensation parameters v1\n"
               f"// machine: {machine.name}  chain: {machine.chain}\n"
               "// units: positions mm (rotary deg); translational errors mm; rotational "
               "errors urad\n")
    location = model.location_table()
    if location:
        text.write("// location errors (constant)\n")
        text.write(" ".join(location) + "\n")
        text.write(" ".join(f"{float(_to_file(n, v)):.12g}" for n, v in location.items()) + "\n")
    for axis, grid in grids.items():
        errors = model.component_errors(axis, grid, strict=True)
        text.write("#\n")
        text.write(f"// component errors of the {axis} axis (direction-independent part)\n")
        text.write(" ".join([axis, *errors]) + "\n")
        for i, position in enumerate(grid):
            text.write(" ".join(f"{float(v):.12g}" for v in
                                [position * MM_PER_M] + [float(_to_file(n, values[i]))
                                                         for n, values in errors.items()]) + "\n")
    return text.getvalue()


def read_isg_csv(text: str) -> CompensationTable:
    """Parse :func:`write_isg_csv`'s text (``//`` comments, ``#`` block breaks) into the
    per-axis grids, component errors and location errors of a :class:`~.tables.CompensationTable`
    (apply it with :func:`~.tables.machine_with_table`).

    Parameters
    ----------
    text : str
        The file's text ([mm], [urad]).

    Returns
    -------
    CompensationTable
        Grids [m], component errors and location errors [m] or [rad].

    Raises
    ------
    MachineDescriptionError
        A row of the wrong length, a non-number or non-finite value, an empty block,
        or no axis block.
    """
    machine = ""
    grids: dict[str, NDArray] = {}
    components: dict[str, dict[str, NDArray]] = {}
    location: dict[str, float] = {}
    blocks: list[list[tuple[int, list[str]]]] = [[]]
    for number, raw in enumerate(text.splitlines(), start=1):
        if raw.startswith("// machine:"):
            named = raw.split(":", 1)[1].split()
            machine = named[0] if named else ""
        line = raw.split("//", 1)[0].strip()
        if not line:
            continue
        if line == "#":
            blocks.append([])
            continue
        blocks[-1].append((number, line.split()))
    for block in blocks:
        if not block:
            continue
        (number, header), rows = block[0], block[1:]
        values = []
        for line_number, fields in rows:
            if len(fields) != len(header):
                raise MachineDescriptionError(f"volumetric file, line {line_number}: "
                                              f"{len(fields)} values; rows must have "
                                              f"{len(header)} (header at line {number})")
            try:
                values.append([float(v) for v in fields])
            except ValueError as exc:
                raise MachineDescriptionError(f"volumetric file, line {line_number}: not a "
                                              f"number ({exc})") from exc
        data = np.asarray(values, dtype=np.float64).reshape(-1, len(header))
        if data.shape[0] == 0:
            raise MachineDescriptionError(f"volumetric file, block at line {number}: no rows")
        if not np.all(np.isfinite(data)):
            raise MachineDescriptionError(f"volumetric file, block at line {number}: non-finite")
        if len(header[0]) == 1:          # an axis argument: component errors
            axis = header[0]
            grids[axis] = data[:, 0] / MM_PER_M
            components[axis] = {name: _from_file(name, data[:, j])
                                for j, name in enumerate(header[1:], start=1)}
        else:
            location.update({name: float(_from_file(name, data[0, j]))
                             for j, name in enumerate(header)})
    if not grids:
        raise MachineDescriptionError("volumetric file: no axis block")
    return CompensationTable(machine=machine, grids=grids, errors=components, location=location)


# ------------------------------------------------------------------- round trip
def interpolation_bound(function_values: NDArray, dense_positions: NDArray,
                        spacing: float) -> float:
    """h^2/8 max|f''| with f'' by finite differences on a dense grid.

    Parameters
    ----------
    function_values : ndarray, shape (M,)
        f on ``dense_positions`` (unit-agnostic: the bound has f's unit).
    dense_positions : ndarray, shape (M,)
        Ascending positions, same unit as ``spacing``.
    spacing : float
        Table spacing h.

    Returns
    -------
    float
        Bound on the linear-interpolation error, in f's unit (0 for fewer than 3 points).
    """
    if dense_positions.size < 3:
        return 0.0
    second = np.gradient(np.gradient(function_values, dense_positions), dense_positions)
    return float(spacing ** 2 / 8.0 * np.max(np.abs(second)))


@dataclass
class RoundTrip:
    """Table (written, read back) minus model, per axis column and at the TCP.

    Parameters
    ----------
    spacing_m : float
        Table spacing [m].
    column_max_error : dict of str to float
        ISO name -> max |table - model| [m or rad].
    column_bound : dict of str to float
        ISO name -> h^2/8 max|f''| [m or rad].
    tcp_max_error_m, tcp_rms_error_m : float
        Largest and RMS TCP gap between the applied file and the model [m].
    tcp_bound_m : float
        Column bounds propagated to the TCP through the Abbe arm [m].
    tcp_model_rms_m : float
        RMS of the model's geometric TCP error itself [m].
    """

    spacing_m: float
    column_max_error: dict[str, float]        # ISO name -> max |table - model| [m or rad]
    column_bound: dict[str, float]            # ISO name -> h^2/8 max|f''|
    tcp_max_error_m: float
    tcp_rms_error_m: float
    tcp_bound_m: float
    tcp_model_rms_m: float

    def as_dict(self) -> dict:
        return {"spacing_m": self.spacing_m, "column_max_error": self.column_max_error,
                "column_bound": self.column_bound, "tcp_max_error_m": self.tcp_max_error_m,
                "tcp_rms_error_m": self.tcp_rms_error_m, "tcp_bound_m": self.tcp_bound_m,
                "tcp_model_rms_m": self.tcp_model_rms_m}


def _reference_machine(model: ErrorModel, dense: int = 4001) -> MachineDescription:
    """The model's geometric part as a machine with very fine tables (the reference),
    without its user effects: those are added at the TCP from their expressions
    (:func:`user_tcp_error`), so that their conversion to error motions is checked."""
    machine = model.machine
    grids = {a: np.linspace(*machine.axes[a].stroke, dense) for a in machine.axis_order
             if not machine.axes[a].is_rotary}
    return machine_with_table(machine, CompensationTable(
        machine.name, grids, {a: model.component_errors(a, g, include_user=False)
                              for a, g in grids.items()},
        model.location_table()))


def round_trip(model: ErrorModel, spacing_m: float, *, points: int = 2000,
               seed: int = 0) -> RoundTrip:
    """Write both files, read them back, apply them and compare with the model.

    Columns: each bilateral column read back, interpolated at ``points`` random
    positions, against the model's component error there. TCP: the read-back
    volumetric file through the kinematic chain against the model's geometric
    TCP error at ``points`` random configurations (rotary axes included).
    The TCP bound propagates each column's bound through its Abbe arm.

    Parameters
    ----------
    model : ErrorModel
        The model exported.
    spacing_m : float
        Table spacing [m].
    points : int, optional
        Random positions / configurations compared.
    seed : int, optional
        Seed of the random positions.

    Returns
    -------
    RoundTrip
        Errors and bounds [m] / [rad].

    Raises
    ------
    ParameterError
        A bad spacing, or a fitted user effect no table can hold.
    """
    rng = np.random.default_rng(seed)
    machine = model.machine
    tables = {a: read_bilateral_csv(write_bilateral_csv(t, machine.name))
              for a, t in bilateral_tables(model, spacing_m).items()}
    column_error, column_bound = {}, {}
    for axis, table in tables.items():
        stroke = machine.axes[axis].stroke
        at = rng.uniform(*stroke, points)
        dense = np.linspace(*stroke, 4001)
        truth_at = model.component_errors(axis, at, strict=True)
        truth_dense = model.component_errors(axis, dense, strict=True)
        half = 0.5 * model.backlash_m(axis)
        for direction in (1.0, -1.0):
            read = table.at(at, direction)
            for name, values in read.items():
                expected = truth_at[name] - (direction * half if name == f"E{axis}{axis}" else 0)
                column_error[name] = max(column_error.get(name, 0.0),
                                         float(np.max(np.abs(values - expected))))
        for name, values in truth_dense.items():
            column_bound[name] = interpolation_bound(values, dense, spacing_m)
    parameters = machine_with_table(machine, read_isg_csv(write_isg_csv(model, spacing_m)))
    q = {a: rng.uniform(*machine.axes[a].stroke, points) for a in machine.axis_order}
    reference = KinematicModel(_reference_machine(model)).tcp_error(
        q, check_stroke=False)["position"] + user_tcp_error(model, q)
    applied = KinematicModel(parameters).tcp_error(
        q, check_stroke=False)["position"]
    gap = np.linalg.norm(applied - reference, axis=1)
    reach = max(np.linalg.norm(machine.tool) + sum(np.linalg.norm(machine.axes[a].offset)
                                                   for a in machine.axis_order)
                + sum(abs(v) for a in machine.axis_order
                      for v in machine.axes[a].stroke if not machine.axes[a].is_rotary), 1e-3)
    tcp_bound = sum(bound * (reach if _is_angle(name) else 1.0)
                    for name, bound in column_bound.items())
    return RoundTrip(spacing_m, column_error, column_bound, float(gap.max()),
                     float(np.sqrt(np.mean(gap ** 2))), float(tcp_bound),
                     float(np.sqrt(np.mean(np.sum(reference ** 2, axis=1)))))



@dataclass(frozen=True)
class CarriedEffect:
    """How much of one fitted geometric effect the volumetric file carries to the TCP.

    Parameters
    ----------
    name : str
        The model's effect name, e.g. ``rotary_location:AC``.
    model_rms_m : float
        RMS of the effect's own TCP error over random configurations [m].
    gap_rms_m : float
        RMS of the file's TCP error for it minus the model's [m].
    """

    name: str
    model_rms_m: float
    gap_rms_m: float

    @property
    def carried(self) -> bool:
        """Whether the file holds it to within a tenth of its size (a left-out effect
        leaves all of it; a held one only the tables' interpolation and second order)."""
        return self.gap_rms_m <= CARRIED_SHARE * self.model_rms_m


#: A file carries an effect when it leaves at most this share of the effect's RMS.
CARRIED_SHARE = 0.1

#: Families that describe the instrument's set-up, not the machine: where a survey's work
#: (or tool) was located. A new part set-up takes out its own, so no file carries them.
SET_UP_FAMILIES = ("setup_location",)


def carried_effects(model: ErrorModel, spacing_m: float, *, points: int = 400,
                    seed: int = 0) -> list[CarriedEffect]:
    """Each fitted geometric catalogue effect (group ``geometric`` or ``rotary``: functions
    of the positions alone; not a survey's set-up, :data:`SET_UP_FAMILIES`) through the
    volumetric file, against the model: the effect's
    TCP error is the model's with it minus without it, at the CNC's commands (not referred
    to a datum), and the file's alike - each written, read back and applied through the
    chain. A second formulation of what :func:`round_trip` checks, on the model's own
    predictions rather than on its tables, so an effect no table holds is seen.

    The chain turns each rotary body about its actual line from its set-up angle; the
    model reads a rotary line's errors as an instrument located at the set-up does (the
    body turned by the raw command, the part's set-up error turning with the work,
    :meth:`~..kinematics.chain.KinematicModel.located_sensitivities`). The two agree where
    every rotary axis is set up at 0, and for the last axis of each side; an outer axis set
    up elsewhere is read otherwise by this check (the file's values are the ISO 230-7
    line errors either way), and its gap is reported, not hidden.

    Parameters
    ----------
    model : ErrorModel
        The model exported.
    spacing_m : float
        Table spacing [m].
    points : int, optional
        Random configurations compared (rotary axes over their strokes).
    seed : int, optional
        Seed of the configurations.

    Returns
    -------
    list of CarriedEffect
        One per fitted geometric catalogue effect, in the model's order.
    """
    from ..effects import family_named, is_catalogue_entry

    rng = np.random.default_rng(seed)
    machine = model.machine
    q = {a: rng.uniform(*machine.axes[a].stroke, points) for a in machine.axis_order}

    # The description's location errors left out of both files alike: a table's location
    # entries replace an axis' own, so with them in the machine an effect's file would be
    # compared against the description's.
    bare = replace(machine, axes={name: replace(axis, location_errors={})
                                  for name, axis in machine.axes.items()})

    def through_file(of: ErrorModel) -> NDArray[np.float64]:
        applied = machine_with_table(bare, read_isg_csv(write_isg_csv(of, spacing_m)))
        return KinematicModel(applied).tcp_error(q, check_stroke=False)["position"]

    def through_model(of: ErrorModel) -> NDArray[np.float64]:
        return of.tcp_error(q, referred=False)[0]       # a file is not referred to a datum

    # The geometric catalogue effects alone: the others need temperatures or feeds, which
    # a file of positions does not take, and each effect's part is its own either way.
    geometric = {name: entry for name, entry in model.effects.items()
                 if is_catalogue_entry(entry) and "family" in entry and
                 entry["family"] not in SET_UP_FAMILIES and
                 family_named(entry["family"]).group in ("geometric", "rotary")}
    model = replace(model, effects=geometric)
    file_with, model_with = through_file(model), through_model(model)
    out = []
    for name in geometric:
        without = model.without_effect(name)
        own = model_with - through_model(without)
        gap = (file_with - through_file(without)) - own
        out.append(CarriedEffect(name, float(np.sqrt(np.mean(np.sum(own ** 2, axis=1)))),
                                 float(np.sqrt(np.mean(np.sum(gap ** 2, axis=1))))))
    return out
