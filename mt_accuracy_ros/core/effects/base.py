"""What every effect family is made of: a context to compute designs in, and the family API.

An **effect family** is one kind of physical cause (a ball-screw pitch error,
a squareness that changes with temperature, servo lag, ...). It offers
**variants** (which axis, which sensor) and, per variant, a grid of
**settings** (hyperparameters that enter non-linearly: a polynomial order,
a screw pitch, a thermal time constant). For a fixed variant and setting the
effect is linear in its parameters p (to first order), so its TCP error at N
readings is ``design (N, 3, P) @ p`` - the design is all the workbench needs
to fit, cross-validate and rank it, and all the error model needs to apply
it once fitted.

Kinematic sensitivities (how a unit motion or location error of an axis
moves the TCP, with its Abbe arms, Khan & Chen eqs. 8-17, Kidani eq. 2.10)
come from the machine's kinematic chain, to first order in the errors (each
error's frame and lever arm): :meth:`Context.jacobian`.

An effect that turns a frame of the chain also turns the tool relative to the
workpiece: its **tool-orientation** design (N, 3, P) [rad per parameter unit]
(:meth:`EffectFamily.orientation_design`, from :meth:`Context.orientation_jacobian`:
d Theta = sign R eps, the rotation part of the same twists, Kidani eq. 2.10's
companion) is what a five-axis model needs to turn its rotary axes, and what an
instrument that measures the tool's direction (a two-sphere R-test) judges.
When the readings measured the direction too, :meth:`Context.measured_design`
stacks both into (N, 6, P): the position rows [m] and the direction rows
scaled by ``orientation_lever_m`` (the instrument's position noise over its
direction noise, so every row carries the same noise) and projected across
the tool axis (the instrument cannot see a turn about it).
"""
from __future__ import annotations

import re
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InputDataError
from ..kinematics.chain import KinematicModel
from ..kinematics.htm import cross
from ..kinematics.machine import COMPONENTS, MachineDescription
from .lru import ByteBoundedCache
from .variables import Variables

#: Columns shared between candidates, kept per context [bytes] (:meth:`Context.shared_columns`).
SHARED_COLUMNS_BYTES = 32 * 2 ** 20
#: ... and only while it can hold this many of them (measured: 76 distinct periods over
#: a survey's three selection steps, each asked for 2-3 times; docs/benchmarks.md).
SHARED_COLUMNS_KEPT = 48
#: The scales' own thermocouples (x1_s0 ...) serve the scale compensation, not the structure.
_SCALE_SENSOR = re.compile(r"^[xyzabc][12]_s\d+$", re.IGNORECASE)



def normalised_stroke(machine, axis: str, q) -> NDArray[np.float64]:
    """Positions ``q`` [m] of ``axis`` mapped to [-1, 1] over its stroke (Legendre's domain):
    u = (2 q - (low + high)) / (high - low), dimensionless, shape of ``q``."""
    low, high = machine.axes[axis].stroke
    return (2.0 * np.asarray(q, dtype=np.float64) - (low + high)) / (high - low)

