"""Rotary-axis location errors from a probed calibration sphere (the KinematicsOpt job).

A sphere is fixed on the machine's workpiece side and probed with a touch
probe in the spindle at several positions of the rotary axes. Each probing
cycle gives touch points on the sphere; :func:`fit_sphere` turns them into
the sphere's centre. Where the CNC expected the centre (its nominal
kinematics) and where the probe found it differ by minus the TCP error of
that configuration (Khan & Chen eq. 17: e = (P_t - P_w)_actual - nominal):
the probe tip is off by e relative to the workpiece, so the sphere appears
off by -e.

:func:`identify_location_errors` fits, by Gauss-Newton least squares through
the kinematic chain (:class:`..kinematics.chain.KinematicModel`), the
position-independent location errors of the rotary axes - for an axis about
x (A) the offsets EY0A, EZ0A of its line and the tilts EB0A, EC0A; likewise
for B and C (Khan & Chen's notation, section 5) - together with the sphere's
unknown setup position (3 nuisance parameters), and reports:

* each error with its standard uncertainty (sigma^2 (J^T J)^-1);
* the dispersion: the RMS and largest distance between measured and modelled
  centres before and after (what KinematicsOpt calls the dispersion);
* the repeatability of repeated cycles at the same configuration.

Each rotary body turns about its actual axis line from the pose where the
sphere and the probe were set up (ISO 230-7; the machine's ``setup_pose``), so
the zero-angle error of each side's last rotary axis is taken out by the set-up and
is never identifiable, nor is an offset along an axis' own line; an outer axis' zero
turns the lines it carries, so the sphere sees it as their tilt and offset, folded
into them. A zero and an offset along the line are refused by name when asked for, and
said otherwise.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import CalibrationError, InputDataError, MachineDescriptionError
from ..kinematics.chain import ErrorOverrides, KinematicModel
from ..kinematics.machine import MachineDescription, location_error_name, outer_zeros
from ..validation import finite_array

LETTERS = "XYZ"


# ------------------------------------------------------------------- spheres
@dataclass(frozen=True)
class SphereFit:
    """Centre (3,) [m], radius [m], and each point's distance from the surface (m,) [m].

    Attributes
    ----------
    centre_m : ndarray, shape (3,)
        Centre [m], the points' frame.
    radius_m : float
        Radius [m] (the given one when fixed).
    residuals_m : ndarray, shape (m,)
        Each point's distance from the surface [m], outward positive.
    """

    centre_m: NDArray[np.float64]
    radius_m: float
    residuals_m: NDArray[np.float64]


def fit_sphere(points_m: ArrayLike, radius_m: float | None = None, *,
               tolerance_m: float = 50e-6, label: str = "sphere") -> SphereFit:
    """Least-squares sphere through touch points.

    The algebraic fit |p|^2 = 2 p.c + (r^2 - |c|^2) starts a geometric
    Gauss-Newton on the distances |p - c| - r (with r fixed when the sphere's
    calibrated radius is given).

    Parameters
    ----------
    points_m : array_like, shape (m, 3)
        Touch points [m].
    radius_m : float, optional
        The sphere's calibrated radius [m]; fitted when None.
    tolerance_m : float, optional
        Largest distance of a point from the fitted surface [m].
    label : str, optional
        The sphere, named in errors.

    Returns
    -------
    SphereFit
        Centre (3,) [m], radius [m] and residuals (m,) [m].

    Raises
    ------
    InputDataError
        Fewer than 4 points (5 without a radius), NaN, points in a plane, or a
        point farther than ``tolerance_m`` from the fitted surface (named by
        index: a touch on something else, or a wrong radius).
    """
    points = finite_array(points_m, f"{label}: touch points", ndim=2)
    if points.shape[1] != 3:
        raise InputDataError(f"{label}: touch points must be (m, 3), got {points.shape}")
    needed = 4 if radius_m is not None else 5
    if points.shape[0] < needed:
        raise InputDataError(f"{label}: {points.shape[0]} touch points; at least {needed} "
                             "are needed")
    spread = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)
    if spread[-1] < 1e-9 * max(spread[0], 1e-12):
        raise InputDataError(f"{label}: the touch points lie in a plane; probe the sphere "
                             "from more than one side")
    design = np.column_stack([2 * points, np.ones(points.shape[0])])
    solution, *_ = np.linalg.lstsq(design, (points ** 2).sum(axis=1), rcond=None)
    centre = solution[:3]
    radius = float(np.sqrt(max(solution[3] + centre @ centre, 0.0)))
    if radius_m is not None:
        radius = float(radius_m)
    for _ in range(20):
        offset = points - centre
        distance = np.linalg.norm(offset, axis=1)
        residual = distance - radius
        unit = offset / distance[:, None]
        jacobian = -unit if radius_m is not None else np.column_stack([-unit,
                                                                       -np.ones(len(unit))])
        step, *_ = np.linalg.lstsq(jacobian, -residual, rcond=None)
        centre = centre + step[:3]
        if radius_m is None:
            radius += float(step[3])
        if np.max(np.abs(step)) < 1e-13:
            break
    residuals = np.linalg.norm(points - centre, axis=1) - radius
    worst = int(np.argmax(np.abs(residuals)))
    if abs(residuals[worst]) > tolerance_m:
        raise InputDataError(
            f"{label}: touch point {worst} is {residuals[worst] * 1e3:+.3f} mm from the sphere "
            f"(tolerance {tolerance_m * 1e3:.3f} mm) - a touch on something else, or a wrong "
            "sphere radius")
    return SphereFit(centre, radius, residuals)


# --------------------------------------------------------- location errors
def default_rotary_parameters(machine: MachineDescription) -> list[str]:
    """For each rotary axis: the two offsets of its line and its two tilts.

    A (about x): EY0A, EZ0A, EB0A, EC0A; B (about y): EX0B, EZ0B, EA0B, EC0B;
    C (about z): EX0C, EY0C, EA0C, EB0C.

    Parameters
    ----------
    machine : MachineDescription
        The machine.

    Returns
    -------
    list of str
        ISO 230-7 location error names (offsets [m], tilts [rad]), then each rotary axis'
        zero-angle error [rad].
    """
    names = []
    for axis in machine.axis_order:
        spec = machine.axes[axis]
        if not spec.is_rotary:
            continue
        own = "ABC".index(axis)
        others = [i for i in range(3) if i != own]
        names += [location_error_name(LETTERS[i], axis) for i in others]
        names += [location_error_name("ABC"[i], axis) for i in others]
    # Zero-angle errors last: a sphere off an axis' line sees its own (asked for by name,
    # EB0B came back 27.9 +- 3.2 urad with 30 true); observable_parameters keeps
    # one only where the setup separates it from the rest.
    for axis in machine.axis_order:
        if machine.axes[axis].is_rotary:
            names.append(location_error_name(axis, axis))
    return names


@dataclass
class LocationIdentification:
    """Result of :func:`identify_location_errors`.

    Attributes
    ----------
    parameters : dict of str to float
        Location error name -> value [m] or [rad].
    uncertainties : dict of str to float
        Name -> standard (k = 1) uncertainty [m] or [rad].
    sphere_offset_m : ndarray, shape (3,)
        The sphere's position error, workpiece frame [m].
    residuals_m : ndarray, shape (N, 3)
        Measured - modelled deviation [m].
    measured_m : ndarray, shape (N, 3)
        The deviations as measured [m].
    condition_number : float
        Of the scaled Jacobian.
    repeatability_m : float or None
        Pooled standard deviation of repeated cycles [m].
    correlations : dict of str to float
        ``"a~b"`` -> correlation of two parameters, where |r| > 0.9.
    not_observable : list of str
        Default parameters one sphere could not separate (left at zero).
    aliases : dict of str to dict of str to float
        What a fitted parameter stands for when others fold into it.
    probe_length_aliases : dict of str to float
        Tool-side line offsets that mimic a probe length change: name -> that change per
        +1 of it.
    """

    parameters: dict[str, float]                  # name -> value [m or rad]
    uncertainties: dict[str, float]               # name -> standard (k = 1) uncertainty
    sphere_offset_m: NDArray[np.float64]          # (3,) sphere position error, workpiece frame
    residuals_m: NDArray[np.float64]              # (N, 3) measured - modelled deviation
    measured_m: NDArray[np.float64]               # (N, 3) the deviations as measured
    condition_number: float
    repeatability_m: float | None = None          # pooled std of repeated cycles
    correlations: dict[str, float] = field(default_factory=dict)
    #: Default parameters one sphere could not separate (left at zero).
    not_observable: list[str] = field(default_factory=list)
    #: What a fitted parameter stands for when others fold into it: name -> {folded
    #: name: coefficient} (EZ0A's value is EZ0A + c EZ0B).
    aliases: dict[str, dict[str, float]] = field(default_factory=dict)
    #: Offsets of a tool-side axis' line along the tool, which move the centres as a probe
    #: longer or shorter would: name -> the probe length change that mimics +1 of it.
    probe_length_aliases: dict[str, float] = field(default_factory=dict)

    def identified_as(self, name: str) -> str:
        """``EZ0A - EZ0B`` for a parameter others fold into, else the name.

        Parameters
        ----------
        name : str
            A fitted parameter's name.

        Returns
        -------
        str
            The name, with the parameters folded into it and their coefficients.
        """
        text = name
        for other, c in self.aliases.get(name, {}).items():
            size = abs(c)
            # A coefficient between an offset and an angle has a unit: say it.
            mixed = (name[1] in LETTERS) != (other[1] in LETTERS)
            unit = (" m/rad x" if name[1] in LETTERS else " rad/m x") if mixed else ""
            text += f" {'+' if c > 0 else '-'} " + (
                other if abs(size - 1) < 0.02 and not mixed else f"{size:.2g}{unit} {other}")
        return text

    @property
    def dispersion_before_m(self) -> float:
        """Largest distance of a measured centre from the mean of all (sphere misplacement
        removed): how much the centre wandered as the axes turned."""
        centred = self.measured_m - self.measured_m.mean(axis=0)
        return float(np.max(np.linalg.norm(centred, axis=1)))

    @property
    def dispersion_after_m(self) -> float:
        """Largest distance between a measured and a modelled centre."""
        return float(np.max(np.linalg.norm(self.residuals_m, axis=1)))

    @property
    def rms_after_m(self) -> float:
        return float(np.sqrt(np.mean(np.sum(self.residuals_m ** 2, axis=1))))

    def as_dict(self) -> dict:
        return {"parameters": dict(self.parameters), "uncertainties_k1": dict(self.uncertainties),
                "sphere_offset_m": self.sphere_offset_m.tolist(),
                "dispersion_before_m": self.dispersion_before_m,
                "dispersion_after_m": self.dispersion_after_m, "rms_after_m": self.rms_after_m,
                "condition_number": self.condition_number,
                "repeatability_m": self.repeatability_m, "cycles": int(self.measured_m.shape[0]),
                "not_observable": list(self.not_observable), "misfit": self.misfit,
                "identified_as": {n: self.identified_as(n) for n in self.parameters},
                "probe_length_aliases": dict(self.probe_length_aliases)}

    @property
    def misfit(self) -> str:
        """Why the fit does not describe the data ("" when it does): what it leaves per
        centre well above the repeated cycles' repeatability, with the likely causes."""
        if not self.repeatability_m:
            return ""
        scatter = self.rms_after_m / np.sqrt(3.0)          # per coordinate, as the repeatability
        floor = max(self.repeatability_m, 0.05e-6)
        if scatter <= MISFIT_FACTOR * floor:
            return ""
        return (f"misfit: the fit leaves {scatter * 1e6:.2f} um of scatter per coordinate, "
                f"{scatter / floor:.0f} x the repeatability ({self.repeatability_m * 1e6:.2f} "
                "um) - likely causes: the probe or tool length, the sphere's nominal position "
                "(--sphere-mm), the axes' nominal positions, or the angle units")

    def text(self) -> str:
        lines = [f"probing: {self.measured_m.shape[0]} cycles; dispersion "
                 f"{self.dispersion_before_m * 1e6:.1f} um before, "
                 f"{self.dispersion_after_m * 1e6:.1f} um after "
                 f"(RMS {self.rms_after_m * 1e6:.2f} um)",
                 "  repeatability of repeated cycles " +
                 (f"{self.repeatability_m * 1e6:.2f} um" if self.repeatability_m else
                  "unknown (no cycle repeated)") +
                 f"; condition number {self.condition_number:.3g}"]
        if self.misfit:
            lines.append(f"  {self.misfit}")
        if self.condition_number > ILL_CONDITIONED:
            lines.append(f"  warning: a badly conditioned design (condition number "
                         f"{self.condition_number:.3g}): the probed positions barely separate "
                         "the parameters - probe the rotary axes over wider angles")
        for name, value in self.parameters.items():
            u = self.uncertainties[name]
            label = self.identified_as(name)
            if name[1] in LETTERS:
                lines.append(f"  {label} {value * 1e6:+9.2f} um  (U, k=2: {2 * u * 1e6:.2f} um)")
            else:
                lines.append(f"  {label} {value * 1e6:+9.2f} urad (U, k=2: "
                             f"{2 * u * 1e6:.2f} urad)")
        s = self.sphere_offset_m * 1e6
        lines.append(f"  sphere set up {s[0]:+.1f}, {s[1]:+.1f}, {s[2]:+.1f} um from its "
                     "nominal place")
        folded = {o for names in self.aliases.values() for o in names}
        absorbed = [n for n in self.not_observable if n not in folded]
        turned = sorted(n for n in folded if n[1] == n[3])
        if folded - set(turned):
            lines.append(f"  folded into the parameters above (one sphere cannot part them): "
                         f"{', '.join(sorted(folded - set(turned)))}")
        if turned:
            lines.append(f"  folded into the parameters above: {', '.join(turned)} - an outer "
                         "axis' zero-angle error turns the lines it carries about its own "
                         "(ISO 230-7), which the sphere sees as their tilt and offset")
        for name, ratio in self.probe_length_aliases.items():
            value = self.parameters[name]
            lines.append(f"  {name} moves the centres as a probe {abs(value * ratio) * 1e6:.1f} um "
                         f"{'longer' if value * ratio > 0 else 'shorter'} would: one sphere "
                         "cannot part them (the probe is taken as calibrated)")
        zeros = [n for n in absorbed if n[1] == n[3]]
        others = [n for n in absorbed if n[1] != n[3]]
        if zeros:
            lines.append(f"  not observable: {', '.join(zeros)} - a zero-angle error is taken "
                         "out by the set-up (from where the sphere and the probe were set up "
                         "every axis turns by its commanded increments; left at zero)")
        if others:
            lines.append(f"  not observable with one sphere at these positions (they move the "
                         f"sphere's set-up position alone; left at zero): {', '.join(others)}")
        return "\n".join(lines)


