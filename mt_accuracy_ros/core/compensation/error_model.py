"""The volumetric error model the nodes run: kinematic chain + the effects it includes.

A model is a machine description plus a set of **effects**, named as the
virtual machine tool names them (:mod:`mt_accuracy_ros.sim.effects`), each with
the parameters the model believes. The same names are the workbench's
candidate library, so "adding the missing effect" means adding its name and
parameters here. Effects a model can hold:

==============================  ========================================  ==========================
effect                          parameters (model form)                   enters as
==============================  ========================================  ==========================
``geometric``                   measured profiles (``set_profile``),      motion errors
                                e.g. ECY                                  (Kidani eq. 2.12)
``squareness``                  ``errors_rad: {EC0Y: ...}``               location errors
``structural_thermal_drift``    ``beta_m_per_k: [bx, by, bz]``,           TCP offset beta dT
                                ``sensor``                                (Zhu eq. 3.12)
``position_dependent_thermal``  ``axis``, ``alpha_per_k``, ``sensor``,    positioning alpha (q - q0)
                                ``reference_m``                           dT (Zhu eq. 3.13)
``spindle_thermal_growth``      ``m_per_k``, ``sensor``, ``direction``    TCP offset along the tool
``abbe_offset``                 ``offset_m: [x, y, z]``                   eps x offset
``reversal``                    ``backlash_m``, ``axes``                  -sign(v) b/2 per axis
``servo_lag``                   ``lag_s``, ``axes``                       -v tau per axis
==============================  ========================================  ==========================

Beyond these, a model holds any effect of the open catalogue
(:mod:`mt_accuracy_ros.core.effects`) the workbench fitted - an entry
``{family, variant, setting, coefficients}`` under a name such as
``positioning_periodic:EXX`` - and user effects declared as an expression
(``{expression, parameters, acts_on, values}``); both are evaluated through
the catalogue, so they act in every node exactly as in the workbench.

Temperatures enter as rises over ``reference_temperatures_c`` (the first
reading, unless given). Everything is vectorised over N command positions.
Lagged terms keep their state between calls (a stream continues them);
``fresh=True`` starts them again in steady state at the first reading.
"""
from __future__ import annotations

import copy
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..effects import (Context, catalogue_error, catalogue_orientation, family_named,
                       is_catalogue_entry)
from ..effects.user import user_declaration
from ..effects.variables import Variables
from ..kinematics.error_functions import ErrorFunction
from ..errors import InputDataError, MachineDescriptionError, ParameterError, reraise_as
from ..kinematics.chain import ErrorOverrides, KinematicModel
from ..kinematics.htm import cross
from ..kinematics.machine import checked_datum  # noqa: F401 (its home; used below)
from ..kinematics.machine import MachineDescription, load_machine
from ..inputs.safe_files import load_yaml, plain_name, read_description

MODEL_EFFECTS = ("geometric", "squareness", "structural_thermal_drift",
                 "position_dependent_thermal", "spindle_thermal_growth", "abbe_offset",
                 "reversal", "servo_lag")

_DEFAULTS = {
    "geometric": {},
    "squareness": {"errors_rad": {}},
    "structural_thermal_drift": {"beta_m_per_k": [0.0, 0.0, 0.0], "sensor": "column"},
    "position_dependent_thermal": {"axis": "X", "alpha_per_k": 0.0, "sensor": "bed",
                                   "reference_m": 0.0},
    "spindle_thermal_growth": {"m_per_k": 0.0, "sensor": "spindle", "direction": [0.0, 0.0, 1.0]},
    "abbe_offset": {"offset_m": [0.0, 0.0, 0.0]},
    "reversal": {"backlash_m": 0.0, "axes": ["X", "Y", "Z"]},
    "servo_lag": {"lag_s": 0.0, "axes": ["X", "Y", "Z"]},
}


