"""Declarative machine descriptions (YAML) for the kinematic error model.

A description names the kinematic chain in ISO 10791-1 notation, e.g.
Kidani's horizontal machining centre ``[w Z b X Y t]`` (workpiece on Z, bed,
tool on X then Y) or Khan & Chen's RPPPR grinder ``[w A X b Y Z B t]``.
Upper-case letters are axes (X, Y, Z linear along x, y, z; A, B, C rotary
about x, y, z); ``w``, ``b``, ``t`` are workpiece, bed and tool.

For each axis: its stroke, the ``offset`` (Kidani's L_*: the position of the
next body's origin in this axis' moving frame, e.g. [L_XY, L_YY, L_ZY] for Y),
its six error motions in ISO 230-1 names (EXX, EYX, EZX, EAX, EBX, ECX for X)
and its location errors (EX0Y ... EC0Y; e.g. the squareness EC0Y).
"""
from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .error_functions import ErrorFunction, parse_error_function
from ..errors import MachineDescriptionError, reraise_as
from ..inputs.safe_files import load_yaml, plain_name, read_description

AXIS_LETTERS = "XYZABC"
COMPONENTS = "XYZABC"  # error motion components: translations X, Y, Z; rotations A, B, C
_DIRECTION = {"X": 0, "Y": 1, "Z": 2, "A": 0, "B": 1, "C": 2}


def motion_error_name(component: str, axis: str) -> str:
    """ISO 230-1 name of a position-dependent error, e.g. ('C', 'X') -> 'ECX'.

    Parameters
    ----------
    component : {"X", "Y", "Z", "A", "B", "C"}
        Error component: translation along or rotation about x, y, z.
    axis : str
        Axis letter the error belongs to.

    Returns
    -------
    str
        The name ``E<component><axis>``.
    """
    return f"E{component}{axis}"


def location_error_name(component: str, axis: str) -> str:
    """ISO 230-1 name of a location error, e.g. ('C', 'Y') -> 'EC0Y' (squareness).

    Parameters
    ----------
    component : {"X", "Y", "Z", "A", "B", "C"}
        Error component: offset along or tilt about x, y, z.
    axis : str
        Axis letter the error belongs to.

    Returns
    -------
    str
        The name ``E<component>0<axis>``.
    """
    return f"E{component}0{axis}"


@dataclass(frozen=True)
class Axis:
    """One axis of the chain.

    Parameters
    ----------
    name : str
        Axis letter, one of X, Y, Z (linear) or A, B, C (rotary).
    stroke : tuple of float, (low, high)
        Travel [m] (linear) or [rad] (rotary).
    offset : ndarray, shape (3,)
        Position of the next body in this axis' frame [m] (Kidani's L_*).
    sign : float
        +1, or -1 when positive command moves the body backwards.
    motion_errors : dict of str to ErrorFunction
        Component letter -> error function of the position (6 entries), values in
        [m] (X, Y, Z) or [rad] (A, B, C).
    location_errors : dict of str to float
        Component letter -> value [m] (X, Y, Z) or [rad] (A, B, C), declared ones only.

    Attributes
    ----------
    is_rotary : bool
        True for A, B, C.
    direction : int
        Index 0, 1, 2 of the direction (x, y, z) the axis moves along or turns about.
    """

    name: str
    stroke: tuple[float, float]
    offset: np.ndarray
    sign: float = 1.0
    motion_errors: dict[str, ErrorFunction] = field(default_factory=dict)
    location_errors: dict[str, float] = field(default_factory=dict)

    @property
    def is_rotary(self) -> bool:
        return self.name in "ABC"

    @property
    def direction(self) -> int:
        return _DIRECTION[self.name]