def _check_inputs(machine: MachineDescription, positions: dict, deviations: NDArray,
                  names: list[str]) -> dict[str, NDArray]:
    n = deviations.shape[0]
    q = {}
    for axis in machine.axis_order:
        if axis not in positions:
            raise InputDataError(f"probing: no positions for axis {axis}")
        values = finite_array(positions[axis], f"probing: axis {axis} positions", ndim=1)
        if values.size != n:
            raise InputDataError(f"probing: axis {axis} has {values.size} positions for "
                                 f"{n} measured centres")
        q[axis] = values
    unknown = set(positions) - set(machine.axis_order)
    if unknown:
        raise InputDataError(f"probing: unknown axis {', '.join(sorted(unknown))}; this "
                             f"machine has {', '.join(machine.axis_order)}")
    for axis in machine.axis_order:
        values = q[axis]
        distinct = np.unique(np.round(values, 12)).size
        if machine.axes[axis].is_rotary and distinct >= 3 and \
                0 < np.degrees(np.ptp(values)) <= RADIAN_SPAN_DEG:
            raise InputDataError(
                f"probing: the {axis} axis was probed over {np.degrees(np.ptp(values)):.3g} deg "
                f"only - radians in the {axis}_deg column? (a calibration turns the axis "
                "tens of degrees)")
    for name in names:
        axis = name[-1]
        if axis not in machine.axes or len(name) != 4 or name[0] != "E" or name[2] != "0":
            raise MachineDescriptionError(f"probing: {name!r} is not a location error of "
                                          f"this machine's axes ({', '.join(machine.axis_order)})")
        if machine.axes[axis].is_rotary and np.unique(np.round(q[axis], 9)).size < 3:
            raise InputDataError(f"probing: {name} needs the {axis} axis probed at 3 or more "
                                 f"positions (got {np.unique(np.round(q[axis], 9)).size})")
    return q