def _finite(where: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        raise ParameterError(f"{where}: expected a finite number, got {value!r}")
    return float(value)


def _checked_parameter(where: str, value, default, machine: MachineDescription):
    """``value`` checked against the kind of its ``default``; returns the clean value."""
    if where.endswith(".axis"):
        if value not in machine.axes or machine.axes[value].is_rotary:
            raise ParameterError(f"{where}: {value!r} is not a linear axis of {machine.name}")
        return value
    if where.endswith(".axes"):
        if not isinstance(value, list) or any(a not in machine.axes for a in value):
            raise ParameterError(f"{where}: expected a list of axes of {machine.name} "
                                 f"({', '.join(machine.axis_order)}), got {value!r}")
        return list(value)
    if where.endswith(".errors_rad"):
        if not isinstance(value, dict):
            raise ParameterError(f"{where}: expected a mapping of location errors to radians")
        out = {}
        for name, angle in value.items():
            match = re.fullmatch(r"E[ABC]0([A-Z])", str(name))
            if not match or match.group(1) not in machine.axes:
                raise ParameterError(f"{where}.{name}: not an angular location error of an axis "
                                     f"of {machine.name} (e.g. EC0Y)")
            out[str(name)] = _finite(f"{where}.{name}", angle)
        return out
    if isinstance(default, str):
        if not isinstance(value, str) or not value:
            raise ParameterError(f"{where}: expected a sensor name, got {value!r}")
        return value
    if isinstance(default, list):
        if not isinstance(value, list) or len(value) != len(default):
            raise ParameterError(f"{where}: expected {len(default)} numbers, got {value!r}")
        numbers = [_finite(f"{where}[{i}]", v) for i, v in enumerate(value)]
        if where.endswith(".direction") and not any(numbers):
            raise ParameterError(f"{where}: the direction must not be zero")
        return numbers
    return _finite(where, value)


def checked_datum_vector(key: str, value, datum: dict, *, non_negative: bool = False
                         ) -> NDArray[np.float64]:
    """The model's error at its datum, corrected or uncertain: three finite values [m]
    (x, y, z), each within 1 mm (a calibration's at one pose; beyond that it is no
    calibration's), and - when not zero - only with a datum.

    Parameters
    ----------
    key : str
        Name of the field checked (``datum_uncertainty_m``, ``datum_correction_m``),
        quoted in messages.
    value : array_like, shape (3,)
        The values [m] (x, y, z).
    datum : dict of str to float
        The model's datum (axis -> command [m] / [rad]); empty: no datum.
    non_negative : bool, optional
        Refuse negative values (an uncertainty).

    Returns
    -------
    ndarray, shape (3,)
        The values [m].

    Raises
    ------
    ParameterError
        Not three finite values within 1 mm (non-negative if asked), or non-zero
        without a datum.
    """
    if isinstance(value, (str, bytes, dict)):
        value = None
    try:
        out = np.array(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        out = np.zeros(0)
    if out.shape != (3,) or not np.all(np.isfinite(out)) or np.any(np.abs(out) > 1e-3) or \
            (non_negative and np.any(out < 0)):
        kind = "finite non-negative" if non_negative else "finite"
        raise ParameterError(f"{key}: expected three {kind} values within 1 mm, in m "
                             f"(x, y, z), got {value!r}")
    if np.any(out) and not datum:
        raise ParameterError(f"{key} is about the model's error at its datum: give the datum "
                             "(the pose the instrument was zeroed at) too")
    return out


def _datum_point(work_point) -> NDArray[np.float64] | None:
    """The target the instrument was zeroed on at the datum: its one fixed target, or the
    machining point (None) when the readings' points differ (several instruments)."""
    if work_point is None:
        return None
    point = np.asarray(work_point, dtype=np.float64)
    if point.ndim == 1:
        return point
    return point[0] if np.all(point == point[0]) else None


@dataclass
class ErrorModel:
    """Machine + included effects; evaluate the TCP error at command positions.

    Parameters
    ----------
    machine : MachineDescription
        The machine description (chain, offsets [m], calibrated error functions).
    effects : dict of str to dict
        Effect name -> parameters (module table; SI units as the keys say:
        ``beta_m_per_k`` [m/K], ``lag_s`` [s] ...), a catalogue entry or a user effect.
        Each is validated on construction.
    reference_temperatures_c : dict of str to float
        Sensor -> reference temperature [degC]; a sensor not named takes its first reading.
    profiles : dict of str to ErrorFunction
        Motion error name (``ECY``) -> live measured profile, [m] or [rad].
    version : int
        Model version (counts changes of effects and parameters).
    machine_source : str
        Bundled name or path the machine was loaded from.
    profile_offsets : dict of str to float
        Motion error name -> offset [m] or [rad] added to its live profile (to meet
        the calibration's mean).
    profile_revision : int
        Counts live profile updates.
    datum : dict of str to float
        Work offset: axis -> command [m] (rotary [rad]); empty: absolute errors.
    datum_uncertainty_m : ndarray, shape (3,), or None
        Expanded (k = 2) uncertainty [m] of the model's error at the datum.
    datum_correction_m : ndarray, shape (3,)
        Machine's error at the datum beyond the model's [m].

    Raises
    ------
    ParameterError
        An unknown effect or parameter, or a value of the wrong kind.
    """

    machine: MachineDescription
    effects: dict[str, dict] = field(default_factory=dict)
    reference_temperatures_c: dict[str, float] = field(default_factory=dict)
    profiles: dict[str, ErrorFunction] = field(default_factory=dict)
    version: int = 1
    machine_source: str = ""     # bundled name or path the machine was loaded from
    profile_offsets: dict[str, float] = field(default_factory=dict)
    #: Counts live profile updates. ``version`` counts model changes (effects and
    #: their parameters) only: a version is a model a user chose, not a data update.
    profile_revision: int = 0
    #: The work offset (axis -> command [m or rad]) where the reference instrument was
    #: zeroed and the part touched off; empty: the model's errors are absolute.
    #: With a datum, the TCP position error is referred to it (:meth:`tcp_error`).
    datum: dict[str, float] = field(default_factory=dict)
    #: (3,) [m] expanded (k = 2) uncertainty of the model's error at the datum: what its
    #: calibration knows there (:func:`.datum.calibration_uncertainty_at`); None: not
    #: stated, the model's error at the datum is taken as exact.
    datum_uncertainty_m: NDArray[np.float64] | None = None
    #: (3,) [m] the machine's error at the datum beyond what the model computes there: the
    #: calibration's error at that one pose, as the readings of an instrument zeroed there
    #: measured it (:func:`..workbench.refit.refit_effects`, within
    #: :attr:`datum_uncertainty_m`). Zero until measured.
    datum_correction_m: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        for name in list(self.effects):
            self.effects[name] = self._validated(name, self.effects[name])
        self.datum = checked_datum(self.datum, self.machine)
        self.datum_uncertainty_m = None if self.datum_uncertainty_m is None else \
            checked_datum_vector("datum_uncertainty_m", self.datum_uncertainty_m, self.datum,
                                 non_negative=True)
        self.datum_correction_m = checked_datum_vector("datum_correction_m",
                                                       self.datum_correction_m, self.datum)
        self._kinematics = KinematicModel(self.machine)
        self._lag_states: dict = {}
        self._datum_cache: dict = {}

    def _validated(self, name: str, parameters: dict | None) -> dict:
        """Defaults merged with ``parameters``, each checked against its default's kind, so
        that a model that loads also evaluates (a bad value is refused here, not mid-run)."""
        if is_catalogue_entry(parameters):
            return _checked_catalogue_entry(name, parameters, self.machine)
        if name not in _DEFAULTS:
            raise ParameterError(f"unknown model effect {name!r}; known: {', '.join(MODEL_EFFECTS)}"
                                 ", an effect of the catalogue (with 'family'), or a user "
                                 "effect (with 'expression')")
        if parameters is not None and not isinstance(parameters, dict):
            raise ParameterError(f"effect {name}: parameters must be a mapping")
        merged = copy.deepcopy(_DEFAULTS[name])
        for key, value in (parameters or {}).items():
            if key not in merged:
                raise ParameterError(f"effect {name} has no parameter {key!r}; "
                                     f"known: {', '.join(merged)}")
            merged[key] = _checked_parameter(f"{name}.{key}", value, _DEFAULTS[name][key],
                                             self.machine)
        return merged

    # ------------------------------------------------------------ changes
    def with_effect(self, name: str, parameters: dict | None = None) -> "ErrorModel":
        """A new model version that also holds ``name`` (or holds it with new parameters).

        Parameters
        ----------
        name : str
            Effect name (see the module table), or a catalogue / user effect's name.
        parameters : dict, optional
            Its parameters (SI units as keyed); defaults for those not given.

        Returns
        -------
        ErrorModel
            A copy with ``version + 1``.

        Raises
        ------
        ParameterError
            An unknown effect or an invalid parameter.
        """
        effects = copy.deepcopy(self.effects)
        effects[name] = parameters or {}
        return ErrorModel(self.machine, effects, dict(self.reference_temperatures_c),
                          dict(self.profiles), self.version + 1, self.machine_source,
                          dict(self.profile_offsets), datum=dict(self.datum),
                          datum_uncertainty_m=self.datum_uncertainty_m,
                          datum_correction_m=self.datum_correction_m.copy())

    def with_machine(self, machine: MachineDescription) -> "ErrorModel":
        """The same model on ``machine`` (e.g. its description with a survey's set-up pose).

        Parameters
        ----------
        machine : MachineDescription
            The machine to evaluate on.

        Returns
        -------
        ErrorModel
            A copy at the same version.
        """
        return ErrorModel(machine, copy.deepcopy(self.effects),
                          dict(self.reference_temperatures_c), dict(self.profiles),
                          self.version, self.machine_source, dict(self.profile_offsets),
                          datum=dict(self.datum), datum_uncertainty_m=self.datum_uncertainty_m,
                          datum_correction_m=self.datum_correction_m.copy())

    def without_effect(self, name: str) -> "ErrorModel":
        """A new model version without effect ``name``.

        Parameters
        ----------
        name : str
            Effect name; a name the model does not hold changes only the version.

        Returns
        -------
        ErrorModel
            A copy with ``version + 1``.
        """
        effects = {k: v for k, v in self.effects.items() if k != name}
        return ErrorModel(self.machine, effects, dict(self.reference_temperatures_c),
                          dict(self.profiles), self.version + 1, self.machine_source,
                          dict(self.profile_offsets), datum=dict(self.datum),
                          datum_uncertainty_m=self.datum_uncertainty_m,
                          datum_correction_m=self.datum_correction_m.copy())

    def set_profile(self, error_name: str, positions_m: ArrayLike, values: ArrayLike) -> None:
        """Use a measured profile (e.g. the kNN systematic yaw ECY) as that motion error.

        Parameters
        ----------
        error_name : str
            ISO 230-1 motion error name, e.g. ``"ECY"``.
        positions_m : array_like, shape (K,)
            Strictly ascending positions of the error's axis [m], K >= 2.
        values : array_like, shape (K,)
            Error at each position [m] (translational) or [rad] (angular).

        Raises
        ------
        InputDataError
            Unequal lengths, fewer than two or non-ascending positions, or NaN/inf.
        """
        x = np.asarray(positions_m, dtype=np.float64)
        y = np.asarray(values, dtype=np.float64)
        if x.shape != y.shape or x.ndim != 1 or x.size < 2 or not np.all(np.diff(x) > 0):
            raise InputDataError(f"profile {error_name}: need >= 2 ascending positions with "
                                 "one value each")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise InputDataError(f"profile {error_name}: NaN/inf values")
        # A live profile is relative to its estimator's zero reference. Where the
        # machine carries a calibrated table of the same error, the first profile
        # is aligned to it (mean difference) and that offset kept for the run, so a
        # later change - a deterioration - shows as a change of the error itself.
        axis = error_name[-1]
        if error_name not in self.profile_offsets:
            calibrated = None
            if axis in self.machine.axes and error_name[1] in self.machine.axes[axis].motion_errors:
                function = self.machine.axes[axis].motion_errors[error_name[1]]
                calibrated = None if function.is_zero else function(x)
            self.profile_offsets[error_name] = float(np.mean(calibrated - y)) \
                if calibrated is not None else 0.0
        y = y + self.profile_offsets[error_name]
        self.profiles[error_name] = ErrorFunction(kind="profile", positions=x, values=y)
        self.profile_revision += 1

    def calibrated(self, error_name: str):
        """The machine description's calibrated function of ``error_name`` (None if zero).

        Raises :class:`InputDataError` for a name that is not an ISO 230-1 motion error
        (``E`` + component + axis, e.g. ``ECX``).

        Parameters
        ----------
        error_name : str
            ISO 230-1 motion error name.

        Returns
        -------
        ErrorFunction or None
            The calibrated function ([m] or [rad] of the axis position), None when the
            machine lacks the axis or the function is zero.
        """
        if not isinstance(error_name, str) or len(error_name) != 3 or error_name[0] != "E" or \
                error_name[1] not in "XYZABC" or error_name[2] not in "XYZABC":
            raise InputDataError(f"profile of {error_name!r}: not an ISO 230-1 motion error "
                                 "name (E, component, axis: e.g. ECX)")
        axis, component = error_name[-1], error_name[1]
        spec = self.machine.axes.get(axis)
        if spec is None or component not in spec.motion_errors:
            return None
        function = spec.motion_errors[component]
        return None if function.is_zero else function

    def apply_profile(self, error_name: str, positions_m: ArrayLike, values: ArrayLike,
                      baseline_difference: ArrayLike | None = None) -> bool:
        """Take a live measured profile the way Kidani's command compensation does.

        Where the machine carries a calibrated table of this error (the
        installation calibration), the dual-scale profile says only how the
        error has *changed*: its own zero and the two scales' graduation errors
        (a false yaw (g2 - g1)/D, Kidani eq. 2.13) are static and cancel in the
        difference against the estimator's baseline. The model then uses
        E(x) = E_calibrated(x) + delta E(x), i.e. the command compensation
        p2 = p1 - delta e (Kidani eqs. 3.14-3.16); before a baseline exists the
        calibration stands and nothing changes (returns False). Without a
        calibrated table the live profile itself is the error (:meth:`set_profile`).

        Returns True when the model changed.

        Parameters
        ----------
        error_name : str
            ISO 230-1 motion error name, e.g. ``"ECY"``.
        positions_m : array_like, shape (K,)
            Strictly ascending positions [m], K >= 2.
        values : array_like, shape (K,)
            The live profile [m] or [rad] (used when there is no calibrated table).
        baseline_difference : array_like, shape (K,), optional
            Change of the profile against the estimator's baseline [m] or [rad].

        Returns
        -------
        bool
            True when the model changed.

        Raises
        ------
        InputDataError
            A malformed name, or positions / values not finite, ascending and of equal length.
        """
        function = self.calibrated(error_name)
        if function is None:
            self.set_profile(error_name, positions_m, values)
            return True
        if baseline_difference is None or np.size(baseline_difference) == 0:
            return False
        x = np.asarray(positions_m, dtype=np.float64)
        change = np.asarray(baseline_difference, dtype=np.float64)
        if x.shape != change.shape or x.ndim != 1 or x.size < 2 or not np.all(np.diff(x) > 0) \
                or not (np.all(np.isfinite(x)) and np.all(np.isfinite(change))):
            raise InputDataError(f"profile {error_name}: need >= 2 ascending finite positions "
                                 "with one finite baseline difference each")
        self.profiles[error_name] = ErrorFunction(kind="profile", positions=x,
                                                  values=function(x) + change)
        self.profile_revision += 1
        return True

    # ------------------------------------------------------------ evaluation
    def _rise(self, sensor: str, temperatures: dict, n: int) -> NDArray[np.float64]:
        if sensor not in temperatures:
            raise InputDataError(f"the model needs temperature {sensor!r}; have "
                                 f"{', '.join(sorted(temperatures)) or 'none'}")
        value = np.broadcast_to(np.asarray(temperatures[sensor], dtype=np.float64), (n,))
        reference = self.reference_temperatures_c.get(sensor)
        if reference is None:
            reference = float(value[0])
            self.reference_temperatures_c[sensor] = reference
        return value - reference

    def overrides(self, positions: dict[str, NDArray], temperatures: dict | None = None
                  ) -> ErrorOverrides:
        """Kinematic-model inputs of the included effects at N positions.

        Parameters
        ----------
        positions : dict of str to ndarray, shape (N,)
            Axis commands [m] (rotary [rad]).
        temperatures : dict of str to array_like, shape (N,) or scalar, optional
            Sensor name -> temperature [degC]; the effects use rises over
            :attr:`reference_temperatures_c` (the first reading when not set).

        Returns
        -------
        ErrorOverrides
            Motion / location errors [m] or [rad] and the bed-to-tool thermal twist
            (N, 6) of the built-in effects.

        Raises
        ------
        InputDataError
            A temperature an effect needs is missing.
        """
        temperatures = temperatures or {}
        n = int(np.size(next(iter(positions.values()))))
        # "geometric" = the description's calibrated errors plus the live profiles.
        out = ErrorOverrides(use_description="geometric" in self.effects)
        if "geometric" in self.effects:
            for name, function in self.profiles.items():
                axis = name[-1]
                out.motion[name] = function(positions[axis])
        if "squareness" in self.effects:
            for name, value in self.effects["squareness"]["errors_rad"].items():
                out.location[name] = float(value)
        if "position_dependent_thermal" in self.effects:
            p = self.effects["position_dependent_thermal"]
            axis = p["axis"]
            name = f"E{axis}{axis}"
            growth = float(p["alpha_per_k"]) * (positions[axis] - float(p["reference_m"])) * \
                self._rise(p["sensor"], temperatures, n)
            # An override replaces the description's function: start from it.
            base = out.motion.get(name)
            if base is None:
                base = self.machine.axes[axis].motion_errors[axis](positions[axis]) \
                    if out.use_description else 0.0
            out.motion[name] = base + growth
        drift = np.zeros((n, 6))
        if "structural_thermal_drift" in self.effects:
            p = self.effects["structural_thermal_drift"]
            drift[:, :3] += np.outer(self._rise(p["sensor"], temperatures, n),
                                     np.asarray(p["beta_m_per_k"], dtype=np.float64))
        if "spindle_thermal_growth" in self.effects:
            p = self.effects["spindle_thermal_growth"]
            direction = np.asarray(p["direction"], dtype=np.float64)
            drift[:, :3] += np.outer(float(p["m_per_k"]) * self._rise(p["sensor"], temperatures, n),
                                     direction / np.linalg.norm(direction))
        if np.any(drift):
            out.thermal["bed_tool"] = drift
        return out

    def datum_error(self, temperatures: dict | None = None,
                    work_point: ArrayLike | None = None) -> NDArray[np.float64]:
        """(3,) the model's TCP error at the :attr:`datum` [m] in the conditions the
        instrument was zeroed in: every temperature at its reference (no rise), the
        axes at rest, the live profiles as they are; at the instrument's fixed target
        ``work_point`` when it has one (else the machining point); plus
        :attr:`datum_correction_m`, what readings showed the calibration missed there.
        Zero without a datum.

        Parameters
        ----------
        temperatures : dict of str to array_like, optional
            Sensor -> temperature [degC]; the first value of each is used for a sensor
            without a reference.
        work_point : array_like, shape (3,), optional
            The instrument's target [m], workpiece frame.

        Returns
        -------
        ndarray, shape (3,)
            Position error at the datum [m], bed frame.
        """
        if not self.datum:
            return np.zeros(3)
        sensors = {**{k: float(np.ravel(np.asarray(v, dtype=np.float64))[0])
                      for k, v in (temperatures or {}).items()},
                   **self.reference_temperatures_c}
        key = (self.profile_revision, tuple(sorted((k, id(f)) for k, f in self.profiles.items())),
               tuple(sorted(sensors.items())), tuple(sorted(self.datum.items())),
               None if work_point is None else tuple(np.ravel(work_point).tolist()))
        if key not in self._datum_cache:
            # A copy: the datum must not advance this model's lag states.
            at_rest = copy.copy(self)
            at_rest._lag_states = {}
            at_rest.reference_temperatures_c = dict(self.reference_temperatures_c)
            pose = {a: np.array([float(v)]) for a, v in self.datum.items()}
            still = {a: np.zeros(1) for a in self.datum}
            position, _ = at_rest.tcp_error(
                pose, {k: np.array([v]) for k, v in sensors.items()}, still, still,
                time_s=np.zeros(1), accelerations=still, spindle_speed_rad_s=np.zeros(1),
                fresh=True, referred=False, work_point=work_point)
            if len(self._datum_cache) > 8:
                self._datum_cache.clear()
            self._datum_cache[key] = position[0]
        return self._datum_cache[key] + self.datum_correction_m

    def tcp_error(self, positions: dict[str, ArrayLike], temperatures: dict | None = None,
                  velocities: dict[str, ArrayLike] | None = None,
                  directions: dict[str, ArrayLike] | None = None, *,
                  time_s: ArrayLike | None = None,
                  accelerations: dict[str, ArrayLike] | None = None,
                  spindle_speed_rad_s: ArrayLike | None = None, fresh: bool = False,
                  referred: bool = True, work_point: ArrayLike | None = None,
                  run_starts: ArrayLike | None = None, located_readings: bool = False,
                  direction_measured: bool = False
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(position error (N, 3) [m], orientation error (N, 3) [rad]) at command positions.

        The error is taken at the machining point (the material under the tool,
        Kidani eqs. 2.9-2.10), or at ``work_point`` ((3,) or (N, 3) [m] in the
        workpiece frame) for an instrument whose target is fixed on the workpiece
        side (an R-test or probed sphere).

        ``directions`` (axis -> +-1, the direction of the last motion) serves the
        reversal effect where the axis stands still; without it sign(v) is used
        (0 at a standstill). ``time_s`` (N,) [s], ``accelerations`` [m/s^2] and
        ``spindle_speed_rad_s`` (N,) serve catalogue effects that need them.
        ``run_starts`` (R,): the first row of each run of a record made of many runs
        (lags restart there, :class:`~..effects.variables.Variables`).

        With a :attr:`datum` (and ``referred``), the position error is the error
        relative to the datum's as the instrument was zeroed there: e(q) - e(datum) at
        the reference temperatures, at rest (:meth:`datum_error`). A compensation then
        never moves the part's datum (but by a :attr:`datum_correction_m`: what the
        calibration missed there), and every constant of a fitted effect (which a fit
        against a zeroed instrument cannot know) is referred to the instrument's zero.
        The orientation stays absolute: a touch-off does not take out a tilt.

        Parameters
        ----------
        positions : dict of str to array_like, shape (N,)
            Axis commands [m] (rotary [rad]), every axis of the machine.
        temperatures : dict of str to array_like, shape (N,) or scalar, optional
            Sensor name -> temperature [degC]; the effects use rises over
            :attr:`reference_temperatures_c` (the first reading when not set).
        velocities : dict of str to array_like, shape (N,), optional
            Axis -> velocity [m/s] (rotary [rad/s]); needed by ``reversal`` and ``servo_lag``.
        directions : dict of str to array_like, shape (N,), optional
            Axis -> direction of the last motion, +1 or -1 (dimensionless).
        time_s : array_like, shape (N,), optional
            Time of each reading [s].
        accelerations : dict of str to array_like, shape (N,), optional
            Axis -> acceleration [m/s^2] (rotary [rad/s^2]).
        spindle_speed_rad_s : array_like, shape (N,), optional
            Spindle speed [rad/s].
        fresh : bool, optional
            Restart lagged terms in steady state at the first reading.
        referred : bool, optional
            Refer the position error to the datum's (when the model has a datum).
        work_point : array_like, shape (3,) or (N, 3), optional
            Instrument target [m], workpiece frame.
        run_starts : array_like of int, shape (R,), optional
            Row index of the first reading of each run.
        located_readings : bool, optional
            True for an instrument's readings whose target (and tool) was located at the
            set-up among them (a survey's): a located tilt is then read as that instrument
            reads it. False (default) for a CNC's own commands: every error as the machine
            makes it, the same whatever poses the batch holds.
        direction_measured : bool, optional
            With ``located_readings``: the instrument also measured the tool's direction,
            located with the work at the set-up (two spheres, ISO 10791-6): a work-side
            tilt's turn is then read as that instrument reads it, as its fit's design did.

        Returns
        -------
        position : ndarray, shape (N, 3)
            TCP position error [m], bed frame.
        orientation : ndarray, shape (N, 3)
            Tool-orientation error, rotation vector [rad], bed frame.

        Raises
        ------
        InputDataError
            A missing axis, a missing temperature, or velocities missing for an effect
            that needs them.
        """
        q = {a: np.atleast_1d(np.asarray(positions[a], dtype=np.float64))
             for a in self.machine.axis_order if a in positions}
        missing = [a for a in self.machine.axis_order if a not in q]
        if missing:
            raise InputDataError(f"positions missing for axis {', '.join(missing)}")
        result = self._kinematics.tcp_error(q, overrides=self.overrides(q, temperatures),
                                            check_stroke=False, work_point=work_point)
        position, orientation = result["position"], result["orientation"]
        if "abbe_offset" in self.effects:
            offset = np.asarray(self.effects["abbe_offset"]["offset_m"], dtype=np.float64)
            position = position + cross(orientation, offset)
        drive = np.zeros_like(position)
        for name, sign_of in (("reversal", True), ("servo_lag", False)):
            if name not in self.effects:
                continue
            if velocities is None:
                raise InputDataError(f"effect {name} needs axis velocities")
            p = self.effects[name]
            for axis in p["axes"]:
                if axis not in q or self.machine.axes[axis].is_rotary:
                    continue
                v = np.broadcast_to(np.asarray(velocities[axis], dtype=np.float64), q[axis].shape)
                direction = np.sign(v) if directions is None or axis not in directions else \
                    np.broadcast_to(np.asarray(directions[axis], dtype=np.float64), q[axis].shape)
                shift = -direction * 0.5 * float(p["backlash_m"]) if sign_of \
                    else -v * float(p["lag_s"])
                drive += shift[:, None] * self.axis_direction(axis, q)
        catalogue = {k: v for k, v in self.effects.items() if is_catalogue_entry(v)}
        if catalogue:
            if fresh:
                self._lag_states = {}
            n = next(iter(q.values())).size
            temps = {k: np.broadcast_to(np.asarray(v, dtype=np.float64), (n,))
                     for k, v in (temperatures or {}).items()}
            for sensor, values in temps.items():
                self.reference_temperatures_c.setdefault(sensor, float(values[0]))
            variables = Variables(q, None if time_s is None else np.asarray(time_s, float),
                                  dict(velocities or {}), dict(accelerations or {}),
                                  dict(directions or {}), temps,
                                  self.reference_temperatures_c, spindle_speed_rad_s,
                                  lag_states=None if run_starts is not None
                                  else self._lag_states, run_starts=run_starts)
            context = Context(self.machine, variables, self._kinematics, orientation,
                              work_point=work_point, located_readings=located_readings,
                              direction_measured=direction_measured)
            turned = np.zeros_like(orientation)
            for name, entry in catalogue.items():
                position = position + catalogue_error(name, entry, context)
                turned = turned + catalogue_orientation(name, entry, context)
            orientation = orientation + turned
        position = position + drive
        if self.datum and referred:
            position = position - self.datum_error(temperatures,
                                                   _datum_point(work_point))[None, :]
        return position, orientation

    def table_motion_errors(self, axis: str, grid: ArrayLike, *, include_user: bool = True,
                            strict: bool = False) -> dict[str, NDArray[np.float64]]:
        """Per-axis error motions of the fitted catalogue effects on ``grid`` (ISO name ->
        values [m or rad]), for a CNC's compensation table: a position-dependent error
        belongs in the table the CNC interpolates at its own command, not in a stream
        that arrives a few milliseconds (and, at feed, millimetres) late.

        Parameters
        ----------
        axis : str
            Axis letter.
        grid : array_like, shape (K,)
            Positions of ``axis`` [m] (rotary [rad]).
        include_user : bool, optional
            Add fitted user effects of this axis' position alone (:mod:`.user_tables`).
        strict : bool, optional
            Refuse a user effect of this axis' position that no table can hold.

        Returns
        -------
        dict of str to ndarray, shape (K,)
            ISO motion error name -> summed values [m] or [rad].
        """
        out: dict[str, NDArray[np.float64]] = {}
        for entry in self.effects.values():
            if not (is_catalogue_entry(entry) and "family" in entry):
                continue
            family = family_named(entry["family"])
            variant = entry.get("variant", "")
            if not hasattr(family, "motion_error") or variant[-1:] != axis:
                continue
            setting = entry.get("setting") or {}
            names = family.parameter_names(variant, setting)
            coefficients = [entry["coefficients"][n] for n in names]
            values = family.motion_error(self.machine, variant, setting, coefficients, grid)
            out[variant] = out.get(variant, 0.0) + values
            if hasattr(family, "pivot_motion_errors"):
                # A table's tilt about a pivot: its pivot's move is the axis' own
                # positioning and straightness.
                for name, moved in family.pivot_motion_errors(self._kinematics, variant,
                                                              setting, coefficients,
                                                              grid).items():
                    out[name] = out.get(name, 0.0) + moved
        if include_user:
            # Fitted user effects of this axis' position alone, as its error motions
            # (user_tables); ``strict`` refuses one of its position that no table can hold.
            from .user_tables import user_motion_errors

            for name, values in user_motion_errors(self, axis, grid, strict=strict).items():
                out[name] = out.get(name, 0.0) + values
        return out

    def component_errors(self, axis: str, grid: ArrayLike, *, include_user: bool = True,
                         strict: bool = False) -> dict[str, NDArray[np.float64]]:
        """The six ISO 230-1 component errors of a linear ``axis`` on ``grid`` [m or rad].

        The live profile where the model uses measured geometry (``geometric``),
        else the machine description's function, plus every fitted catalogue
        effect that is a function of this axis' position: what a CNC's per-axis
        compensation table holds.

        Parameters
        ----------
        axis : str
            Linear axis letter.
        grid : array_like, shape (K,)
            Positions of ``axis`` [m] (rotary [rad]).
        include_user : bool, optional
            Add fitted user effects of this axis' position alone.
        strict : bool, optional
            Refuse a user effect of this axis' position that no table can hold.

        Returns
        -------
        dict of str to ndarray, shape (K,)
            ``E<component><axis>`` for the six components -> values [m] (X, Y, Z) or
            [rad] (A, B, C).
        """
        spec = self.machine.axes[axis]
        grid = np.asarray(grid, dtype=np.float64)
        fitted = self.table_motion_errors(axis, grid, include_user=include_user, strict=strict)
        out = {}
        for component in "XYZABC":
            name = f"E{component}{axis}"
            function = self.profiles.get(name) if "geometric" in self.effects else None
            base = function(grid) if function is not None else spec.motion_errors[component](grid)
            out[name] = np.asarray(base, dtype=np.float64) + fitted.get(name, 0.0)
        return out

    def location_table(self) -> dict[str, float]:
        """Every location error the model holds (squareness, offsets) by ISO name [m or rad]:
        the calibrated description's, the ``squareness`` effect's and the catalogue's."""
        out: dict[str, float] = {}
        if "geometric" in self.effects:
            for name in self.machine.axis_order:
                for component, value in self.machine.axes[name].location_errors.items():
                    out[f"E{component}0{name}"] = float(value)
        out.update({k: float(v) for k, v in
                    self.effects.get("squareness", {}).get("errors_rad", {}).items()})
        for name, value in self.table_location_errors().items():
            out[name] = out.get(name, 0.0) + value
        return out

    def backlash_m(self, axis: str) -> float:
        """Reversal value of a linear axis [m]: the built-in and catalogue ``reversal``.

        Parameters
        ----------
        axis : str
            Linear axis letter.

        Returns
        -------
        float
            Total backlash [m] (0 when the model holds none for ``axis``).
        """
        total = 0.0
        builtin = self.effects.get("reversal")
        if isinstance(builtin, dict) and axis in builtin.get("axes", []):
            total += float(builtin.get("backlash_m", 0.0))
        for entry in self.effects.values():
            if is_catalogue_entry(entry) and entry.get("family") == "reversal" and \
                    entry.get("variant") == axis:
                total += float(entry["coefficients"]["backlash_m"])
        return total

    def table_location_errors(self) -> dict[str, float]:
        """Location errors of the fitted catalogue effects [m or rad]: squareness, rotary
        lines' offsets and tilts (ISO 230-7), a tilt's pivot lever as its carried lines'
        offsets - what a CNC's location block holds."""
        out: dict[str, float] = {}
        for entry in self.effects.values():
            if is_catalogue_entry(entry) and "family" in entry:
                family = family_named(entry["family"])
                if hasattr(family, "location_error"):
                    variant = entry.get("variant", "")
                    setting = entry.get("setting") or {}
                    names = family.parameter_names(variant, setting)
                    for name, value in family.location_error(
                            self.machine, variant, setting,
                            [entry["coefficients"][n] for n in names]).items():
                        out[name] = out.get(name, 0.0) + value
        return out

    @property
    def kinematics(self) -> KinematicModel:
        """The machine's nominal kinematic chain (what a controller inverts)."""
        return self._kinematics

    def axis_direction(self, axis: str, positions: dict[str, NDArray]) -> NDArray[np.float64]:
        """d(tool - workpiece)/d q_axis (N, 3): where a unit move of the axis takes the TCP.

        +unit for a tool-branch linear axis, -unit for one carrying the workpiece.

        Parameters
        ----------
        axis : str
            Axis letter.
        positions : dict of str to ndarray, shape (N,)
            Axis commands [m] (rotary [rad]).

        Returns
        -------
        ndarray, shape (N, 3)
            TCP displacement per unit command, [m/m] (per [rad] for a rotary axis), bed frame.
        """
        q = {a: np.asarray(v, dtype=np.float64) for a, v in positions.items()}
        step = 1e-6
        moved = dict(q)
        moved[axis] = q[axis] + step
        return (self._kinematics.nominal_relative(moved) - self._kinematics.nominal_relative(q)) \
            / step

    def correction(self, positions, temperatures=None, velocities=None) -> NDArray[np.float64]:
        """Value to add to the command [m]: minus the position error (first order).

        Parameters
        ----------
        positions : dict of str to array_like, shape (N,)
            Axis commands [m] (rotary [rad]).
        temperatures : dict of str to array_like, optional
            Sensor -> temperature [degC].
        velocities : dict of str to array_like, shape (N,), optional
            Axis -> velocity [m/s].

        Returns
        -------
        ndarray, shape (N, 3)
            Correction [m], bed frame.
        """
        return -self.tcp_error(positions, temperatures, velocities)[0]


def _check_user_variables(name: str, declaration: dict, machine: MachineDescription) -> None:
    """Every name in a user expression is a parameter or a variable this machine can have
    (temperatures are checked against the data when it arrives)."""
    from ..effects.expression import parse

    axes = [a.lower() for a in machine.axis_order]
    known = set(axes) | {"t", "spindle_speed", "spindle_rpm"} | \
        {f"{p}_{a}" for p in ("v", "acc", "dir") for a in axes}
    expression = parse(declaration["expression"], f"user effect {name!r}")
    unknown = sorted(n for n in expression.names - set(declaration["parameters"])
                     if n not in known and not (n.startswith("T_") and len(n) > 2))
    if unknown:
        raise ParameterError(f"user effect {name!r}: unknown variable {unknown[0]!r}; "
                             f"variables: {', '.join(sorted(known))}, T_<sensor>")


#: Readings of the representative grid a user expression is evaluated on at load.
_GRID_READINGS = 97


def representative_variables(machine: MachineDescription, names, readings: int = _GRID_READINGS
                             ) -> Variables:
    """The variables a model may meet on this machine, at ``readings`` points: every axis
    over its whole stroke (each in its own order, so the points spread over the work
    volume), the temperatures ``names`` asks for over the controller's temperature range
    about 20 degC, feeds, accelerations and directions of both signs up to the
    controller's feed, spindle speeds up to its maximum, 8 h of time.

    Parameters
    ----------
    machine : MachineDescription
        The machine (strokes and ``cnc:`` limits).
    names : iterable of str
        Variable names an expression uses; ``T_<sensor>`` ones get temperatures.
    readings : int, optional
        Number of points N.

    Returns
    -------
    Variables
        Positions [m] / [rad], time [s] over 8 h, feeds [m/s], accelerations within
        +-10 [m/s^2], directions +-1, temperatures [degC] and references (20 degC),
        spindle speed [rad/s]; every array shape (N,), seeded (reproducible).
    """
    from .limits import CorrectionLimits

    limits = CorrectionLimits.of(machine)
    rng = np.random.default_rng(0)
    sweep = np.linspace(0.0, 1.0, readings)
    positions = {}
    for axis in machine.axis_order:
        low, high = machine.axes[axis].stroke
        positions[axis] = low + (high - low) * rng.permutation(sweep)
    signed = np.linspace(-1.0, 1.0, readings)
    sensors = {n[2:] for n in names if n.startswith("T_") and len(n) > 2}
    temperatures = {sensor: 20.0 + limits.temperature_range_k * rng.permutation(signed)
                    for sensor in sensors}
    return Variables(positions, np.linspace(0.0, 8 * 3600.0, readings),
                     {a: limits.max_feed_m_per_s * rng.permutation(signed)
                      for a in machine.axis_order},
                     {a: 10.0 * rng.permutation(signed) for a in machine.axis_order},
                     {a: np.sign(rng.permutation(signed)) for a in machine.axis_order},
                     temperatures, {sensor: 20.0 for sensor in sensors},
                     limits.max_spindle_speed_rpm * 2 * np.pi / 60 * sweep)


def _check_user_evaluates(name: str, declaration: dict, machine: MachineDescription) -> None:
    """A user effect must evaluate - finite, linear in its parameters, at its fitted values
    and at its bounds - on the machine's representative grid, or the model does not load:
    a model that loads never fails mid-run (an overflow, a NaN)."""
    from ..effects.expression import parse
    from ..effects.user import UserExpression

    where = f"user effect {name!r}"
    names = parse(declaration["expression"], where).names
    context = Context(machine, representative_variables(machine, names))
    family = UserExpression(name, declaration)
    try:
        with np.errstate(all="ignore"):
            design = family.design(context, name, {})
            checks = []
            parameters = family.parameter_names(name, {})
            if "values" in declaration:
                checks.append(("its fitted values", [declaration["values"][p]
                                                     for p in parameters]))
            bounds = family.parameter_limits(context, name, {})
            if bounds:
                checks.append(("its bounds", [bounds.get(p, (0.0, ""))[0] for p in parameters]))
            for what, values in checks:
                error = design @ np.asarray(values, dtype=np.float64)
                if not np.all(np.isfinite(error)):
                    raise ParameterError(f"{where}: not finite at {what} on {machine.name}'s "
                                         "travel and temperature range")
    except ParameterError:
        raise
    except (ArithmeticError, ValueError, TypeError, MemoryError) as exc:
        raise ParameterError(f"{where}: cannot be evaluated on {machine.name}'s travel and "
                             f"temperature range ({type(exc).__name__}: {str(exc)[:200]})"
                             ) from exc


def _checked_catalogue_entry(name: str, entry: dict, machine: MachineDescription) -> dict:
    """A fitted catalogue effect or a user effect, checked so that it will evaluate."""
    if "expression" in entry:
        declaration = user_declaration(name, entry)
        _check_user_variables(name, declaration, machine)
        _check_user_evaluates(name, declaration, machine)
        return declaration
    allowed = {"family", "variant", "setting", "coefficients", "uncertainties"}
    unknown = set(entry) - allowed
    if unknown:
        raise ParameterError(f"effect {name}: unknown key(s) {', '.join(sorted(unknown))}; "
                             f"a catalogue effect has {', '.join(sorted(allowed))}")
    family = family_named(str(entry["family"]))
    variant = str(entry.get("variant", ""))
    setting = entry.get("setting") or {}
    if not isinstance(setting, dict):
        raise ParameterError(f"effect {name}: 'setting' must be a mapping")
    try:
        names = family.parameter_names(variant, setting)
    except (KeyError, TypeError, ValueError) as exc:
        raise ParameterError(f"effect {name}: setting {setting!r} does not fit family "
                             f"{family.name} ({exc})") from exc
    coefficients = entry.get("coefficients")
    if family.name == "rotary_location" and isinstance(coefficients, dict):
        zeros = sorted(k for k in coefficients if len(k) == 4 and k[1] == k[3] and k[2] == "0")
        if zeros:
            raise ParameterError(
                f"effect {name}: {', '.join(zeros)} is a zero-angle error, which the set-up "
                "takes out (each rotary body turns about its actual line from the set-up "
                f"pose, ISO 230-7): remove it; the coefficients are {', '.join(names)}")
    if not isinstance(coefficients, dict) or set(coefficients) != set(names):
        raise ParameterError(f"effect {name}: 'coefficients' must give {', '.join(names)}")
    return {"family": family.name, "variant": variant, "setting": dict(setting),
            "coefficients": {k: _finite(f"{name}.coefficients.{k}", v)
                             for k, v in coefficients.items()},
            **({"uncertainties": {str(k): float(v) for k, v in
                                  entry["uncertainties"].items()}}
               if isinstance(entry.get("uncertainties"), dict) else {})}


def model_to_dict(model: ErrorModel) -> dict:
    """The YAML form of a model (profiles excluded: they stream in live).

    Parameters
    ----------
    model : ErrorModel
        The model.

    Returns
    -------
    dict
        ``machine``, ``version``, ``effects``, ``reference_temperatures_c`` [degC] and,
        when set, ``datum`` [m / rad], ``datum_uncertainty_m`` and ``datum_correction_m`` [m].
    """
    out = {"machine": model.machine_source or model.machine.name, "version": int(model.version),
           "effects": {name: copy.deepcopy(params) for name, params in model.effects.items()},
           "reference_temperatures_c": dict(model.reference_temperatures_c)}
    if model.datum:
        out["datum"] = dict(model.datum)
    if model.datum_uncertainty_m is not None:
        out["datum_uncertainty_m"] = [float(v) for v in model.datum_uncertainty_m]
    if np.any(model.datum_correction_m):
        out["datum_correction_m"] = [float(v) for v in model.datum_correction_m]
    return out


@reraise_as(ParameterError, "model")
def model_from_dict(data: dict, source: str = "<dict>", base_dir: Path | None = None, *,
                    from_network: bool = False, model_dir: Path | None = None,
                    trusted_machines: tuple[str, ...] = ()) -> ErrorModel:
    """``{machine: NAME|PATH, effects: {name: {params} | true}, reference_temperatures_c: {}}``.

    ``from_network``: the model came from a message or a parameter any DDS peer may
    set; its machine must then be a bundled name, a plain file name in ``model_dir``
    (the node's configured directory) or one of ``trusted_machines`` (the machine
    the node was started with, as its model names it) - never another path.

    Raises only :class:`ParameterError` (malformed content of any kind included).

    Parameters
    ----------
    data : dict
        The parsed YAML mapping.
    source : str, optional
        Where ``data`` came from, quoted in messages.
    base_dir : pathlib.Path, optional
        Directory a relative machine path is resolved against (the model file's).
    from_network : bool, optional
        The model came from a DDS peer (see above).
    model_dir : pathlib.Path, optional
        The node's model directory.
    trusted_machines : tuple of str, optional
        Machine references a network model may also use.

    Returns
    -------
    ErrorModel
        The validated model, at the version ``data`` gives.

    Raises
    ------
    ParameterError
        Any malformed content, an invalid machine, or a refused machine path.
    """
    if not isinstance(data, dict) or "machine" not in data:
        raise ParameterError(f"{source}: a model needs 'machine' (bundled name or path)")
    if not isinstance(data["machine"], str):
        raise ParameterError(f"{source}: 'machine' must be a bundled name or a path")
    raw_effects = data.get("effects") or {}
    if not isinstance(raw_effects, dict):
        raise ParameterError(f"{source}: 'effects' must map effect names to their parameters "
                             f"(got a {type(raw_effects).__name__})")
    version = data.get("version", 1)
    if isinstance(version, bool) or not isinstance(version, int) or version < 0:
        raise ParameterError(f"{source}: 'version' must be a non-negative integer "
                             f"(got {version!r})")
    temperatures = data.get("reference_temperatures_c") or {}
    if not isinstance(temperatures, dict):
        raise ParameterError(f"{source}: 'reference_temperatures_c' must map sensors to degC")
    effects = {}
    for name, value in raw_effects.items():
        if value is False:
            continue
        if not (value is True or value is None or isinstance(value, dict)):
            raise ParameterError(f"{source}: effects.{name} must be true, false or a mapping "
                                 "of parameters")
        effects[str(name)] = {} if value is True or value is None else dict(value)
    try:
        machine_source = str(data["machine"])
        if from_network and machine_source not in trusted_machines:
            machine_source = _network_machine(machine_source, model_dir)
        elif not Path(machine_source).is_absolute() and base_dir is not None and \
                (base_dir / machine_source).is_file():
            machine_source = str((base_dir / machine_source).resolve())
        model = ErrorModel(load_machine(machine_source), effects,
                           {str(k): float(v) for k, v in
                            (data.get("reference_temperatures_c") or {}).items()},
                           machine_source=machine_source, datum=data.get("datum") or {},
                           datum_uncertainty_m=data.get("datum_uncertainty_m"),
                           datum_correction_m=data.get("datum_correction_m", np.zeros(3)))
    except (ParameterError, MachineDescriptionError) as exc:
        raise ParameterError(f"{source}: {exc}") from exc
    model.version = version
    return model


BUNDLED_MODELS = Path(__file__).resolve().parents[2] / "models"


@reraise_as(ParameterError, "model")
def _inline(text: str) -> bool:
    return "\n" in text or text.startswith("{")


def _in_directory(name: str, directory: Path | None, what: str) -> Path | None:
    """``directory / name`` when ``name`` is a plain file name of a regular file that
    stays inside ``directory`` (a symlink out of it is refused), else None."""
    if directory is None or not plain_name(name):
        return None
    path = directory / name
    if not path.is_file():
        return None
    if path.resolve().parent != directory.resolve():
        raise ParameterError(f"{what} {name!r} in the model directory links outside it: refused")
    return path


def _network_machine(name: str, model_dir: Path | None) -> str:
    """A network model's machine: a bundled name or a plain file name in ``model_dir``."""
    for candidate in (name, f"{name}.yaml"):
        path = _in_directory(candidate, model_dir, "machine")
        if path is not None and path.suffix in (".yaml", ".yml"):
            return str(path)
    if plain_name(name) and not Path(name).suffix:
        return name   # a bundled name; load_machine refuses any other
    raise ParameterError(f"machine {name[:80]!r} refused: a model from the network names a "
                         "bundled machine or a file in the node's model_dir, never a path")


def resolve_model(text: str, *, from_network: bool = False, model_dir: str | Path | None = None,
                  trusted_machines: tuple[str, ...] = ()) -> ErrorModel:
    """A bundled model name (``demo``), a path to a model YAML, or inline YAML text.

    Parameters
    ----------
    text : str
        What the user (or a peer) gave.
    from_network : bool
        True for a model a DDS peer can send (the ``model`` topic, a ``model``
        parameter set at run time): it is then inline YAML, a bundled model name, or
        a plain file name in ``model_dir`` - **never a path** - and its machine is a
        bundled name or a file in ``model_dir``. False for the command line and a
        node's start-up parameters, where paths are the user's own.
    model_dir : str or Path, optional
        The one directory network-named files may come from (a node's ``model_dir``
        parameter; none by default).
    trusted_machines : tuple of str
        Machine references a network model may also use: the node's start-up machine
        (a monitor publishes its versions naming the machine it was started with).

    Every file is read as a regular file of bounded size, and errors never quote
    a file's content (:mod:`mt_accuracy_ros.core.inputs.safe_files`).

    Returns
    -------
    ErrorModel
        The model, its machine resolved.

    Raises
    ------
    ParameterError
        No such model, or a path where a network-named model may give none.
    """
    text = str(text).strip()
    directory = Path(model_dir) if model_dir else None
    if _inline(text):
        data = load_yaml(text, "inline model", ParameterError)
        return model_from_dict(data, "<inline model>", from_network=from_network,
                               model_dir=directory, trusted_machines=trusted_machines)
    bundled = BUNDLED_MODELS / f"{text}.yaml"
    if plain_name(text) and not Path(text).suffix and bundled.is_file():
        return load_model(bundled)
    if from_network:
        path = _in_directory(text, directory, "model")
        if path is None or path.suffix not in (".yaml", ".yml"):
            raise ParameterError(
                f"model {text[:80]!r} refused: a model from the network is inline YAML, a "
                f"bundled model ({', '.join(_bundled_model_names())}) or a model file in "
                "the node's model_dir" + ("" if directory else " (none configured)") +
                ", never a path")
        return load_model(path, from_network=True, model_dir=directory,
                          trusted_machines=trusted_machines)
    path = Path(text)
    if path.suffix in (".yaml", ".yml") or path.exists():
        return load_model(path)
    raise ParameterError(f"no model {text[:80]!r} (bundled: {', '.join(_bundled_model_names())}"
                         "; or a path, or inline YAML)")


def _bundled_model_names() -> list[str]:
    return sorted(p.stem for p in BUNDLED_MODELS.glob("*.yaml"))


def load_model(path, *, from_network: bool = False, model_dir: Path | None = None,
               trusted_machines: tuple[str, ...] = ()) -> ErrorModel:
    """A model YAML file (regular, bounded in size; errors do not quote it).

    Parameters
    ----------
    path : str or pathlib.Path
        The model file.
    from_network : bool, optional
        The file was named by a DDS peer (its machine is then restricted, see
        :func:`model_from_dict`).
    model_dir : pathlib.Path, optional
        The node's model directory.
    trusted_machines : tuple of str, optional
        Machine references a network model may also use.

    Returns
    -------
    ErrorModel
        The validated model.

    Raises
    ------
    ParameterError
        An unreadable or oversized file, bad YAML, or invalid content.
    """
    path = Path(path)
    text = read_description(path, "model", ParameterError)
    data = load_yaml(text, str(path), ParameterError)
    return model_from_dict(data, str(path), base_dir=path.parent, from_network=from_network,
                           model_dir=model_dir, trusted_machines=trusted_machines)