@dataclass(frozen=True)
class MachineDescription:
    """A parsed machine description.

    ``workpiece_branch`` and ``tool_branch`` list axis letters from the bed
    outwards (Khan & Chen's N and M loops).

    Parameters
    ----------
    name : str
        Machine name.
    chain : str
        ISO 10791-1 chain string, e.g. ``"[w Z b X Y t]"``.
    workpiece_branch, tool_branch : tuple of str
        Axis letters of each branch from the bed outwards.
    axes : dict of str to Axis
        Axis letter -> axis.
    tool : ndarray, shape (3,)
        Tool tip in the last tool-side frame [m].
    workpiece : ndarray, shape (3,)
        Workpiece point in the last workpiece-side frame [m].
    description : str
        Free text.
    scale_distance_m : dict of str to float
        Axis -> distance between its two linear scales [m] (dual-scale yaw).
    structure_length_m : float or None
        See the attribute comment above.
    cnc : dict
        Validated compensation limits (keys of :data:`CNC_KEYS`, SI units).
    abbe_arms_known : bool
        See the attribute comment above.
    setup_pose : dict of str to float
        Rotary axis -> set-up command [rad].
    setup_notes : tuple of str
        Assumptions made reading the set-up pose.
    """

    name: str
    chain: str
    workpiece_branch: tuple[str, ...]
    tool_branch: tuple[str, ...]
    axes: dict[str, Axis]
    tool: np.ndarray
    workpiece: np.ndarray
    description: str = ""
    scale_distance_m: dict[str, float] = field(default_factory=dict)
    #: Length of structure between a temperature sensor and the tool [m] that can
    #: expand (bounds thermal gains); None = estimated from the chain's dimensions.
    structure_length_m: float | None = None
    #: The controller's compensation limits (``cnc:`` in the YAML; see
    #: :mod:`mt_accuracy_ros.core.compensation.limits`), validated numbers.
    cnc: dict = field(default_factory=dict)
    #: False for a machine known only from a survey (:func:`generic_cartesian`): its
    #: offsets are not known, so a tilt's Abbe arm along the tool is fitted, not assumed
    #: (the workbench then offers ``angular_arm``).
    abbe_arms_known: bool = True
    #: Where the work (the part, an R-test's or a probed sphere) and the tool were set
    #: up: rotary axis -> command [rad]; an axis not named was at 0. A rotary axis'
    #: location errors (ISO 230-7) turn the body about the actual axis line *from this
    #: pose*: at it the body is where the set-up found it (:mod:`.chain`).
    setup_pose: dict[str, float] = field(default_factory=dict)
    #: What reading the set-up pose assumed, one sentence each (an angle of a continuous
    #: axis taken modulo a full turn: :func:`setup_angle_in_stroke`).
    setup_notes: tuple[str, ...] = ()

    def setup_angle(self, axis: str) -> float:
        """The set-up command of rotary ``axis`` [rad] (0 when the set-up pose omits it).

        Parameters
        ----------
        axis : str
            Rotary axis letter.

        Returns
        -------
        float
            Set-up command [rad].
        """
        return float(self.setup_pose.get(axis, 0.0))

    @property
    def axis_order(self) -> tuple[str, ...]:
        return self.workpiece_branch + self.tool_branch

    def check_positions(self, positions: dict[str, np.ndarray], tolerance: float = 1e-9) -> None:
        """Raise :class:`MachineDescriptionError` for unknown axes or positions outside the
        stroke.

        Parameters
        ----------
        positions : dict of str to ndarray, shape (N,)
            Axis positions [m] (rotary [rad]).
        tolerance : float, optional
            Allowance beyond the stroke's ends, in the axis' unit [m] or [rad].

        Raises
        ------
        MachineDescriptionError
            An unknown axis, a non-finite position or one outside the stroke.
        """
        for name, values in positions.items():
            if name not in self.axes:
                raise MachineDescriptionError(f"unknown axis {name!r}; this machine has "
                                              f"{', '.join(self.axis_order)}")
            low, high = self.axes[name].stroke
            values = np.asarray(values, dtype=np.float64)
            if not np.all(np.isfinite(values)):
                raise MachineDescriptionError(f"axis {name}: non-finite position")
            if values.size and (values.min() < low - tolerance or values.max() > high + tolerance):
                raise MachineDescriptionError(
                    f"axis {name}: position {values.min():.6g} .. {values.max():.6g} outside "
                    f"the stroke [{low:.6g}, {high:.6g}]")


_CHAIN = re.compile(r"^\[\s*w((?:\s+[XYZABC])*)\s+b((?:\s+[XYZABC])*)\s+t\s*\]$")