def identify_location_errors(machine: MachineDescription, positions: dict[str, ArrayLike],
                             centre_deviation_m: ArrayLike, parameters: list[str] | None = None,
                             *, sphere_nominal_m: ArrayLike | None = None,
                             iterations: int = 6) -> LocationIdentification:
    """Location errors and the sphere's setup position from probed sphere centres.

    Parameters
    ----------
    machine : MachineDescription
        The machine description; its own errors are *not* used (the fit finds
        the location errors alone).
    positions : dict of str to array_like, shape (N,)
        Axis letter -> commanded positions of every axis at each cycle [m] (rotary [rad]).
    centre_deviation_m : array_like, shape (N, 3)
        Found minus expected sphere centre, machine (bed) frame [m].
    parameters : list of str, optional
        Location-error names to identify (default :func:`default_rotary_parameters`,
        those one sphere can separate: :func:`observable_parameters`).
    sphere_nominal_m : array_like, shape (3,), optional
        The sphere centre in the workpiece-end frame, as the cycle assumed
        it (default: the machine's workpiece point) [m].
    iterations : int, optional
        Most Gauss-Newton iterations.

    Returns
    -------
    LocationIdentification
        Values [m] or [rad] with standard (k = 1) uncertainties, the sphere's offset
        (3,) [m], residuals (N, 3) [m], the condition number and what was not
        observable.

    Raises
    ------
    InputDataError, MachineDescriptionError
        Mismatched, non-finite or unknown inputs (named).
    CalibrationError
        Parameters the probed positions cannot separate, named.
    """
    deviations = finite_array(centre_deviation_m, "probing: centre deviations", ndim=2)
    if deviations.shape[1] != 3:
        raise InputDataError(f"probing: centre deviations must be (N, 3), got {deviations.shape}")
    names = list(parameters) if parameters is not None else default_rotary_parameters(machine)
    if not names:
        raise MachineDescriptionError(f"probing: {machine.name} has no rotary axis to calibrate")
    q = _check_inputs(machine, positions, deviations, names)
    not_observable: list[str] = []
    if parameters is None:
        names, not_observable = observable_parameters(machine, q, sphere_nominal_m=sphere_nominal_m)
    n, p = deviations.shape[0], len(names)
    if 3 * n <= p + 3:
        raise InputDataError(f"probing: {n} cycles cannot fix {p} errors and the sphere's "
                             "position; probe more positions")
    nominal_point = np.asarray(machine.workpiece if sphere_nominal_m is None else
                               finite_array(sphere_nominal_m, "probing: sphere position",
                                            ndim=1), float)
    labels = [*names, "sphere x", "sphere y", "sphere z"]
    predicted = _predictor(machine, q, names, nominal_point)
    theta = np.zeros(p + 3)
    for _ in range(iterations):
        base = predicted(theta)
        scaled, scale = _scaled_jacobian(predicted, theta, labels)
        _, singular, vt = np.linalg.svd(scaled, full_matrices=False)
        if singular[-1] < RANK_TOLERANCE * singular[0]:
            null = np.abs(vt[-1])
            involved = [labels[j] for j in np.flatnonzero(null > 0.3 * null.max())]
            raise CalibrationError(f"probing: {' and '.join(involved)} cannot be told apart "
                                   "with this sphere and these positions; leave one out or "
                                   "probe more positions")
        step, *_ = np.linalg.lstsq(scaled, (deviations - base).ravel(), rcond=None)
        theta = theta + step / scale
        if np.max(np.abs(step / scale)) < 1e-12:
            break
    residuals = deviations - predicted(theta)
    before = float(np.max(np.linalg.norm(deviations - deviations.mean(axis=0), axis=1)))
    after = float(np.max(np.linalg.norm(residuals, axis=1)))
    if after > before:
        raise CalibrationError(
            f"probing: the fit makes the dispersion worse ({before * 1e6:.1f} um before, "
            f"{after * 1e6:.1f} um after): the model does not describe these data - check the "
            "angle units, the probe or tool length and the sphere's nominal position")
    dof = 3 * n - (p + 3)
    sigma2 = float(np.sum(residuals ** 2)) / dof
    covariance = sigma2 * np.linalg.inv(scaled.T @ scaled) / np.outer(scale, scale)
    std = np.sqrt(np.diag(covariance))
    correlation = covariance / np.outer(std, std)
    correlations = {f"{names[i]}~{names[j]}": float(correlation[i, j])
                    for i in range(p) for j in range(i + 1, p) if abs(correlation[i, j]) > 0.9}
    aliases = _aliases(machine, q, names, not_observable, nominal_point) if not_observable \
        else {}
    for kept, zeros in _outer_zero_folds(machine, q, names, not_observable,
                                         nominal_point).items():
        aliases.setdefault(kept, {}).update(zeros)
    return LocationIdentification(
        dict(zip(names, (float(v) for v in theta[:p]))),
        dict(zip(names, (float(v) for v in std[:p]))), theta[p:].copy(), residuals, deviations,
        float(singular[0] / singular[-1]), _repeatability(q, deviations), correlations,
        not_observable, aliases, _probe_length_aliases(machine, q, names, nominal_point))