class Context:
    """Machine + variables at N readings; caches kinematic sensitivities.

    ``orientation`` (N, 3) [rad]: the model's tool-orientation error at the readings,
    for the Abbe family (optional). ``work_point`` ((3,) or (N, 3) [m], workpiece
    frame): a fixed target the readings were taken at (an R-test or probed
    sphere); by default the machining point (:meth:`KinematicModel.machining_point`).

    Parameters
    ----------
    machine : MachineDescription
        The machine.
    variables : Variables
        Positions [m] / [rad], temperatures [degC], feeds ... at the N readings.
    kinematics : KinematicModel, optional
        The machine's chain (built from ``machine`` when not given).
    orientation : ndarray, shape (N, 3), optional
        Model's tool-orientation error [rad].
    orientation_lever_m : float, optional
        Set when the readings measured the tool's direction: the instrument's
        position noise over its direction noise [m per rad].
    direction_measured : bool, optional
        The readings measured the tool's direction (by default: ``orientation_lever_m``
        is set); a model predicting them (:meth:`ErrorModel.tcp_error`) says so without
        a lever, so that a tilt's turn is read as the instrument read it.
    work_point : ndarray, shape (3,) or (N, 3), optional
        Fixed target [m], workpiece frame.
    zero_rows : ndarray of int, shape (N,), optional
        The row each reading's instrument was zeroed at.

    Raises
    ------
    InputDataError
        Positions missing for an axis of the machine.
    """

    def __init__(self, machine: MachineDescription, variables: Variables,
                 kinematics: KinematicModel | None = None,
                 orientation: NDArray[np.float64] | None = None, *,
                 orientation_lever_m: float | None = None,
                 work_point: NDArray[np.float64] | None = None,
                 zero_rows: NDArray[np.intp] | None = None,
                 located_readings: bool = False,
                 direction_measured: bool | None = None) -> None:
        self.machine = machine
        #: True for an instrument's readings, whose target (and tool) was located at the
        #: set-up: the located families then read the set-up among them. False for a CNC's
        #: own commands (a compensation's batch), which get every error as the machine
        #: makes it, whatever poses the batch holds.
        self.located_readings = located_readings
        #: (N,) the reading each reading's instrument was zeroed at (a log of zeroed runs:
        #: its run's first), or None: a position design is then referred to that row.
        self.zero_rows = None if zero_rows is None else np.asarray(zero_rows, dtype=np.intp)
        self.work_point = work_point
        #: Set when the readings measured the tool's direction: [m per rad] that makes a
        #: direction row's noise the position rows' (see the module docstring).
        self.orientation_lever_m = orientation_lever_m
        #: The instrument measured the tool's direction: a located instrument then read a
        #: tilt's turn located with the work (the fit's design and the model's prediction
        #: alike).
        self.direction_measured = orientation_lever_m is not None \
            if direction_measured is None else bool(direction_measured)
        self.variables = variables
        self.kinematics = kinematics or KinematicModel(machine)
        self.orientation = orientation
        self.n = variables.n
        self._jacobians: dict[str, NDArray[np.float64]] = {}
        self._frames: dict | None = None
        self.cache: dict = {}   # families' precomputed bases (e.g. periodic) for these readings
        self._shared: ByteBoundedCache | None = None
        missing = [a for a in machine.axis_order if a not in variables.positions]
        if missing:
            raise InputDataError(f"positions missing for axis {', '.join(missing)}")

    def shared_columns(self, key: tuple, make) -> NDArray[np.float64]:
        """Columns several candidates ask for at these readings (the harmonics of one
        axis' position at one period serve its positioning, straightness and angular
        errors): ``make()`` once, kept read-only in a least-recently-used store of
        :data:`SHARED_COLUMNS_BYTES`.

        Parameters
        ----------
        key : tuple
            Hashable identity of the columns.
        make : callable
            ``() -> ndarray, shape (N, P)`` computing them (unit-agnostic).

        Returns
        -------
        ndarray, shape (N, P)
            The columns, read-only.
        """
        if self._shared is None:
            # A step asks for dozens of them before asking again: nothing is kept that the
            # store could not hold that many of (1e5 readings: 3.2 MB each).
            self._shared = ByteBoundedCache(SHARED_COLUMNS_BYTES, SHARED_COLUMNS_KEPT)
        columns = self._shared.get(key)
        if columns is None:
            columns = make()
            columns.flags.writeable = False
            self._shared.put(key, columns)
        return columns

    def jacobian(self, error_name: str) -> NDArray[np.float64]:
        """d e_TCP / d (error ``error_name``) at the readings, shape (N, 3) [m per m or rad].

        ``error_name`` is an ISO 230-1 motion error (``EXX``, ``EBX``, ``ECA``) or
        location error (``EC0Y``, ``EX0B``). The analytic first-order sensitivity
        of the HTM chain (:meth:`KinematicModel.error_frames`: the frame the
        error acts in and its lever to the TCP); a name the chain does not have
        moves nothing.

        Parameters
        ----------
        error_name : str
            ISO 230-1 motion error (``EXX``, ``EBX``, ``ECA``) or location error (``EC0Y``).

        Returns
        -------
        ndarray, shape (N, 3)
            TCP displacement per unit error, bed frame [m/m] (translation) or [m/rad] (rotation).
        """
        if error_name not in self._jacobians:
            if self._frames is None:
                positions = {a: self.variables.positions[a] for a in self.machine.axis_order}
                self._frames = self.kinematics.error_frames(positions,
                                                            work_point=self.work_point)
            frame = self._frames.get(error_name)
            if frame is None:
                self._jacobians[error_name] = np.zeros((self.n, 3))
            else:
                sign, rotation, lever = frame
                component = COMPONENTS.index(error_name[1])
                if component < 3:
                    sensitivity = rotation[:, :, component]
                else:
                    sensitivity = cross(rotation[:, :, component - 3], lever)
                self._jacobians[error_name] = sign * np.ascontiguousarray(sensitivity)
        return self._jacobians[error_name]

    @property
    def target_groups(self) -> NDArray[np.intp] | None:
        """(N,) which located target each reading was taken at, or None for one target
        (:func:`target_groups`)."""
        if "target_groups" not in self.cache:
            self.cache["target_groups"] = target_groups(self.work_point, self.n)
        return self.cache["target_groups"]

    def located(self, error_name: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(position (N, 3) [m per unit], orientation (N, 3) [rad per unit]) of a rotary
        axis' location error ``error_name`` as an instrument located at the set-up reads
        it: the body turning about its actual line, the target (and a head's tool) located
        by a translation at the set-up pose
        (:meth:`~..kinematics.chain.KinematicModel.located_sensitivities`). Computed for
        the four line errors of every rotary axis at once: the chain's frames they share
        are most of the cost (a five-axis model asks for both axes' at every evaluation).

        Parameters
        ----------
        error_name : str
            Location error of a rotary axis, e.g. ``EX0C``, ``EA0C``.

        Returns
        -------
        position : ndarray, shape (N, 3)
            [m per m] or [m per rad].
        orientation : ndarray, shape (N, 3)
            [rad per m] or [rad per rad].
        """
        key = "located:" + error_name
        if key not in self._jacobians:
            rotary = [a for a in self.machine.axis_order if self.machine.axes[a].is_rotary]
            if error_name[3] not in rotary:
                rotary.append(error_name[3])
            # The line's two offsets and two tilts, and its zero (an outer axis' zero turns
            # the lines it carries, ISO 230-7); an offset along the line moves nothing.
            names = [f"E{c}0{axis}" for axis in rotary for c in "XYZABC"
                     if c != "XYZ"["ABC".index(axis)]]
            positions = {a: self.variables.positions[a] for a in self.machine.axis_order}
            found = self.kinematics.located_sensitivities(positions, names,
                                                          work_point=self.work_point)
            for name, pair in found.items():
                self._jacobians["located:" + name] = pair
        return self._jacobians[key]

    def arm_jacobian(self, error_name: str) -> NDArray[np.float64]:
        """d e_TCP / d (rotation ``error_name`` times an extra arm of 1 m along the tool
        axis), (N, 3) [m per rad m]: ``sign (R[:, :, c] x t)`` for a rotation component c,
        t the nominal tool axis; zero for a translation. How a tilt moves the TCP through
        the part of its Abbe arm the chain does not know (a tool offset not given).

        Parameters
        ----------
        error_name : str
            ISO 230-1 motion error (``EXX``, ``EBX``, ``ECA``) or location error (``EC0Y``).

        Returns
        -------
        ndarray, shape (N, 3)
            [m per (rad m)], bed frame.
        """
        key = "arm:" + error_name
        if key not in self._jacobians:
            self._jacobians[key] = self._arm_sensitivity(error_name)
        return self._jacobians[key]

    def _arm_sensitivity(self, error_name: str) -> NDArray[np.float64]:
        # The turn's axis in the bed frame (the orientation sensitivity) across the tool.
        # Not kept: a survey without the tool's direction needs the orientation
        # sensitivity only here (N x 3 floats per error name: 2.4 MB each at 1e5 readings).
        turn = self._jacobians.get("orientation:" + error_name)
        if turn is None:
            turn = self._orientation_sensitivity(error_name)
        return cross(turn, self.tool_axis())

    def arm_moves(self, error_name: str) -> bool:
        """Does an extra arm along the tool carry the rotation ``error_name`` to the TCP
        anywhere (:meth:`arm_jacobian` not zero)? Asked of every rotation; answered
        without keeping the sensitivity.

        Parameters
        ----------
        error_name : str
            ISO 230-1 motion error (``EXX``, ``EBX``, ``ECA``) or location error (``EC0Y``).

        Returns
        -------
        bool
            True when any component exceeds 1e-12 m per (rad m).
        """
        key = "arm:" + error_name
        arm = self._jacobians[key] if key in self._jacobians else \
            self._arm_sensitivity(error_name)
        return bool(np.any(np.abs(arm) > 1e-12))

    def orientation_jacobian(self, error_name: str) -> NDArray[np.float64]:
        """d (tool orientation relative to the workpiece) / d (error ``error_name``), (N, 3)
        [rad per m or rad]: ``sign R[:, :, c]`` for a rotation component c of the error
        (its axis in the bed frame), zero for a translation (Kidani eq. 2.10's rotation
        part; :meth:`KinematicModel.tcp_error_linear`).

        Parameters
        ----------
        error_name : str
            ISO 230-1 motion error (``EXX``, ``EBX``, ``ECA``) or location error (``EC0Y``).

        Returns
        -------
        ndarray, shape (N, 3)
            [rad per rad] (zero for a translation), bed frame.
        """
        key = "orientation:" + error_name
        if key not in self._jacobians:
            self._jacobians[key] = self._orientation_sensitivity(error_name)
        return self._jacobians[key]

    def _orientation_sensitivity(self, error_name: str) -> NDArray[np.float64]:
        self.jacobian(error_name)   # builds the frames
        frame = self._frames.get(error_name)
        if frame is None or COMPONENTS.index(error_name[1]) < 3:
            return np.zeros((self.n, 3))
        sign, rotation, _ = frame
        component = COMPONENTS.index(error_name[1]) - 3
        return sign * np.ascontiguousarray(rotation[:, :, component])

    @property
    def width(self) -> int:
        """Measured components per reading: 3 (TCP position) or 6 (and tool direction)."""
        return 3 if self.orientation_lever_m is None else 6

    def tool_axis(self) -> NDArray[np.float64]:
        """(N, 3) unit tool axis in the bed frame, nominal chain."""
        if "tool_axis" not in self.cache:
            self.cache["tool_axis"] = self.kinematics.tool_axis(
                {a: self.variables.positions[a] for a in self.machine.axis_order})
        return self.cache["tool_axis"]

    def _direction_rows(self, orientation: NDArray[np.float64]) -> NDArray[np.float64]:
        """(N, 3, ...) orientation -> what the instrument sees of it, scaled: the part
        across the tool axis times ``orientation_lever_m``."""
        axis = self.tool_axis()
        along_axis = np.einsum("nc,nc...->n...", axis, orientation)
        across = orientation - axis.reshape(axis.shape + (1,) * (orientation.ndim - 2)) * \
            along_axis[:, None]
        return self.orientation_lever_m * across

    def measured_design(self, family: "EffectFamily", variant: str, setting: dict
                        ) -> NDArray[np.float64]:
        """(N, width, P): the family's TCP design, and (when the direction was measured)
        its direction design as the instrument sees it (module docstring).

        Parameters
        ----------
        family : EffectFamily
            The effect family.
        variant : str
            Its variant.
        setting : dict
            Its setting.

        Returns
        -------
        ndarray, shape (N, 3, P) or (N, 6, P)
            Position rows [m per parameter unit], then direction rows scaled by
            ``orientation_lever_m`` [m per parameter unit]; referred to ``zero_rows`` if set.
        """
        design = family.design(self, variant, setting)
        if self.zero_rows is not None:
            # A zeroed instrument reads e(t) - e(t_zero): so does every column.
            design = design - design[self.zero_rows]
        if self.orientation_lever_m is None:
            return design
        turn = family.orientation_design(self, variant, setting)
        turn = np.zeros_like(design) if turn is None else self._direction_rows(turn)
        return np.concatenate([design, turn], axis=1)

    def measured_separable(self, family: "EffectFamily", variant: str, setting: dict
                           ) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        """:meth:`EffectFamily.separable_design` with the sensitivity (N, width).

        Parameters
        ----------
        family : EffectFamily
            The effect family.
        variant : str
            Its variant.
        setting : dict
            Its setting.

        Returns
        -------
        tuple of ndarray or None
            (sensitivity (N, 3) or (N, 6) [m per unit], basis (N, P)); None when the
            design is not separable or the readings are referred to zero rows.
        """
        if self.zero_rows is not None:
            return None     # referred to a zero row, a design is no longer one product
        separable = family.separable_design(self, variant, setting)
        if separable is None or self.orientation_lever_m is None:
            return separable
        sensitivity, basis = separable
        turn = family.orientation_sensitivity(self, variant, setting)
        turn = np.zeros_like(sensitivity) if turn is None else self._direction_rows(turn)
        return np.concatenate([sensitivity, turn], axis=1), basis

    def normalised_position(self, axis: str) -> NDArray[np.float64]:
        """Position mapped to [-1, 1] over the stroke (Legendre's domain).

        Parameters
        ----------
        axis : str
            Axis letter.

        Returns
        -------
        ndarray, shape (N,)
            Dimensionless u = (2 q - (low + high)) / (high - low).
        """
        return normalised_stroke(self.machine, axis, self.variables.positions[axis])

    def moves(self, axis: str) -> bool:
        """Did ``axis`` move over these readings? (an axis that stood still cannot show an
        error that depends on its position)

        Parameters
        ----------
        axis : str
            Axis letter.

        Returns
        -------
        bool
            True when its positions span a non-zero range.
        """
        return bool(np.ptp(self.variables.positions[axis]) > 0)

    def linear_axes(self, moving: bool = False) -> list[str]:
        """The machine's linear axes, in chain order.

        Parameters
        ----------
        moving : bool, optional
            Only those that moved over the readings.

        Returns
        -------
        list of str
            Axis letters.
        """
        return [a for a in self.machine.axis_order if not self.machine.axes[a].is_rotary
                and (not moving or self.moves(a))]

    def rotary_axes(self, moving: bool = False) -> list[str]:
        """The machine's rotary axes, in chain order.

        Parameters
        ----------
        moving : bool, optional
            Only those that moved over the readings.

        Returns
        -------
        list of str
            Axis letters.
        """
        return [a for a in self.machine.axis_order if self.machine.axes[a].is_rotary
                and (not moving or self.moves(a))]

    def structure_sensors(self) -> list[str]:
        """Temperature sensors of the structure that change (dead or constant ones are left out)."""
        out = []
        for name, values in self.variables.temperatures.items():
            if _SCALE_SENSOR.match(name):
                continue
            finite = values[np.isfinite(values)]
            if finite.size == values.size and np.ptp(finite) > 1e-3:
                out.append(name)
        return sorted(out)


#: Several targets are spheres located one by one when there are at most this fraction
#: of the readings of them (a probing cycle's few spheres; a tracker's or the machining
#: point's targets change with every reading and share one zero).
TARGETS_PER_READING = 0.05


def target_groups(work_point, n: int) -> NDArray[np.intp] | None:
    """(N,) the index of each reading's target among the few an instrument located one by
    one (several probed spheres: each found at the set-up, each its own zero), or None
    when there is one target, none, or one per reading.

    Parameters
    ----------
    work_point : array_like, shape (3,) or (N, 3), or None
        The readings' targets [m], workpiece frame.
    n : int
        Number of readings N.

    Returns
    -------
    ndarray of intp, shape (N,), or None
        Target index per reading.
    """
    if work_point is None:
        return None
    points = np.asarray(work_point, dtype=np.float64)
    if points.ndim != 2 or points.shape[0] != n:
        return None
    _, groups = np.unique(points, axis=0, return_inverse=True)
    count = int(groups.max()) + 1
    return groups.ravel().astype(np.intp) if 1 < count <= TARGETS_PER_READING * n else None


def per_component(column: NDArray[np.float64]) -> NDArray[np.float64]:
    """(N,) -> (N, 3, 3): the same regressor on x, y and z, one parameter each.

    Parameters
    ----------
    column : ndarray, shape (N,)
        The regressor (unit-agnostic).

    Returns
    -------
    ndarray, shape (N, 3, 3)
        ``design[:, c, c] = column``; a parameter's unit is [m] per the column's unit.
    """
    design = np.zeros((column.size, 3, 3))
    for c in range(3):
        design[:, c, c] = column
    return design


def along(jacobian: NDArray[np.float64], columns: NDArray[np.float64]) -> NDArray[np.float64]:
    """(N, 3) sensitivity x (N, P) basis -> (N, 3, P) design.

    Parameters
    ----------
    jacobian : ndarray, shape (N, 3)
        TCP sensitivity [m per error unit].
    columns : ndarray, shape (N, P)
        Basis columns (error units per parameter unit).

    Returns
    -------
    ndarray, shape (N, 3, P)
        Design [m per parameter unit].
    """
    return jacobian[:, :, None] * columns[:, None, :]


class EffectFamily:
    """Base class of an effect family (override the methods; see the module docstring).

    Class attributes: ``name`` (unique, used in candidate names ``name:variant``),
    ``group`` (geometric / thermal / motion / cross-axis / rotary / user),
    ``summary`` (one line of physics), ``reference`` (the seed equations) and
    ``complexity`` (Occam's tie-break).
    """

    name = "effect"
    group = "other"
    summary = ""
    reference = ""
    #: How much an explanation assumes (inputs, searched hyperparameters): 1 a single
    #: constant or input, 2 a function or a lag, 3 a searched period or a product. When
    #: the data cannot tell two candidates apart, the simpler is named (Occam).
    complexity = 2
    #: A candidate only where the caller asks for it (a thermal log's command): a blend
    #: of many sensors that would out-fit a named effect of a survey.
    log_only = False

    def variant_complexity(self, variant: str) -> int:
        """:attr:`complexity` of one variant (a family whose variants differ in what they
        assume overrides this).

        Parameters
        ----------
        variant : str
            The variant.

        Returns
        -------
        int
            1, 2 or 3 (see :attr:`complexity`).
        """
        return self.complexity

    def variants(self, ctx: Context) -> list[str]:
        """The variants this family offers on these readings (axes that moved, sensors
        that changed ...).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            Variant names.
        """
        raise NotImplementedError

    #: The key of a setting that is a continuous quantity searched on a grid (a period, a
    #: time constant): the workbench refines it between grid points; None if none is.
    continuous_setting: str | None = None
    #: True when each setting's design is the first columns of the last setting's (a
    #: polynomial order): the workbench then computes one design for all of them.
    nested_settings: bool = False

    def nested_columns(self, variant: str, setting: dict, largest: dict) -> list[int] | None:
        """Which columns of the ``largest`` setting's design, in order, are ``setting``'s
        design, or None when it is no part of it: the workbench then makes one design
        (and one set of products) for all the settings. By default the first columns,
        for a family with :attr:`nested_settings`.

        Parameters
        ----------
        variant : str
            The variant.
        setting : dict
            A setting.
        largest : dict
            The setting whose design holds all the others'.

        Returns
        -------
        list of int or None
            Column indices into the largest design.
        """
        if not self.nested_settings:
            return None
        return list(range(len(self.parameter_names(variant, setting))))

    @property
    def preselects(self) -> bool:
        """Whether :meth:`preselect` may choose a setting (the workbench skips it if not):
        a family that overrides it does."""
        return type(self).preselect is not EffectFamily.preselect or \
            type(self).preselect_folds is not EffectFamily.preselect_folds

    def settings(self, ctx: Context, variant: str) -> list[dict[str, Any]]:
        """The grid of settings (hyperparameters) searched for ``variant``; one empty
        setting by default.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            Which axis, error or sensor (one of :meth:`variants`).

        Returns
        -------
        list of dict
            Settings, e.g. ``[{"order": 1}, {"order": 2}]``.
        """
        return [{}]

    def parameter_names(self, variant: str, setting: dict) -> list[str]:
        """Names of the P linear parameters of ``variant`` at ``setting``, in design-column
        order.

        Parameters
        ----------
        variant : str
            Which axis, error or sensor (one of :meth:`variants`).
        setting : dict
            Hyperparameters (one of :meth:`settings`), e.g. ``{"period_m": 0.01}``.

        Returns
        -------
        list of str
            P parameter names (their units are the family's).
        """
        raise NotImplementedError

    def design(self, ctx: Context, variant: str, setting: dict) -> NDArray[np.float64]:
        """(N, 3, P) TCP error per unit parameter [m per parameter unit].

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            Which axis, error or sensor (one of :meth:`variants`).
        setting : dict
            Hyperparameters (one of :meth:`settings`), e.g. ``{"period_m": 0.01}``.

        Returns
        -------
        ndarray, shape (N, 3, P)
            Design [m per parameter unit], bed frame.
        """
        raise NotImplementedError

    def separable_design(self, ctx: Context, variant: str, setting: dict
                         ) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        """(sensitivity (N, 3), basis (N, P)) when :meth:`design` is
        ``along(sensitivity, basis)`` - one direction at the TCP times scalar columns, as
        an error motion acting through the kinematic chain is - else None. The workbench
        then scores the candidate on N values per column instead of 3N (it keeps the
        sensitivity per candidate, so families may differ for the same variant).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            Which axis, error or sensor (one of :meth:`variants`).
        setting : dict
            Hyperparameters (one of :meth:`settings`), e.g. ``{"period_m": 0.01}``.

        Returns
        -------
        tuple of ndarray or None
            (sensitivity (N, 3) [m per error unit], basis (N, P) [error unit per
            parameter unit]), or None.
        """
        return None

    def orientation_sensitivity(self, ctx: Context, variant: str, setting: dict
                                ) -> NDArray[np.float64] | None:
        """(N, 3) tool-orientation sensitivity [rad per unit] along the same scalar columns
        as :meth:`separable_design`'s, or None when the effect turns nothing (a
        translation, a thermal drift): the default.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            Which axis, error or sensor (one of :meth:`variants`).
        setting : dict
            Hyperparameters (one of :meth:`settings`), e.g. ``{"period_m": 0.01}``.

        Returns
        -------
        ndarray, shape (N, 3), or None
            [rad per error unit], bed frame.
        """
        return None

    def orientation_design(self, ctx: Context, variant: str, setting: dict
                           ) -> NDArray[np.float64] | None:
        """(N, 3, P) tool-orientation error per unit parameter [rad per parameter unit],
        or None when the effect does not turn the tool relative to the workpiece. By
        default the separable design's columns along :meth:`orientation_sensitivity`.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            Which axis, error or sensor (one of :meth:`variants`).
        setting : dict
            Hyperparameters (one of :meth:`settings`), e.g. ``{"period_m": 0.01}``.

        Returns
        -------
        ndarray, shape (N, 3, P), or None
            [rad per parameter unit], bed frame.
        """
        sensitivity = self.orientation_sensitivity(ctx, variant, setting)
        if sensitivity is None:
            return None
        separable = self.separable_design(ctx, variant, setting)
        if separable is None:
            return None
        return along(sensitivity, separable[1])

    def explanation(self, variant: str, setting: dict) -> str:
        """One sentence of physics for a user: what this variant at this setting is.

        Parameters
        ----------
        variant : str
            Which axis, error or sensor (one of :meth:`variants`).
        setting : dict
            Hyperparameters (one of :meth:`settings`), e.g. ``{"period_m": 0.01}``.

        Returns
        -------
        str
            The sentence (the family's :attr:`summary` by default).
        """
        return self.summary

    def preselect(self, ctx: Context, variant: str, settings: list[dict],
                  residual: NDArray[np.float64], mask: NDArray[np.bool_],
                  train: NDArray[np.bool_]) -> dict | None:
        """Optionally choose a setting from the training readings' residual (fast path for
        long grids); None = let the workbench choose by BIC over every setting.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            Which axis, error or sensor (one of :meth:`variants`).
        settings : list of dict
            The settings to choose from.
        residual : ndarray, shape (N, 3)
            Residual of the model so far [m].
        mask : ndarray of bool, shape (N, 3)
            Components measured.
        train : ndarray of bool, shape (N,)
            Training readings.

        Returns
        -------
        dict or None
            The chosen setting.
        """
        return None

    def preselect_folds(self, ctx: Context, variant: str, settings: list[dict],
                        residuals: NDArray[np.float64], mask: NDArray[np.bool_],
                        trains: NDArray[np.bool_]) -> list[dict | None]:
        """:meth:`preselect` for several training sets at once: ``residuals`` (F, N, 3),
        ``trains`` (F, N); a family may do them together faster.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            Which axis, error or sensor (one of :meth:`variants`).
        settings : list of dict
            The settings to choose from.
        residuals : ndarray, shape (F, N, 3)
            Residual per fold [m].
        mask : ndarray of bool, shape (N, 3)
            Components measured.
        trains : ndarray of bool, shape (F, N)
            Training readings per fold.

        Returns
        -------
        list of (dict or None)
            One choice per fold.
        """
        return [self.preselect(ctx, variant, settings, r, mask, t)
                for r, t in zip(residuals, trains)]

    def parameter_limits(self, ctx: Context, variant: str, setting: dict
                         ) -> dict[str, tuple[float, str]]:
        """The largest |value| physics allows each parameter on ``ctx.machine``, with the
        reason: ``{name: (bound, why)}``; parameters not named are bounded only by the
        consistency rule and the controller's limits (:mod:`.physics`).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            Which axis, error or sensor (one of :meth:`variants`).
        setting : dict
            Hyperparameters (one of :meth:`settings`), e.g. ``{"period_m": 0.01}``.

        Returns
        -------
        dict of str to tuple of (float, str)
            Parameter name -> (bound in the parameter's unit, reason).
        """
        return {}

    def fit_problems(self, ctx: Context, variant: str, setting: dict, coefficients
                     ) -> list[str]:
        """Why physics refuses this fit beyond single parameters' limits (a relation
        between the parameters, e.g. an implausible arm): one sentence each, or none.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            Which axis, error or sensor (one of :meth:`variants`).
        setting : dict
            Hyperparameters (one of :meth:`settings`), e.g. ``{"period_m": 0.01}``.
        coefficients : sequence of float, length P
            Fitted parameters, in :meth:`parameter_names` order and their units.

        Returns
        -------
        list of str
            Problems (empty: none).
        """
        return []

    def describe_setting(self, setting: dict) -> str:
        """The setting in words, e.g. ``"period_m 0.01"``.

        Parameters
        ----------
        setting : dict
            The setting.

        Returns
        -------
        str
            ``key value`` pairs joined by commas.
        """
        return ", ".join(f"{k} {v:g}" if isinstance(v, (int, float)) else f"{k} {v}"
                         for k, v in setting.items())