def outer_zeros(machine: MachineDescription, axes: str) -> list[str]:
    """The zero-angle errors of the rotary axes that carry one of ``axes`` on its side.

    An outer axis' zero error e turns the body by q + e about its line (ISO 230-7), and
    with it the lines of the rotary axes it carries: a sphere located at the set-up (by a
    translation) then reads it exactly as the carried line turned by e about the outer
    line - a tilt e of that line and an offset e x (its origin's arm from the outer line)
    (:meth:`~.chain.KinematicModel.located_sensitivities`).

    Parameters
    ----------
    machine : MachineDescription
        The machine.
    axes : str
        Rotary axis letters, e.g. ``"C"`` or ``"BC"``.

    Returns
    -------
    list of str
        ISO names, e.g. ``["EB0B"]`` for ``"C"`` on a ``[w C B X Y b Z t]`` trunnion.
    """
    out = []
    for branch in (machine.workpiece_branch, machine.tool_branch):
        for axis in axes:
            if axis not in branch:
                continue
            # The branch runs from the bed outwards: the axes before this one carry it.
            for outer in branch[:branch.index(axis)]:
                name = f"E{outer}0{outer}"
                if machine.axes[outer].is_rotary and name not in out:
                    out.append(name)
    return out


def parse_chain(chain: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Workpiece and tool branches (from the bed outwards) of an ISO 10791-1 chain string.

    ``"[w Z b X Y t]"`` -> ``(("Z",), ("X", "Y"))``.

    Parameters
    ----------
    chain : str
        Chain string ``[w <axes> b <axes> t]``, axes from X, Y, Z, A, B, C.

    Returns
    -------
    workpiece : tuple of str
        Workpiece-side axes from the bed outwards.
    tool : tuple of str
        Tool-side axes from the bed outwards.

    Raises
    ------
    MachineDescriptionError
        Not a string of that form, or an axis named twice.
    """
    if not isinstance(chain, str):
        raise MachineDescriptionError(
            f"chain: expected a string like '[w Z b X Y t]', got {chain!r}")
    match = _CHAIN.match(chain.strip())
    if not match:
        raise MachineDescriptionError(
            f"chain: {chain!r} is not of the form '[w <axes> b <axes> t]' with axes from "
            f"{', '.join(AXIS_LETTERS)} (e.g. '[w Z b X Y t]')")
    workpiece = tuple(reversed(match.group(1).split()))
    tool = tuple(match.group(2).split())
    letters = workpiece + tool
    if len(set(letters)) != len(letters):
        raise MachineDescriptionError(f"chain: {chain!r} names an axis twice")
    return workpiece, tool


def _vector(spec, where: str) -> np.ndarray:
    try:
        vector = np.asarray(spec, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise MachineDescriptionError(f"{where}: expected three numbers [m], got {spec!r}") from exc
    if vector.shape != (3,) or not np.all(np.isfinite(vector)):
        raise MachineDescriptionError(f"{where}: expected three finite numbers [m], got {spec!r}")
    return vector


@reraise_as(MachineDescriptionError, "machine description")
def machine_from_dict(data: dict, source: str = "<dict>",
                      replaced_setup: Mapping[str, str] | None = None) -> MachineDescription:
    """Build and validate a description from its parsed YAML mapping.

    Parameters
    ----------
    data : dict
        The YAML mapping: ``name``, ``chain``, ``axes``, ``tool``, ``workpiece`` required;
        lengths in [m], angles in [rad] unless written ``{value: .., unit: ..}``.
    source : str, optional
        Where ``data`` came from, quoted in error messages.
    replaced_setup : mapping of str to str, optional
        Rotary axis -> who gives its set-up instead (:func:`read_setup_pose`).

    Returns
    -------
    MachineDescription
        The validated description.

    Raises
    ------
    MachineDescriptionError
        Any missing, malformed, non-finite or out-of-stroke entry (other errors
        raised inside are re-raised as this one).
    """
    if not isinstance(data, dict):
        raise MachineDescriptionError(f"{source}: top level must be a mapping")
    for key in ("name", "chain", "axes", "tool", "workpiece"):
        if key not in data:
            raise MachineDescriptionError(f"{source}: missing required field '{key}'")
    workpiece_branch, tool_branch = parse_chain(data["chain"])
    axes_spec = data["axes"]
    if not isinstance(axes_spec, dict):
        raise MachineDescriptionError(f"{source}: 'axes' must map axis letters to their data")
    unknown = set(axes_spec) - set(workpiece_branch + tool_branch)
    if unknown:
        raise MachineDescriptionError(
            f"{source}: axes.{sorted(unknown)[0]} is not in the chain {data['chain']!r}")
    axes: dict[str, Axis] = {}
    for letter in workpiece_branch + tool_branch:
        where = f"{source}: axes.{letter}"
        if letter not in axes_spec:
            raise MachineDescriptionError(f"{where}: missing (the chain names axis {letter})")
        spec = axes_spec[letter] or {}
        for key in ("stroke", "offset"):
            if key not in spec:
                raise MachineDescriptionError(f"{where}: missing required field '{key}'")
        stroke = _stroke(spec["stroke"], letter, f"{where}.stroke")
        offset = _vector(spec["offset"], f"{where}.offset")
        sign = float(spec.get("sign", 1.0))
        if sign not in (1.0, -1.0):
            raise MachineDescriptionError(f"{where}.sign: must be 1 or -1")
        errors_spec = spec.get("errors", {}) or {}
        motion: dict[str, ErrorFunction] = {}
        for name in errors_spec:
            if not re.fullmatch(rf"E[{COMPONENTS}]{letter}", str(name)):
                raise MachineDescriptionError(
                    f"{where}.errors.{name}: not an error of axis {letter} "
                    "(expected one of "
                    f"{', '.join(motion_error_name(c, letter) for c in COMPONENTS)})")
        for component in COMPONENTS:
            name = motion_error_name(component, letter)
            motion[component] = parse_error_function(errors_spec.get(name, 0.0),
                                                     f"{where}.errors.{name}")
        location: dict[str, float] = {}
        for name, value in (spec.get("location_errors", {}) or {}).items():
            match = re.fullmatch(rf"E([{COMPONENTS}])0{letter}", str(name))
            if not match:
                raise MachineDescriptionError(
                    f"{where}.location_errors.{name}: expected E<X|Y|Z|A|B|C>0{letter}")
            value = float(value)
            if not np.isfinite(value):
                raise MachineDescriptionError(f"{where}.location_errors.{name}: non-finite")
            location[match.group(1)] = value
        axes[letter] = Axis(name=letter, stroke=(float(stroke[0]), float(stroke[1])),
                            offset=offset, sign=sign, motion_errors=motion,
                            location_errors=location)
    setup_notes: list[str] = []
    return MachineDescription(
        name=str(data["name"]), chain=str(data["chain"]), workpiece_branch=workpiece_branch,
        tool_branch=tool_branch, axes=axes, tool=_vector(data["tool"], f"{source}: tool"),
        workpiece=_vector(data["workpiece"], f"{source}: workpiece"),
        description=str(data.get("description", "")),
        scale_distance_m={str(k): float(v)
                          for k, v in (data.get("scale_distance_m") or {}).items()},
        structure_length_m=_positive_or_none(data.get("structure_length_m"),
                                             f"{source}: structure_length_m"),
        cnc=_cnc_section(data.get("cnc"), f"{source}: cnc"),
        setup_pose=read_setup_pose(data.get("setup_pose"), axes, f"{source}: setup_pose",
                                   setup_notes, replaced_setup),
        setup_notes=tuple(setup_notes))


#: Angle units a rotary stroke or a set-up angle may be given in (to rad).
ANGLE_UNITS = {"rad": 1.0, "mrad": 1e-3, "deg": np.pi / 180.0}
#: Length units a linear stroke may be given in (to m).
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "in": 0.0254}
#: The largest rotary travel a bare list is taken as radians for: beyond two turns and a
#: little it is degrees written without their unit.
_MAX_BARE_RAD = 2.0 * 2.0 * np.pi + 1e-6


def _stroke(spec, letter: str, where: str) -> np.ndarray:
    """[low, high] in SI (m, rad): a bare list (SI) or ``{value: [lo, hi], unit: deg}``.

    A bare rotary stroke beyond two turns is refused as degrees written without a unit.
    """
    rotary = letter in "ABC"
    units = ANGLE_UNITS if rotary else LENGTH_UNITS
    scale = 1.0
    if isinstance(spec, dict):
        if set(spec) != {"value", "unit"}:
            raise MachineDescriptionError(f"{where}: expected [low, high] or {{value: [low, high],"
                                          f" unit: {'deg' if rotary else 'mm'}}}")
        unit = str(spec["unit"])
        if unit not in units:
            raise MachineDescriptionError(f"{where}: unit {unit!r} is not one of "
                                          f"{', '.join(units)}")
        scale, spec = units[unit], spec["value"]
    try:
        stroke = np.asarray(spec, dtype=np.float64) * scale
    except (TypeError, ValueError) as exc:
        raise MachineDescriptionError(f"{where}: expected [low, high], got {spec!r}") from exc
    if stroke.shape != (2,) or not np.all(np.isfinite(stroke)) or stroke[1] <= stroke[0]:
        raise MachineDescriptionError(f"{where}: expected [low, high] with low < high")
    if rotary and scale == 1.0 and np.max(np.abs(stroke)) > _MAX_BARE_RAD:
        raise MachineDescriptionError(
            f"{where}: [{stroke[0]:g}, {stroke[1]:g}] rad is more than two turns - degrees? "
            f"write {{value: [{stroke[0]:g}, {stroke[1]:g}], unit: deg}}")
    return stroke


def angle_with_unit(value, where: str, error: type[Exception],
                    units: dict[str, float] | None = None) -> float:
    """``{value: -90, unit: deg}`` -> rad; a bare number, an unknown unit or a value that
    is not a finite number is refused with ``error`` naming ``where`` and the mend.

    Parameters
    ----------
    value : dict
        ``{value: <number>, unit: <str>}``.
    where : str
        Where the angle sits, quoted in the message.
    error : type of Exception
        The package error class to raise.
    units : dict of str to float, optional
        Unit name -> factor to [rad]; :data:`ANGLE_UNITS` by default.

    Returns
    -------
    float
        The angle [rad].

    Raises
    ------
    error
        A bare number, an unknown unit or a non-finite value.
    """
    units = ANGLE_UNITS if units is None else units
    if not (isinstance(value, dict) and set(value) == {"value", "unit"}):
        raise error(f"{where}: give the angle with its unit, e.g. {{value: -90, unit: deg}}"
                    f" (got {value!r})")
    angle, unit = value["value"], str(value["unit"])
    if unit not in units:
        raise error(f"{where}: unit {unit!r} is not one of {', '.join(units)}")
    if isinstance(angle, bool) or not isinstance(angle, (int, float)) or \
            not np.isfinite(angle):
        raise error(f"{where}: expected a number, got {angle!r}")
    return float(angle) * units[unit]


def read_setup_pose(spec, axes: dict[str, "Axis"], where: str,
                    notes: list[str] | None = None, replaced: Mapping[str, str] | None = None
                    ) -> dict[str, float]:
    """Rotary axis -> set-up command [rad] from ``{A: {value: -90, unit: deg}, ...}``.

    Every angle carries its unit; an axis the machine lacks, a linear axis, or a bare
    number is refused in one line saying how to write it. ``notes`` collects what was
    assumed (an angle of a continuous axis taken modulo a full turn).

    Parameters
    ----------
    spec : dict or None
        The ``setup_pose`` mapping; None gives an empty pose.
    axes : dict of str to Axis
        The machine's axes.
    where : str
        Where the pose sits, quoted in messages.
    notes : list of str, optional
        Appended with one sentence per assumption made.
    replaced : mapping of str to str, optional
        Rotary axis -> who gives its set-up instead (a survey's column map): an angle of
        such an axis outside its stroke is not used and said in ``notes``, not refused.

    Returns
    -------
    dict of str to float
        Rotary axis -> set-up command [rad], within the stroke.

    Raises
    ------
    MachineDescriptionError
        Not a mapping, not a rotary axis of the machine, an angle without a unit or
        outside the stroke.
    """
    if spec is None:
        return {}
    if not isinstance(spec, dict):
        raise MachineDescriptionError(f"{where}: expected a mapping like "
                                      "{C: {value: 0, unit: deg}}")
    pose: dict[str, float] = {}
    for axis, value in spec.items():
        axis = str(axis)
        if axis not in axes or not axes[axis].is_rotary:
            rotary = [a for a in axes if axes[a].is_rotary]
            raise MachineDescriptionError(
                f"{where}.{axis}: not a rotary axis of this machine (rotary: "
                f"{', '.join(rotary) or 'none'})")
        angle = angle_with_unit(value, f"{where}.{axis}", MachineDescriptionError)
        try:
            pose[axis] = setup_angle_in_stroke(axes[axis], angle, f"{where}.{axis}", notes)
        except MachineDescriptionError as exc:
            if not replaced or axis not in replaced or not np.isfinite(angle):
                raise
            # Another set-up replaces it: the file's impossible one is said, not used.
            if notes is not None:
                notes.append(f"{exc}: not used - {replaced[axis]} gives {axis}'s set-up")
    return pose


#: A rotary stroke at least this long turns a full turn: its angles are modulo 360 deg.
FULL_TURN = 2.0 * np.pi - 1e-9


def setup_angle_in_stroke(axis: "Axis", angle: float, where: str,
                          notes: list[str] | None = None) -> float:
    """A set-up angle [rad] of rotary ``axis`` as a command within its stroke.

    An axis whose stroke spans a full turn (a C table, 0..360 deg) is continuous: an
    angle and the same angle plus whole turns are one orientation, so -45 deg is taken
    as 315 deg, and ``notes`` gets the sentence that says so. Anything else outside the
    stroke is refused in one line.

    Parameters
    ----------
    axis : Axis
        The rotary axis.
    angle : float
        Set-up angle [rad].
    where : str
        Where the angle sits, quoted in messages.
    notes : list of str, optional
        Appended with the sentence when the angle is taken modulo a turn.

    Returns
    -------
    float
        The command [rad] within the stroke.

    Raises
    ------
    MachineDescriptionError
        A non-finite angle, or one outside the stroke of a non-continuous axis.
    """
    low, high = axis.stroke
    if not np.isfinite(angle):
        raise MachineDescriptionError(f"{where}: not a finite angle")
    if high - low >= FULL_TURN and not low - 1e-9 <= angle <= high + 1e-9:
        turns = np.floor((angle - low) / (2.0 * np.pi))
        given, angle = angle, float(angle - turns * 2.0 * np.pi)   # low <= angle < low + 2 pi
        if notes is not None:
            notes.append(f"{where}: {np.degrees(given):g} deg taken as "
                         f"{np.degrees(angle):g} deg ({axis.name} turns a full turn, "
                         f"stroke [{np.degrees(low):g}, {np.degrees(high):g}] deg: its "
                         "angles are modulo 360 deg)")
    if not low - 1e-9 <= angle <= high + 1e-9:
        raise MachineDescriptionError(
            f"{where}: {np.degrees(angle):g} deg is outside the stroke "
            f"[{np.degrees(low):g}, {np.degrees(high):g}] deg")
    return float(angle)


#: Keys of a machine's ``cnc:`` section and what each holds (SI units).
CNC_KEYS = {
    "max_correction_m": "largest correction per TCP component the controller takes [m] "
                        "(a number, or {X: .., Y: .., Z: ..})",
    "max_correction_rate_m_per_s": "largest change of the correction per second [m/s]",
    "max_feed_m_per_s": "fastest feed of a linear axis [m/s]",
    "temperature_range_k": "temperatures the model must stay bounded over: +- this about "
                           "each sensor's reference [K]",
    "max_temperature_rate_k_per_s": "fastest temperature change of a structure [K/s]",
    "max_spindle_speed_rpm": "fastest spindle speed [rpm]",
}


def _positive_or_none(value, where: str) -> float | None:
    if value is None:
        return None
    try:
        number = float(value)
    except (TypeError, ValueError) as exc:
        raise MachineDescriptionError(f"{where}: expected a positive number, got {value!r}") \
            from exc
    if not (np.isfinite(number) and number > 0):
        raise MachineDescriptionError(f"{where}: expected a positive number, got {value!r}")
    return number


def _cnc_section(spec, where: str) -> dict:
    """The ``cnc:`` mapping with every value a positive finite number (per-axis mapping
    allowed for ``max_correction_m``)."""
    if spec is None:
        return {}
    if not isinstance(spec, dict):
        raise MachineDescriptionError(f"{where}: expected a mapping of {', '.join(CNC_KEYS)}")
    unknown = set(spec) - set(CNC_KEYS)
    if unknown:
        raise MachineDescriptionError(f"{where}: unknown key(s) "
                                      f"{', '.join(sorted(map(str, unknown)))};"
                                      f" known: {', '.join(CNC_KEYS)}")
    out: dict = {}
    for key, value in spec.items():
        if key == "max_correction_m" and isinstance(value, dict):
            if not value or set(value) - set("XYZ"):
                raise MachineDescriptionError(f"{where}.{key}: per component X, Y, Z")
            out[key] = {str(a): _positive_or_none(v, f"{where}.{key}.{a}")
                        for a, v in value.items()}
        else:
            out[key] = _positive_or_none(value, f"{where}.{key}")
    return out


#: The bundled machine descriptions (``kidani_hmc``, ``khan_chen_rpppr``).
BUNDLED_MACHINES = Path(__file__).resolve().parents[2] / "machines"


def generic_cartesian(strokes: dict[str, tuple[float, float]], tool_length_m: float = 0.0,
                      name: str = "generic_cartesian", work_axes: tuple[str, ...] = ()
                      ) -> MachineDescription:
    """A Cartesian machine known only from its survey: linear axes ``strokes`` (axis ->
    (low, high) [m], e.g. the travel the readings cover), chain ``[w b X Y Z t]`` - or,
    with ``work_axes`` (the axes that carry the workpiece, from the bed outwards, e.g.
    ``("Y", "X")`` for a table on a saddle), those on the workpiece side and the rest on
    the tool side (``[w X Y b Z t]``), so that an angular error of a table axis acts
    through the positions of the axes it carries.

    Nothing of the real machine's geometry is assumed: every axis stacks on the tool
    side with zero offsets, so an angular error of an axis reaches the TCP through the
    positions of the axes after it (and the tool length) - the part of an Abbe arm
    that varies over the survey. A constant arm the real machine has adds an angular
    error times a constant: a straightness of the same axis, which the catalogue
    names as such.

    Parameters
    ----------
    strokes : dict of str to tuple of float
        Axis (X, Y, Z) -> (low, high) travel [m]; an axis that stood still gets a
        nominal 1 mm of travel.
    tool_length_m : float, optional
        Tool length along z [m].
    name : str, optional
        Machine name.
    work_axes : tuple of str, optional
        Surveyed axes that carry the workpiece, from the bed outwards.

    Returns
    -------
    MachineDescription
        With ``abbe_arms_known=False``, work axes with ``sign=-1``.

    Raises
    ------
    MachineDescriptionError
        No linear axis, a work axis not surveyed or named twice, a non-finite travel.
    """
    axes = [a for a in "XYZ" if a in strokes]
    if not axes:
        raise MachineDescriptionError("a generic Cartesian machine needs at least one of the "
                                      "axes X, Y, Z")
    work = [str(a).upper() for a in work_axes]
    unknown = [a for a in work if a not in axes]
    if unknown or len(set(work)) != len(work):
        raise MachineDescriptionError(f"work axes {work}: each one of the surveyed axes "
                                      f"({', '.join(axes)}) at most once")
    tool = [a for a in axes if a not in work]
    spec = {}
    for axis in axes:
        low, high = (float(v) for v in strokes[axis])
        if not (np.isfinite(low) and np.isfinite(high)):
            raise MachineDescriptionError(f"axis {axis}: travel [{low}, {high}] is not finite")
        if not high > low:
            # An axis that stood still: a nominal 1 mm of travel keeps the description valid.
            low, high = low - 5e-4, low + 5e-4
        # A survey's coordinates are the tool relative to the work, like a CNC's: a table
        # moves against its command (the bundled vmc.yaml's sign -1).
        spec[axis] = {"stroke": [low, high], "offset": [0.0, 0.0, 0.0],
                      "sign": -1.0 if axis in work else 1.0}
    from dataclasses import replace

    return replace(machine_from_dict({
        "name": name, "chain": "[" + " ".join(["w", *reversed(work), "b", *tool, "t"]) + "]",
        "description": "generic Cartesian machine from the survey's travel (no --machine)",
        "tool": [0.0, 0.0, float(tool_length_m)], "workpiece": [0.0, 0.0, 0.0],
        "axes": spec}, name), abbe_arms_known=False)


def with_setup_pose(machine: MachineDescription, pose: dict[str, float],
                    source: str = "setup_pose") -> MachineDescription:
    """``machine`` with the set-up pose ``pose`` (rotary axis -> command [rad]) on top of
    its own; an axis that is not one of its rotary axes, or an angle outside its stroke,
    is refused in one line.

    Parameters
    ----------
    machine : MachineDescription
        The machine.
    pose : dict of str to float
        Rotary axis -> set-up command [rad].
    source : str, optional
        Where the pose came from, quoted in messages.

    Returns
    -------
    MachineDescription
        A copy with the merged pose and notes (``machine`` itself when ``pose`` is empty).

    Raises
    ------
    MachineDescriptionError
        An axis that is not rotary on ``machine`` or an angle outside its stroke.
    """
    from dataclasses import replace

    if not pose:
        return machine
    rotary = [a for a in machine.axis_order if machine.axes[a].is_rotary]
    pose, notes = dict(pose), list(machine.setup_notes)
    for axis, angle in pose.items():
        if axis not in rotary:
            raise MachineDescriptionError(
                f"{source}: {axis} is not a rotary axis of {machine.name} (rotary: "
                f"{', '.join(rotary) or 'none'})")
        pose[axis] = setup_angle_in_stroke(machine.axes[axis], angle,
                                           f"{source}.{axis} ({machine.name})", notes)
    return replace(machine, setup_pose={**machine.setup_pose, **pose},
                   setup_notes=tuple(notes))


def checked_datum(datum, machine: MachineDescription) -> dict[str, float]:
    """A work offset (axis -> command) checked against ``machine``: every axis once, finite,
    within its stroke (a datum outside it is a unit slip). Empty stays empty.

    Parameters
    ----------
    datum : dict of str to float or None
        Axis -> command [m] (rotary [rad]).
    machine : MachineDescription
        The machine whose axes and strokes apply.

    Returns
    -------
    dict of str to float
        Axis -> command [m] or [rad], every axis of ``machine`` (or empty).

    Raises
    ------
    ParameterError
        Not a mapping, not every axis exactly once, a non-finite value or one outside
        the stroke.
    """
    import math

    from ..errors import ParameterError

    if not datum:
        return {}
    if not isinstance(datum, dict):
        raise ParameterError(f"datum: expected axis -> position, got {datum!r}")
    if set(datum) != set(machine.axis_order):
        raise ParameterError(f"datum: give every axis of {machine.name} once "
                             f"({', '.join(machine.axis_order)}); got {', '.join(map(str, datum))}")
    out = {}
    for axis in machine.axis_order:
        value = datum[axis]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                not math.isfinite(value):
            raise ParameterError(f"datum.{axis}: expected a finite number, got {value!r}")
        value = float(value)
        low, high = machine.axes[axis].stroke
        if not low - 1e-9 <= value <= high + 1e-9:
            unit = "rad" if machine.axes[axis].is_rotary else "m"
            raise ParameterError(f"datum.{axis} = {value:g} {unit} is outside the stroke "
                                 f"[{low:g}, {high:g}] {unit} (SI units: m and rad)")
        out[axis] = value
    return out


def bundled_machine_names() -> list[str]:
    return sorted(p.stem for p in BUNDLED_MACHINES.glob("*.yaml"))


def bundled_machine_path(name: str) -> Path:
    """The file of the bundled machine ``name``; a name that is not one is refused
    (nothing outside the bundled directory is reachable through a name).

    Parameters
    ----------
    name : str
        Bundled machine name without suffix, e.g. ``"kidani_hmc"``.

    Returns
    -------
    pathlib.Path
        The YAML file in :data:`BUNDLED_MACHINES`.

    Raises
    ------
    MachineDescriptionError
        Not a plain name, or no such bundled machine.
    """
    if not plain_name(name) or not (BUNDLED_MACHINES / f"{name}.yaml").is_file():
        raise MachineDescriptionError(f"no bundled machine {name[:80]!r} (bundled: "
                                      f"{', '.join(bundled_machine_names())}; or a path to a "
                                      "machine YAML)")
    return BUNDLED_MACHINES / f"{name}.yaml"


@reraise_as(MachineDescriptionError, "machine description")
def load_machine(path_or_name: str | Path,
                 replaced_setup: Mapping[str, str] | None = None) -> MachineDescription:
    """Load a description from a YAML file, or a bundled one by name
    (``kidani_hmc``, ``khan_chen_rpppr``): a name has no suffix.

    The file must be a regular file of at most
    :data:`~mt_accuracy_ros.core.inputs.safe_files.MAX_DESCRIPTION_BYTES`; errors never quote it.

    Parameters
    ----------
    path_or_name : str or pathlib.Path
        Path to a machine YAML, or a bundled machine's name.
    replaced_setup : mapping of str to str, optional
        Rotary axis -> who gives its set-up instead (a survey's column map): the file's
        angle for it is then not refused when outside the stroke, only said.

    Returns
    -------
    MachineDescription
        The validated description.

    Raises
    ------
    MachineDescriptionError
        Unreadable or too large file, bad YAML, or an invalid description.
    """
    path = Path(path_or_name)
    if not path.suffix:
        path = bundled_machine_path(str(path_or_name))
    text = read_description(path, "machine description", MachineDescriptionError)
    return machine_from_dict(load_yaml(text, str(path), MachineDescriptionError), str(path),
                             replaced_setup)