def _probe_length_aliases(machine: MachineDescription, q: dict[str, NDArray],
                          names: list[str], point: NDArray, step: float = 1e-6
                          ) -> dict[str, float]:
    """The fitted offsets of tool-side rotary axes whose effect on the centres is a probe
    length change's (the columns parallel within 0.1 %, each up to the sphere's set-up):
    name -> the probe length change that mimics +1 of it."""
    from dataclasses import replace

    tool = np.asarray(machine.tool, dtype=np.float64)
    if not np.linalg.norm(tool) or not any(machine.axes[a].is_rotary
                                           for a in machine.tool_branch):
        return {}
    longer = replace(machine, tool=tool + step * tool / np.linalg.norm(tool))
    # A longer probe moves every found centre by what it moves the tip.
    length = (KinematicModel(longer).nominal_relative(q, work_point=point) -
              KinematicModel(machine).nominal_relative(q, work_point=point)) / step
    predicted = _predictor(machine, q, names, point)
    base = predicted(np.zeros(len(names) + 3))
    b = (length - length.mean(axis=0)).ravel()
    out = {}
    for j, name in enumerate(names):
        if name[-1] not in machine.tool_branch or name[1] not in LETTERS:
            continue
        theta = np.zeros(len(names) + 3)
        theta[j] = step
        column = (predicted(theta) - base) / step
        a = (column - column.mean(axis=0)).ravel()
        if a @ a > 0 and b @ b > 0 and abs(a @ b) >= 0.999 * np.sqrt((a @ a) * (b @ b)):
            out[name] = float(a @ b / (b @ b))
    return out


def _aliases(machine: MachineDescription, q: dict[str, NDArray], kept: list[str],
             dropped: list[str], point: NDArray, step: float = 1e-6
             ) -> dict[str, dict[str, float]]:
    """What each dropped parameter folds into: its effect on the centres as a combination
    of the kept parameters' and the sphere's (least squares on the first-order columns);
    kept -> {dropped: coefficient} where the coefficient is above 5 %."""
    names = kept + dropped
    predicted = _predictor(machine, q, names, point)
    base = predicted(np.zeros(len(names) + 3)).ravel()
    columns = []
    for j in range(len(names) + 3):
        theta = np.zeros(len(names) + 3)
        theta[j] = step
        columns.append((predicted(theta).ravel() - base) / step)
    columns = np.column_stack(columns)
    basis = np.column_stack([columns[:, :len(kept)], columns[:, len(names):]])
    out: dict[str, dict[str, float]] = {}
    for i, name in enumerate(dropped):
        coefficients, *_ = np.linalg.lstsq(basis, columns[:, len(kept) + i], rcond=None)
        for k, value in enumerate(coefficients[:len(kept)]):
            if abs(value) > 0.05:
                out.setdefault(kept[k], {})[name] = float(value)
    return out


def _outer_zero_folds(machine: MachineDescription, q: dict[str, NDArray], kept: list[str],
                      dropped: list[str], point: NDArray) -> dict[str, dict[str, float]]:
    """What each dropped outer axis' zero folds into: kept -> {zero: coefficient}.

    An outer axis' zero e turns the lines it carries about its own (ISO 230-7): the sphere,
    located at the set-up, sees the carried line turned by e - its tilt and its offset
    (:func:`~..kinematics.machine.outer_zeros`). The chain turns each body about its line
    from the set-up and so cannot make a zero; its reading as a located sphere's
    (:meth:`~..kinematics.chain.KinematicModel.located_sensitivities`) is taken on the
    kept parameters and the sphere's set-up position by least squares. A zero that those
    leave more than :data:`ZERO_FOLD_REST` of is not folded (nor one that moves nothing).
    """
    rotary = "".join(a for a in machine.axis_order if machine.axes[a].is_rotary)
    zeros = [name for name in dropped if name in outer_zeros(machine, rotary)]
    if not zeros or not kept:
        return {}
    model = KinematicModel(machine)
    found = model.located_sensitivities(q, kept + zeros, work_point=point)
    # The sphere's set-up position: a translation of the workpiece frame, turning with it.
    work = model.branch("workpiece", q, errors=False, check_stroke=False)[:, :3, :3]
    columns = [found[name][0].ravel() for name in kept]
    basis = np.column_stack(columns + [work[:, :, i].ravel() for i in range(3)])
    out: dict[str, dict[str, float]] = {}
    for zero in zeros:
        column = found[zero][0].ravel()
        norm = float(np.linalg.norm(column))
        coefficients, *_ = np.linalg.lstsq(basis, column, rcond=None)
        if norm == 0.0 or np.linalg.norm(column - basis @ coefficients) > ZERO_FOLD_REST * norm:
            continue
        for name, value, own in zip(kept, coefficients, columns):
            if abs(value) * float(np.linalg.norm(own)) > 1e-3 * norm:
                out.setdefault(name, {})[zero] = float(value)
    return out


#: An outer zero whose located reading the kept parameters and the sphere leave more than
#: this fraction of is not said to fold into them.
ZERO_FOLD_REST = 1e-4
RANK_TOLERANCE = 1e-7
#: A column this small against the largest is round-off: the parameter moves nothing.
ZERO_COLUMN = 1e-7
#: Condition number (of the scaled Jacobian) above which the design is called badly
#: conditioned (the simulated +-60 deg plan gives about 16).
ILL_CONDITIONED = 1e3
#: Remaining scatter above this many times the repeatability: a misfit (said, not hidden).
MISFIT_FACTOR = 3.0
#: Rotary positions whose whole span is at most this many degrees (a full turn's 2 pi,
#: read as degrees) were radians written into a degree column - no calibration turns an
#: axis through less.
RADIAN_SPAN_DEG = 2.0 * np.pi * 1.01


def _predictor(machine: MachineDescription, q: dict[str, NDArray], names: list[str],
               nominal_point: NDArray):
    """theta = (errors..., sphere offset (3)) -> (N, 3) predicted centre deviations."""
    p = len(names)
    # The sphere is a fixed target on the workpiece side: the error is taken there.
    model = KinematicModel(machine)
    nominal = model.nominal_relative(q, work_point=nominal_point)

    def predicted(theta: NDArray) -> NDArray:
        sphere = nominal_point + theta[p:]
        overrides = ErrorOverrides(location=dict(zip(names, theta[:p])), use_description=False)
        error = model.tcp_error(q, overrides=overrides, check_stroke=False,
                                work_point=sphere)["position"]
        return -(error + model.nominal_relative(q, work_point=sphere) - nominal)
    return predicted


def _scaled_jacobian(predicted, theta: NDArray, labels: list[str], step: float = 1e-6
                     ) -> tuple[NDArray, NDArray]:
    """Central-difference Jacobian with unit-norm columns, and the column norms."""
    columns = []
    for j in range(theta.size):
        delta = np.zeros(theta.size)
        delta[j] = step
        columns.append(((predicted(theta + delta) - predicted(theta - delta)) / (2 * step)).ravel())
    jacobian = np.column_stack(columns)
    scale = np.linalg.norm(jacobian, axis=0)
    # A parameter the set-up takes out (a zero error, an offset along its own line) moves
    # the centres by round-off alone: relative to the largest column, it moves nothing.
    zero = scale < max(1e-12, ZERO_COLUMN * float(scale.max(initial=0.0)))
    if zero.any():
        bad = [labels[j] for j in np.flatnonzero(zero)]
        raise CalibrationError(f"probing: {', '.join(bad)} do(es) not change the probed "
                               "centres at these positions")
    return jacobian / scale, scale


def observable_parameters(machine: MachineDescription, positions: dict[str, ArrayLike],
                          candidates: list[str] | None = None, *,
                          sphere_nominal_m: ArrayLike | None = None
                          ) -> tuple[list[str], list[str]]:
    """Split ``candidates`` into those one sphere at these positions can identify and the rest.

    Candidates are taken in order (tilts before offsets by default) and kept
    while each adds a direction the sphere's position and the kept ones do
    not already span. A translation of a rotary axis's frame that stays fixed
    in the machine as the axes turn looks like the sphere's setup position or
    like another axis's offset, and lands in the second list.

    Parameters
    ----------
    machine : MachineDescription
        The machine.
    positions : dict of str to array_like, shape (N,)
        Axis letter -> positions of the probing cycle [m] (rotary [rad]).
    candidates : list of str, optional
        Location error names to try, in order (default :func:`default_rotary_parameters`,
        tilts before offsets).
    sphere_nominal_m : array_like, shape (3,), optional
        The sphere's nominal position, workpiece frame [m] (default the machine's
        workpiece point).

    Returns
    -------
    tuple of list of str
        (kept, dropped): the names one sphere identifies, and the rest.
    """
    names = candidates if candidates is not None else default_rotary_parameters(machine)
    names = sorted(names, key=lambda n: n[1] in LETTERS) if candidates is None else list(names)
    q = {a: np.asarray(v, float) for a, v in positions.items()}
    point = np.asarray(machine.workpiece if sphere_nominal_m is None else sphere_nominal_m, float)
    kept: list[str] = []
    dropped: list[str] = []
    for name in names:
        trial = kept + [name]
        predicted = _predictor(machine, q, trial, point)
        labels = [*trial, "sphere x", "sphere y", "sphere z"]
        try:
            scaled, _ = _scaled_jacobian(predicted, np.zeros(len(trial) + 3), labels)
        except CalibrationError:
            dropped.append(name)
            continue
        singular = np.linalg.svd(scaled, compute_uv=False)
        (kept if singular[-1] >= RANK_TOLERANCE * singular[0] else dropped).append(name)
    return kept, dropped


def _repeatability(q: dict[str, NDArray], deviations: NDArray) -> float | None:
    keys = np.round(np.column_stack(list(q.values())), 9)
    _, groups = np.unique(keys, axis=0, return_inverse=True)
    groups = groups.ravel()
    squares, dof = 0.0, 0
    for g in np.unique(groups):
        rows = deviations[groups == g]
        if rows.shape[0] > 1:
            squares += float(np.sum((rows - rows.mean(axis=0)) ** 2))
            dof += 3 * (rows.shape[0] - 1)
    return float(np.sqrt(squares / dof)) if dof else None


def volumetric_error(machine: MachineDescription, location_errors: dict[str, float],
                     positions: dict[str, ArrayLike]) -> NDArray[np.float64]:
    """(N, 3) TCP error that ``location_errors`` alone cause at ``positions`` [m].

    Parameters
    ----------
    machine : MachineDescription
        The machine (its own error description is not used).
    location_errors : dict of str to float
        ISO 230-7 location error name -> value [m] or [rad].
    positions : dict of str to array_like, shape (N,)
        Axis letter -> positions [m] (rotary [rad]); the stroke is not checked.

    Returns
    -------
    ndarray, shape (N, 3)
        TCP position error [m], bed frame.
    """
    model = KinematicModel(machine)
    q = {a: np.asarray(v, float) for a, v in positions.items()}
    overrides = ErrorOverrides(location=dict(location_errors), use_description=False)
    return model.tcp_error(q, overrides=overrides, check_stroke=False)["position"]
