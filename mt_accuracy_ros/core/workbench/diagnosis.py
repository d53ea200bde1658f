"""Model versus measurement: where the model fails and which physical effect is missing.

Given reference measurements of the TCP error (laser, probe, ball bar, ...)
and an :class:`~..compensation.error_model.ErrorModel`, the residual
r = measured - model (each component's mean removed: an instrument measures
from its own zero) is

1. **localised** (:mod:`.localisation`): the share of its variance each
   variable explains (axis positions, feeds, directions, accelerations,
   temperatures and their differences, time, spindle speed), cross-validated,
   and the strongest periodic component along each axis - in numbers even when
   no effect of the catalogue fits;
2. **explained** (:mod:`.selection`): every effect of the open catalogue
   (:mod:`..effects`: geometric, rotary, thermal, motion, cross-axis, the
   user's own) is scored by time-blocked cross-validation with its
   hyperparameters chosen inside the fold; the best is tested on the
   readings the fits did not see and added only if it passes; the search
   repeats for several missing effects at once.

The verdict is honest: when nothing passes and the residual stands clearly
above the instrument's noise (a chi-square test on the readings), it says
"an unexplained systematic residual of ... remains" with where it lives,
never "nothing beyond noise".
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..compensation.error_model import ErrorModel
# The scale pair's yaw effects live with the scales; re-exported for their former users.
from ..scales.yaw_diagnosis import (YAW_EXPLANATIONS, YawObservations,  # noqa: F401
                                    yaw_corrections, yaw_regressors)
from .statistics import DEFAULT_DIRECTION_UNCERTAINTY_RAD, stated_uncertainty
from ..errors import InsufficientDataError, ParameterError
from ..effects import Context, EffectFamily, families as catalogue_families, is_catalogue_entry
from ..effects.base import target_groups
from ..effects.user import UserExpression
from .context_memo import ContextMemo
from .localisation import Localisation, LocalisationMemo, localise
from .distributions import chi2_sf
from .selection import Selector, Term
from .selection.folds import Folds
from .selection.significance import Evidence, PassRule
from .separability import alternatives, sentence
from ..effects.variables import Variables, run_starts_of

AXES3 = "XYZ"

#: Built-in model effects and the catalogue candidates they already cover.
_COVERED = {
    "structural_thermal_drift": lambda p: [f"structural_thermal_drift:{p['sensor']}"],
    "spindle_thermal_growth": lambda p: [f"structural_thermal_drift:{p['sensor']}"],
    "position_dependent_thermal": lambda p: [f"position_dependent_thermal:{p['axis']}:"
                                             f"{p['sensor']}"],
    "squareness": lambda p: [f"squareness:{n}" for n in p.get("errors_rad", {})] or
    ["squareness:EC0Y", "squareness:EB0Z", "squareness:EA0Z"],
    "abbe_offset": lambda p: ["abbe_offset:tool"],
    "reversal": lambda p: [f"reversal:{a}" for a in p.get("axes", [])],
    "servo_lag": lambda p: [f"servo_lag:{a}" for a in p.get("axes", [])],
}


@dataclass
class Observations:
    """N reference readings in time order.

    positions / velocities / accelerations / directions: axis -> (N,) [m, m/s, m/s^2, +-1];
    measured_m (N, 3) [m] with measured_mask (N, 3); time_s (N,) [s];
    temperatures: sensor -> (N,) [degC]; spindle_speed_rad_s (N,) or None;
    uncertainty_m: the instrument's k = 2 uncertainty [m].

    An instrument that also measures the tool's direction (a two-sphere R-test)
    gives ``measured_orientation_rad`` (N, 3) [rad]: the rotation of the tool
    relative to the workpiece in the bed frame, as seen across the tool axis
    (the part about the axis is invisible to it), with ``orientation_measured``
    (N,) and its own k = 2 uncertainty ``orientation_uncertainty_rad``. The
    workbench then judges every effect on both (:class:`~..effects.base.Context`).

    ``work_point`` ((3,) or (N, 3) [m], in the workpiece frame): the target of an
    instrument fixed on the workpiece side (an R-test's or a probed sphere, a
    retroreflector); the model is evaluated there. None (the default): the readings
    are taken at the machining point, where the tool is (Kidani eqs. 2.9-2.10);
    :func:`work_points` builds it from per-reading targets.

    ``run_of_row`` (N,): a record made of many **runs** (a log of many days, each run
    contiguous): every lag restarts at its run's first reading and time counts from
    it. ``zeroed_runs``: the instrument was zeroed at each run's first reading, so
    every run has its own zero - measured and model are then both referred to it
    (:meth:`zeroed`); otherwise the readings are absolute across runs.

    Parameters
    ----------
    positions : dict of str to ndarray, shape (N,)
        Axis letter -> command position [m] (rotary [rad]).
    measured_m : ndarray, shape (N, 3)
        The measured TCP position error [m] (x, y, z).
    measured_mask : ndarray of bool, shape (N, 3)
        Which components each reading measured.
    time_s : ndarray, shape (N,)
        Reading times [s], non-decreasing.
    velocities : dict of str to ndarray, shape (N,), optional
        Axis letter -> command velocity [m/s] (rotary [rad/s]).
    temperatures : dict of str to ndarray, shape (N,), optional
        Sensor name -> temperature [degC].
    uncertainty_m : float, optional
        The instrument's expanded position uncertainty (k = 2) [m].
    predicted_m : ndarray, shape (N, 3), optional
        Position predictions made elsewhere [m], used instead of the model's.
    predicted_orientation : ndarray, shape (N, 3), optional
        Tool-direction predictions made elsewhere [rad], used instead of the model's.
    directions : dict of str to ndarray, shape (N,), optional
        Axis letter -> direction of the last motion (+1 / -1, 0 unknown).
    accelerations : dict of str to ndarray, shape (N,), optional
        Axis letter -> command acceleration [m/s^2] (rotary [rad/s^2]).
    spindle_speed_rad_s : ndarray, shape (N,), optional
        Spindle speed [rad/s].
    measured_orientation_rad : ndarray, shape (N, 3), optional
        The measured tool-direction error [rad] (rotation about x, y, z, bed frame).
    orientation_measured : ndarray of bool, shape (N,), optional
        Which readings measured the tool's direction.
    orientation_uncertainty_rad : float, optional
        The instrument's expanded tool-direction uncertainty (k = 2) [rad].
    work_point : ndarray, shape (3,) or (N, 3), optional
        The instrument's target [m], workpiece frame; None: the machining point.
    run_of_row : ndarray of int, shape (N,), optional
        Each reading's run (contiguous runs); None: one run.
    zeroed_runs : bool, optional
        The instrument was zeroed at each run's first reading.
    """

    positions: dict[str, NDArray[np.float64]]
    measured_m: NDArray[np.float64]
    measured_mask: NDArray[np.bool_]
    time_s: NDArray[np.float64]
    velocities: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    temperatures: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    uncertainty_m: float = 1e-6
    #: Optional: (N, 3) position and orientation predictions made elsewhere (e.g. with
    #: the profiles that were live at each reading); used instead of model.tcp_error.
    predicted_m: NDArray[np.float64] | None = None
    predicted_orientation: NDArray[np.float64] | None = None
    directions: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    accelerations: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    spindle_speed_rad_s: NDArray[np.float64] | None = None
    measured_orientation_rad: NDArray[np.float64] | None = None
    orientation_measured: NDArray[np.bool_] | None = None
    orientation_uncertainty_rad: float = 2e-6
    work_point: NDArray[np.float64] | None = None
    run_of_row: NDArray[np.int64] | None = None
    zeroed_runs: bool = False

    @property
    def run_starts(self) -> NDArray[np.intp] | None:
        """(R,) first row of each run (None: one run)."""
        if self.run_of_row is None:
            return None
        starts = run_starts_of(self.run_of_row)
        return starts if starts.size > 1 or self.zeroed_runs else None

    @property
    def zero_rows(self) -> NDArray[np.intp] | None:
        """(N,) the row each reading's instrument zero was taken at (its run's first), or
        None when the readings are absolute."""
        if not self.zeroed_runs or self.run_of_row is None:
            return None
        starts = run_starts_of(self.run_of_row)
        return starts[np.searchsorted(starts, np.arange(self.n), side="right") - 1]

    def zeroed(self, values: NDArray[np.float64]) -> NDArray[np.float64]:
        """``values`` (N, ...) referred to each run's zero row (unchanged when absolute).

        Parameters
        ----------
        values : ndarray, shape (N, ...)
            A quantity at the N readings, any unit.

        Returns
        -------
        ndarray, shape (N, ...)
            ``values`` minus its value at each reading's zero row, same unit (``values``
            itself when the readings are absolute).
        """
        zero = self.zero_rows
        return values if zero is None else values - values[zero]

    def subset(self, rows) -> "Observations":
        """The readings ``rows`` alone, every per-reading field picked alike.

        Parameters
        ----------
        rows : slice, ndarray of int or ndarray of bool, shape (N,)
            The readings kept, as numpy indexes them (keep the time order).

        Returns
        -------
        Observations
            The picked readings (units unchanged); a single work point and the
            uncertainties are shared.
        """
        pick = lambda d: {k: np.asarray(v)[rows] for k, v in d.items()}  # noqa: E731
        return Observations(pick(self.positions), self.measured_m[rows], self.measured_mask[rows],
                            self.time_s[rows], pick(self.velocities), pick(self.temperatures),
                            self.uncertainty_m,
                            None if self.predicted_m is None else self.predicted_m[rows],
                            None if self.predicted_orientation is None
                            else self.predicted_orientation[rows], pick(self.directions),
                            pick(self.accelerations),
                            None if self.spindle_speed_rad_s is None
                            else self.spindle_speed_rad_s[rows],
                            None if self.measured_orientation_rad is None
                            else self.measured_orientation_rad[rows],
                            None if self.orientation_measured is None
                            else self.orientation_measured[rows],
                            self.orientation_uncertainty_rad,
                            self.work_point if self.work_point is None or
                            np.ndim(self.work_point) == 1
                            else np.asarray(self.work_point)[rows],
                            None if self.run_of_row is None else self.run_of_row[rows],
                            self.zeroed_runs)

    def set_directions(self, errors: list, uncertainties: list[float]) -> str:
        """Take the tool direction of the readings that measured it: ``errors`` (N,) of a
        (3,) error [rad] or None (not measured), ``uncertainties`` (N,) k = 2 [rad]
        (those of unmeasured readings are ignored). Nothing measured: nothing is set.
        Returns "" or the sentence saying the documented default uncertainty was taken.

        Parameters
        ----------
        errors : list, length N
            Per reading, the measured tool-direction error, a (3,) [rad] (about x, y, z),
            or None where not measured.
        uncertainties : list of float, length N
            Per reading, its expanded uncertainty (k = 2) [rad]; all zero for none stated
            (:data:`.statistics.DEFAULT_DIRECTION_UNCERTAINTY_RAD` is then taken).

        Returns
        -------
        str
            "" or the sentence saying the default uncertainty was taken.
        """
        measured = np.array([e is not None for e in errors], dtype=bool)
        if not measured.any():
            return ""
        self.measured_orientation_rad = np.array([e if e is not None else (0.0, 0.0, 0.0)
                                                  for e in errors], dtype=np.float64)
        self.orientation_measured = measured
        self.orientation_uncertainty_rad, note = stated_uncertainty(
            np.asarray(uncertainties, dtype=np.float64)[measured],
            DEFAULT_DIRECTION_UNCERTAINTY_RAD, "tool direction", "rad")
        return note

    @property
    def measures_direction(self) -> bool:
        """Did the instrument measure the tool's direction at any reading?"""
        return self.measured_orientation_rad is not None and \
            self.orientation_measured is not None and bool(np.any(self.orientation_measured))

    @property
    def orientation_lever_m(self) -> float:
        """[m/rad] that gives a direction reading the noise of a position reading: the
        position's k = 2 uncertainty over the direction's."""
        if not (np.isfinite(self.orientation_uncertainty_rad) and
                0.0 < self.orientation_uncertainty_rad < 0.1):
            raise ParameterError(f"tool-direction uncertainty {self.orientation_uncertainty_rad!r}"
                                 " rad: must be finite, positive and below 0.1 rad")
        return float(self.uncertainty_m / self.orientation_uncertainty_rad)

    @property
    def n(self) -> int:
        return self.measured_m.shape[0]

    def variables(self, reference_temperatures_c: dict[str, float] | None = None) -> Variables:
        """The readings' machine state as the effects read it.

        Parameters
        ----------
        reference_temperatures_c : dict of str to float, optional
            Sensor name -> reference of its rise [degC] (default: its first reading).

        Returns
        -------
        Variables
            Positions, velocities, accelerations, directions, temperatures, time and
            spindle speed of the N readings (their units as here), with the runs' starts.
        """
        return Variables(dict(self.positions), self.time_s, dict(self.velocities),
                         dict(self.accelerations), dict(self.directions),
                         dict(self.temperatures), dict(reference_temperatures_c or {}),
                         self.spindle_speed_rad_s, run_starts=self.run_starts)

    def model_inputs(self) -> dict:
        """Keyword arguments of :meth:`ErrorModel.tcp_error` beyond positions."""
        inputs = {"temperatures": self.temperatures, "velocities": self.velocities or None,
                  "directions": self.directions or None, "time_s": self.time_s,
                  "accelerations": self.accelerations or None,
                  "spindle_speed_rad_s": self.spindle_speed_rad_s,
                  "located_readings": True,      # an instrument's, located at the set-up
                  "direction_measured": self.measures_direction}
        if self.work_point is not None:
            inputs["work_point"] = self.work_point
        if self.run_starts is not None:
            inputs["run_starts"] = self.run_starts
        return inputs


def work_points(kinematics, positions: dict[str, NDArray[np.float64]], targets: list
                ) -> NDArray[np.float64] | None:
    """(N, 3) [m] the point each reading was taken at, workpiece frame: its instrument's
    fixed target, or - for a reading without one (None) - the machining point. None when
    no reading names a target (every reading at the machining point).

    Parameters
    ----------
    kinematics : KinematicModel
        The machine's kinematic model (its ``machining_point`` gives the point of a reading
        without a target).
    positions : dict of str to ndarray, shape (N,)
        Axis letter -> command position [m] (rotary [rad]), every axis of the machine.
    targets : list, length N
        Per reading, its instrument's target, a (3,) [m] in the workpiece frame, or None.

    Returns
    -------
    ndarray, shape (N, 3) or (3,), or None
        The points [m], workpiece frame: (3,) when every reading names the same target;
        None when none names one.
    """
    if all(t is None for t in targets):
        return None
    if all(t is not None and np.array_equal(t, targets[0]) for t in targets):
        return np.asarray(targets[0], dtype=np.float64)     # one instrument, one target
    points = kinematics.machining_point(positions)
    for i, target in enumerate(targets):
        if target is not None:
            points[i] = target
    return points


@dataclass
class Candidate:
    """A candidate effect's fit to the residual."""

    effect: str                       # family name, e.g. "positioning_periodic"
    parameters: dict
    cv_rmse_after: float
    error_reduction: float
    significant: bool
    explanation: str
    variant: str = ""
    #: Standard (k = 1) uncertainty of each fitted parameter [unit of the parameter].
    parameter_uncertainties: dict = field(default_factory=dict)
    setting: dict = field(default_factory=dict)
    confidence: float = 0.0           # 1 - max-T-adjusted p-value of the held-out test
    share_of_excess: float = 0.0      # of the residual above noise it removes (held out)
    group: str = ""
    declaration: dict | None = None   # a user effect's declaration
    #: Why physics refuses this fit ("" if it does not): never named, never added.
    refusal: str = ""
    #: The held-out block test's p-value, adjusted for every candidate tried (max-T).
    adjusted_p: float = 1.0
    #: Candidates the readings cannot part it from, each with its own fit of what this
    #: one explains: [{"name", "parameters", "reason"}] (:mod:`.separability`).
    inseparable: list = field(default_factory=list)

    @property
    def name(self) -> str:
        return f"{self.effect}:{self.variant}" if self.variant else self.effect

    def as_dict(self) -> dict:
        """SI values (``parameters``, ``parameter_uncertainties`` k = 1, ``setting``) and
        their engineering reading (``display``: value ± U (k = 2) in um/K, urad, ...)."""
        from ..effects.display import display_parameters, display_setting

        return {"effect": self.effect, "variant": self.variant, "name": self.name,
                "group": self.group, "setting": self.setting,
                "setting_display": display_setting(self.setting),
                # A fit physics refuses is said in words (``refusal``), not read as values.
                "display": {name: "not reported: physics refuses the fit"
                            for name in self.parameters} if self.refusal else
                display_parameters(self.effect, self.variant, self.parameters,
                                   self.parameter_uncertainties),
                "cv_rmse_after": self.cv_rmse_after, "error_reduction": self.error_reduction,
                "significant": self.significant, "confidence": self.confidence,
                "share_of_excess": self.share_of_excess, "explanation": self.explanation,
                "parameters": self.parameters,
                "parameter_uncertainties": self.parameter_uncertainties,
                "refusal": self.refusal, "adjusted_p": self.adjusted_p,
                # Only where the readings cannot part it from another candidate.
                **({"inseparable": self.inseparable} if self.inseparable else {})}


@dataclass
class Diagnosis:
    baseline_rmse: float            # in-sample residual RMSE of the current model [m]
    baseline_cv_rmse: float         # CV RMSE of the residual with only a constant offset
    max_abs_error: float
    fraction_outside_band: float
    ranking: list[Candidate]        # first step, best first
    selected: list[Candidate] = field(default_factory=list)   # added in order, joint fit
    localisation: Localisation | None = None        # of the residual as it is
    #: Per component: RMS of what the selected effects leave above the noise [m].
    unexplained_m: dict[str, float] = field(default_factory=dict)
    residual_above_noise: bool = False
    noise_sigma: float = 0.0
    final_cv_rmse: float = 0.0
    #: Where what the selected effects leave lives (the same as ``localisation`` when
    #: nothing was selected).
    localisation_after: Localisation | None = None
    #: When the instrument measured the tool's direction: the direction residual's RMS
    #: [rad] as the model stands, and per component (about x, y, z) what the selected
    #: effects leave above the instrument's noise [rad].
    direction_rmse_rad: float | None = None
    unexplained_direction_rad: dict[str, float] = field(default_factory=dict)
    #: The model's fitted effects refitted on the same readings (a
    #: :class:`~.refit.Refit`, set by the monitor's check; None if not made).
    refit: object | None = None
    #: What the monitor's check cost, set by its search worker: wall and CPU [s].
    search_wall_s: float = float("nan")
    search_cpu_s: float = float("nan")
    #: Effects the selection named and took out again once a later one explained them:
    #: [{"name", "by", "sentence"}] in the order dropped.
    dropped: list[dict] = field(default_factory=list)

    @property
    def found(self) -> Candidate | None:
        """The first effect named (or, for rankings made without a selection - the yaw
        workbench - the first significant candidate)."""
        if self.selected:
            return self.selected[0]
        return next((c for c in self.ranking if c.significant), None)

    def verdict(self) -> str:
        """The honest closing sentence: what remains unexplained, if anything."""
        systematic = {c: v for c, v in self.unexplained_m.items() if v > 0}
        turned = {c: v for c, v in self.unexplained_direction_rad.items() if v > 0}
        if not (systematic or turned) or not self.residual_above_noise:
            return ""
        parts = []
        if systematic:
            worst = max(systematic, key=systematic.get)
            where = self.localisation_after.sentence() if self.localisation_after else ""
            parts.append(f"an unexplained systematic residual of {systematic[worst] * 1e6:.1f} "
                         f"um on {worst} remains{'; ' + where if where else ''}")
        if turned:
            worst = max(turned, key=turned.get)
            parts.append(f"an unexplained tool-direction error of {turned[worst] * 1e6:.1f} "
                         f"urad about {worst} remains")
        return "; ".join(parts)

    def text(self) -> str:
        head = f"residual RMSE {self.baseline_rmse * 1e6:.2f} um"
        if self.direction_rmse_rad is not None:
            head += f" (tool direction {self.direction_rmse_rad * 1e6:.1f} urad)"
        if self.selected:
            names = "; ".join(f"{c.name} ({c.explanation}; confidence {c.confidence:.0%})"
                              for c in self.selected)
            text = (f"{head}; most likely missing: {names}; adding "
                    f"{'them' if len(self.selected) > 1 else 'it'} would leave "
                    f"{self.final_cv_rmse * 1e6:.2f} um (cross-validated)")
        elif self.residual_above_noise:
            refused = [c for c in self.ranking if c.refusal]
            closest = min(refused, key=lambda c: c.cv_rmse_after) if refused else None
            text = f"{head}; no catalogue effect explains it" + (
                f" (the closest fit, {closest.name}, is refused by physics: {closest.refusal})"
                if closest is not None and closest.cv_rmse_after <=
                min(c.cv_rmse_after for c in self.ranking) else "")
        else:
            where = self.localisation.sentence() if self.localisation else ""
            return (f"{head}; within the instrument's noise ({self.noise_sigma * 1e6:.2f} um): "
                    f"nothing missing{' (weakly: ' + where + ')' if where else ''}")
        verdict = self.verdict()
        return f"{text}; {verdict}" if verdict else text


def residuals(model: ErrorModel, obs: Observations, *, absolute: bool = False
              ) -> NDArray[np.float64]:
    """measured - model (N, 3), each measured component's mean removed (per target when
    several spheres were located one by one: :func:`~..effects.base.target_groups`).

    Reference instruments measure from a zero reference of their own, so a
    constant offset per component carries no information about the model -
    unless the instrument was zeroed at the model's datum (``absolute``: the
    model's error is referred to the same pose, and the mean is kept).

    Parameters
    ----------
    model : ErrorModel
        The model (its ``tcp_error`` is evaluated unless ``obs.predicted_m`` is set).
    obs : Observations
        The N readings.
    absolute : bool, optional
        The instrument was zeroed at the model's datum: the means are kept.

    Returns
    -------
    ndarray, shape (N, 3)
        measured - model [m], zero where a component was not measured.
    """
    predicted = obs.predicted_m if obs.predicted_m is not None else \
        model.tcp_error(obs.positions, **obs.model_inputs(), fresh=True)[0]
    residual = obs.measured_m - obs.zeroed(predicted)
    # Several spheres located one by one: each its own zero (Context.target_groups).
    groups = target_groups(obs.work_point, obs.n)
    groups = np.zeros(obs.n, dtype=np.intp) if groups is None else groups
    for c in range(3):
        for group in np.unique(groups):
            measured = obs.measured_mask[:, c] & (groups == group)
            # Zeroed runs know their zero (each run's first reading): no mean to take out.
            if measured.any() and not absolute and not obs.zeroed_runs:
                residual[measured, c] -= residual[measured, c].mean()
    residual[~obs.measured_mask] = 0.0
    return residual


def user_effects_to_fit(model: ErrorModel) -> dict[str, dict]:
    """Declared user effects of the model that have no fitted values yet.

    Parameters
    ----------
    model : ErrorModel
        The model whose effects are read.

    Returns
    -------
    dict of str to dict
        Effect name -> its declaration (``expression``, ...), in the model's order.
    """
    return {name: p for name, p in model.effects.items()
            if isinstance(p, dict) and "expression" in p and "values" not in p}


def candidate_terms(model: ErrorModel, ctx: Context,
                    family_list: list[EffectFamily] | None = None) -> list[Term]:
    """Every catalogue term not already in the model.

    Parameters
    ----------
    model : ErrorModel
        The model; its built-in and fitted effects cover the terms they hold.
    ctx : Context
        The readings' context (it sets each family's variants and settings).
    family_list : list of EffectFamily, optional
        The families to draw from; None: the whole catalogue with the model's user
        effects yet to fit, log-only families left out. ``geometric`` is never drawn
        from.

    Returns
    -------
    list of Term
        Each variant with its settings (a variant with none is left out); a user effect
        is kept even when the model holds it.
    """
    covered = set(model.effects)
    for name, parameters in model.effects.items():
        if name in _COVERED and not is_catalogue_entry(parameters):
            covered.update(_COVERED[name](parameters))
    terms = []
    for family in family_list if family_list is not None else \
            catalogue_families(user_effects_to_fit(model)):
        if family.name == "geometric" or (family.log_only and family_list is None):
            continue
        for variant in family.variants(ctx):
            term = Term(family, variant, family.settings(ctx, variant))
            if not term.settings:
                continue  # e.g. a lag the record is too short to support
            if isinstance(family, UserExpression) or term.name not in covered:
                terms.append(term)
    return terms


def _check_user_terms(terms: list[Term], selector: Selector, model: ErrorModel,
                      ctx: Context) -> None:
    """A user effect whose design adds nothing to the model's own is refused, named."""
    included = [selector.offsets]
    names = ["a constant offset"]
    for name, entry in model.effects.items():
        if is_catalogue_entry(entry) and "family" in entry:
            from ..effects import family_named

            family = family_named(entry["family"])
            design = ctx.measured_design(family, entry.get("variant", ""),
                                         entry.get("setting") or {})
            included.append(design.reshape(-1, design.shape[2])[selector.rows])
            names.append(name)
    for term in terms:
        if not isinstance(term.family, UserExpression):
            continue
        columns = selector.design_rows(term, {})
        scale = np.linalg.norm(columns, axis=0)
        if not np.any(scale > 0):
            raise ParameterError(f"user effect {term.variant!r}: zero on every reading "
                                 "(no effect on these data)")
        def explained(base) -> bool:
            projection, *_ = np.linalg.lstsq(base, columns, rcond=None)
            rest = np.linalg.norm(columns - base @ projection, axis=0)
            return bool(np.all(rest <= 1e-6 * np.maximum(scale, 1e-300)))

        # Offsets are always in the fit: each effect is judged together with them.
        culprits = [names[0]] if explained(included[0]) else \
            [name for base, name in zip(included[1:], names[1:])
             if explained(np.column_stack([included[0], base]))]
        if not culprits and len(included) > 2 and explained(np.column_stack(included)):
            culprits = [", ".join(names[1:]) + " together"]
        if culprits:
            raise ParameterError(f"user effect {term.variant!r}: its design is collinear "
                                 f"with {culprits[0]} already in the model (it could not be "
                                 "told apart)")


def _candidate(scored, explanation_of, significant: bool) -> Candidate:
    term = scored.term
    names = scored.parameter_names or term.family.parameter_names(term.variant, scored.setting)
    values = scored.coefficients if scored.coefficients is not None else np.full(len(names),
                                                                                  np.nan)
    errors = scored.standard_errors if scored.standard_errors is not None else \
        np.full(len(names), np.nan)
    declaration = term.family.declaration if isinstance(term.family, UserExpression) else None
    return Candidate(term.family.name, dict(zip(names, map(float, values))), scored.cv_rmse,
                     scored.reduction, significant, explanation_of(scored), term.variant,
                     dict(zip(names, map(float, errors))), dict(scored.setting),
                     float(1.0 - min(scored.adjusted_p, scored.coefficient_p))
                     if significant else 0.0,
                     float(scored.share_of_excess), term.family.group, declaration,
                     scored.refusal, float(scored.adjusted_p))


def diagnose(model: ErrorModel, obs: Observations, *, min_reduction: float = 0.05,
             folds: int = 5, max_effects: int = 4, alpha: float = 0.05,
             min_share: float = 0.25, family_list: list[EffectFamily] | None = None,
             localise_residual: bool = True, forward: bool = False,
             blocks: NDArray[np.intp] | None = None, pair_lookahead: bool = True,
             localisations: LocalisationMemo | None = None,
             contexts: ContextMemo | None = None,
             residual: NDArray[np.float64] | None = None) -> Diagnosis:
    """Localise the residual and select the missing effects (see the module docstring).

    ``forward``: validate as the model will be used on a log - each block predicted by
    a fit on the earlier blocks only (:class:`~.selection.Selector`); ``blocks`` (N,)
    gives those blocks (whole runs of a log of many runs) instead of equal cuts.
    ``pair_lookahead``: when no single effect passes, try two at once (two effects
    hiding each other show at the start; a re-diagnosis of the same readings after the
    named effects were added judges what they leave one effect at a time).
    ``localisations``: a memo of ``obs``' localisations, for a caller that diagnoses the
    same readings again (a residual seen before is not localised again); ``contexts``:
    a memo of their context, for the same caller (the candidates' designs are not made
    again); ``residual``: :func:`residuals` of ``model`` at ``obs``, if the caller has it
    (it is not changed).

    Parameters
    ----------
    model : ErrorModel
        The model whose residual is diagnosed.
    obs : Observations
        The N reference readings, in time order.
    min_reduction : float, optional
        Least fraction of the held-out RMSE an effect must cut, dimensionless.
    folds : int, optional
        K of the time-blocked cross-validation (ignored when ``blocks`` is given).
    max_effects : int, optional
        The most effects named.
    alpha : float, optional
        Level of the held-out test (p-values adjusted for every candidate tried).
    min_share : float, optional
        Least fraction of the error above the noise an effect must remove.
    family_list : list of EffectFamily, optional
        The families to draw from (:func:`candidate_terms`); None: the catalogue.
    localise_residual : bool, optional
        Localise the residual before and after (:mod:`.localisation`).
    forward : bool, optional
        See above.
    blocks : ndarray of int, shape (N,), optional
        See above: non-decreasing 0, 1, ... with at least two blocks.
    pair_lookahead : bool, optional
        See above.
    localisations : LocalisationMemo, optional
        See above.
    contexts : ContextMemo, optional
        See above.
    residual : ndarray, shape (N, 3), optional
        See above [m].

    Returns
    -------
    Diagnosis
        The residual's figures [m] (and tool direction [rad]), the first step's
        ranking, the effects named (SI parameters), where the residual lives before and
        after, what remains above the noise and the effects dropped again.

    Raises
    ------
    InsufficientDataError
        Fewer than ``4 * folds`` readings (without ``blocks``).
    ParameterError
        A user effect zero on every reading or collinear with the model's own effects;
        a tool-direction uncertainty not finite, positive and below 0.1 rad.
    ValueError
        ``blocks`` not of shape (N,), non-decreasing 0, 1, ... with at least two.
    """
    if blocks is None and obs.n < 4 * folds:
        raise InsufficientDataError(f"{obs.n} reference readings; need >= {4 * folds}")
    frame = residual_frame(model, obs, contexts=contexts, residual=residual)
    ctx, residual, mask = frame.ctx, frame.residual, frame.mask
    position_residual, lever, directions = frame.position_residual, frame.lever, \
        obs.measures_direction
    noise_sigma = obs.uncertainty_m / 2.0   # the instrument's k = 2 uncertainty
    variables = ctx.variables
    selector = Selector(ctx, residual, mask, noise_sigma, folds=folds, alpha=alpha,
                        min_reduction=min_reduction, min_share=min_share, forward=forward,
                        blocks=blocks)
    terms = candidate_terms(model, ctx, family_list)
    _check_user_terms(terms, selector, model, ctx)
    steps = selector.run(terms, max_terms=max_effects, beam=3 if pair_lookahead else 0)
    first = steps[0] if steps else None

    def explain(scored):
        return scored.term.family.explanation(scored.term.variant, scored.setting)

    ranking = [_candidate(s, explain, s.significant) for s in (first.ranking if first else [])]
    selected = [_candidate(s.added, explain, True) for s in steps if s.added is not None]
    for candidate, step in zip(selected, [s for s in steps if s.added is not None]):
        candidate.cv_rmse_after = step.added.cv_rmse
    say_inseparable(selector, [s.added for s in steps if s.added is not None], selected, terms)
    if selector.simpler_start and selected:
        # Beside the term begun from, or - when a later one explained it and took its
        # place - beside the first named.
        began = [c for c in selected if c.name == selector.simpler_start.started_from]
        (began or selected)[0].explanation += "; " + selector.simpler_start.sentence()
    position_mask = obs.measured_mask
    in_sample = float(np.sqrt(np.mean(position_residual[position_mask] ** 2))) \
        if position_mask.any() else 0.0
    remaining = selector.remaining_residual()
    final_cv = steps[-1].base_cv_rmse if steps and steps[-1].added is None else \
        (steps[-1].added.cv_rmse if steps else in_sample)
    unexplained, unexplained_direction, above = {}, {}, False
    for c, component in enumerate(selector.components):
        rows = mask[:, c]
        if rows.sum() < 2:
            continue
        r = remaining[rows, c]
        mean_square = float(np.mean(r ** 2))
        systematic = float(np.sqrt(max(0.0, mean_square - noise_sigma ** 2)))
        if c < 3:
            unexplained[component] = systematic
        else:
            unexplained_direction["xyz"[c - 3]] = systematic / lever
        # Chi-square: could these residuals be the instrument's noise alone?
        if noise_sigma > 0 and chi2_sf(mean_square * r.size / noise_sigma ** 2, r.size - 1) < \
                0.001 and systematic > 0.5 * noise_sigma:
            above = True
    localisation = localisation_after = None
    if localise_residual:
        strokes = {a: model.machine.axes[a].stroke for a in model.machine.axis_order}
        where = localise if localisations is None else localisations.localise
        localisation = where(position_residual, position_mask, variables,
                             ctx.structure_sensors(), noise_sigma, strokes, folds,
                             ctx.zero_rows)
        localisation_after = where(remaining[:, :3], position_mask, variables,
                                   ctx.structure_sensors(), noise_sigma, strokes, folds,
                                   ctx.zero_rows) \
            if selected and above else localisation
    direction_rmse = None
    if directions:
        rows = mask[:, 3:]
        direction_rmse = float(np.sqrt(np.sum(residual[:, 3:][rows] ** 2) /
                                       max(1, int(obs.orientation_measured.sum())))) / lever
    dropped = [{"name": gone.term.name, "by": by.term.name,
                "sentence": f"dropped {gone.term.name}: {by.term.name} explains it"}
               for gone, by in selector.dropped]
    dropped += [{"name": gone.term.name, "by": "+".join(kept),
                 "sentence": f"dropped {gone.term.name}: {', '.join(kept)} together leave it "
                             "nothing to carry (every number of it within its uncertainty "
                             "in their joint fit, U, k = 2)"}
                for gone, kept in selector.dropped_jointly]
    dropped += [{"name": gone.term.name, "by": refused,
                 "sentence": f"dropped {gone.term.name}: it was named beside {refused}, which "
                             "physics refuses in their joint fit, and does not pass the "
                             "acceptance rule without it"}
                for gone, refused in selector.dropped_with_refused]
    dropped += [{"name": gone.term.name, "by": earlier,
                 "sentence": f"dropped {gone.term.name}: named after {earlier}, it made "
                             f"physics refuse their joint fit ({earlier}: {reason}); "
                             f"{earlier} without it is accepted"}
                for gone, earlier, reason in selector.dropped_for_refusal]
    return Diagnosis(in_sample, first.base_cv_rmse if first else in_sample,
                     float(np.max(np.abs(position_residual[position_mask]), initial=0.0)),
                     float(np.mean(np.abs(position_residual[position_mask]) > obs.uncertainty_m))
                     if position_mask.any() else 0.0,
                     ranking, selected, localisation, unexplained, above, noise_sigma,
                     float(final_cv), localisation_after, direction_rmse, unexplained_direction,
                     dropped=dropped)


def say_inseparable(selector: Selector, added: list, selected: list[Candidate],
                    terms: list[Term]) -> None:
    """Each named candidate with what the readings cannot part it from (in place: its
    ``inseparable`` list, and a sentence ending its explanation).

    Parameters
    ----------
    selector : Selector
        The selection that named them.
    added : list of Scored
        The selection's named terms, in order (term, setting and coefficients, SI).
    selected : list of Candidate
        The same as candidates, in the same order; changed in place.
    terms : list of Term
        The candidates the selection considered.
    """
    if not added:
        return
    found = alternatives(selector, [(s.term, s.setting) for s in added],
                         [s.coefficients for s in added], terms)
    for candidate, alike in zip(selected, found):
        candidate.inseparable = alike
        if alike:
            candidate.explanation += "; " + sentence(candidate.name, alike)


@dataclass
class ResidualFrame:
    """What the workbench fits: the context of the readings and the residual (N, K).

    K = 3 (the TCP position [m]) or 6 when the instrument measured the tool's direction
    too (its residual across the tool axis, times ``lever`` [m/rad]: every row then has
    the position's noise). ``position_residual`` (N, 3) is the first part alone.

    Attributes
    ----------
    ctx : Context
        The readings' context.
    residual : ndarray, shape (N, K)
        The residual [m] (the direction's part scaled by ``lever``).
    mask : ndarray of bool, shape (N, K)
        Which rows each reading measured.
    position_residual : ndarray, shape (N, 3)
        The position residual [m].
    lever : float or None
        [m/rad] the direction's scale; None when the direction was not measured.
    """

    ctx: Context
    residual: NDArray[np.float64]
    mask: NDArray[np.bool_]
    position_residual: NDArray[np.float64]
    lever: float | None


def residual_frame(model: ErrorModel, obs: Observations, *, absolute: bool = False,
                   contexts: ContextMemo | None = None,
                   residual: NDArray[np.float64] | None = None) -> ResidualFrame:
    """The residual of ``model`` at ``obs`` as the selection sees it (see ResidualFrame;
    ``absolute``: the position's mean kept, see :func:`residuals`; ``contexts``: a memo
    that hands out an earlier look's context of the same readings; ``residual``:
    :func:`residuals` of ``model`` at ``obs``, when the caller has it already).

    Parameters
    ----------
    model : ErrorModel
        The model.
    obs : Observations
        The N readings.
    absolute : bool, optional
        See above.
    contexts : ContextMemo, optional
        See above.
    residual : ndarray, shape (N, 3), optional
        See above [m].

    Returns
    -------
    ResidualFrame
        The context, the residual (N, K) [m] with its mask, the position residual and
        the lever [m/rad].

    Raises
    ------
    ParameterError
        A tool-direction uncertainty not finite, positive and below 0.1 rad.
    """
    if residual is None:
        residual = residuals(model, obs, absolute=absolute)
    mask = obs.measured_mask
    variables = obs.variables(model.reference_temperatures_c)
    orientation = obs.predicted_orientation
    directions = obs.measures_direction
    if orientation is None and ("geometric" in model.effects or model.profiles or directions):
        orientation = model.tcp_error(obs.positions, **obs.model_inputs(), fresh=True)[1]
    lever = obs.orientation_lever_m if directions else None
    make = Context if contexts is None else contexts.context
    ctx = make(model.machine, variables, model._kinematics, orientation,
               orientation_lever_m=lever, work_point=obs.work_point, zero_rows=obs.zero_rows,
               located_readings=True)   # an instrument's readings, located at the set-up
    position_residual = residual
    if directions:
        # The tool's direction as a second measured quantity, scaled to the position's
        # noise and seen as the instrument sees it (across the tool axis).
        turned = direction_residuals(ctx, obs, orientation)
        residual = np.concatenate([residual, turned], axis=1)
        mask = np.concatenate([mask, np.repeat(obs.orientation_measured[:, None], 3, axis=1)],
                              axis=1)
    return ResidualFrame(ctx, residual, mask, position_residual, lever)


def direction_residuals(ctx: Context, obs: Observations, predicted: NDArray[np.float64]
                        ) -> NDArray[np.float64]:
    """(N, 3) measured - model tool direction across the tool axis, times
    ``ctx.orientation_lever_m`` [m]; zero where the direction was not measured. Absolute,
    unlike the position (:class:`~.selection.Selector`): a constant tilt is the machine's.

    Parameters
    ----------
    ctx : Context
        The readings' context (its tool axis and ``orientation_lever_m`` [m/rad]).
    obs : Observations
        The N readings, with the measured tool direction.
    predicted : ndarray, shape (N, 3)
        The model's tool-direction error [rad] (about x, y, z).

    Returns
    -------
    ndarray, shape (N, 3)
        The difference across the tool axis times the lever [m].
    """
    axis = ctx.tool_axis()
    difference = np.asarray(obs.measured_orientation_rad, dtype=np.float64) - predicted
    across = difference - axis * np.einsum("nc,nc->n", difference, axis)[:, None]
    across[~np.asarray(obs.orientation_measured, dtype=bool)] = 0.0
    return ctx.orientation_lever_m * across


def effect_name_problem(name: str, model: ErrorModel) -> str:
    """Why ``name`` cannot be asked for ("" if it can): a catalogue name
    (``family:variant``), a family (its best variant is meant), a user effect
    declared in the model, or a built-in model effect.

    Parameters
    ----------
    name : str
        The name asked for.
    model : ErrorModel
        The model (its declared user effects).

    Returns
    -------
    str
        "" or the sentence saying what can be asked for.
    """
    from ..compensation.error_model import MODEL_EFFECTS

    if name in MODEL_EFFECTS or (name in model.effects and "expression" in model.effects[name]):
        return ""
    family_names = {f.name for f in catalogue_families()}
    if name.split(":", 1)[0] in family_names:
        return ""
    return (f"unknown effect {name!r}: give a catalogue name (family:variant, e.g. "
            f"positioning_periodic:EXX), a family ({', '.join(sorted(family_names))}), "
            "or a user effect declared in the model")


def pick_candidate(diagnosis: Diagnosis, name: str) -> Candidate | None:
    """The candidate ``name`` asks for: exact catalogue name, else the best of a family
    (jointly fitted selections first).

    Parameters
    ----------
    diagnosis : Diagnosis
        The diagnosis whose selected and ranked candidates are searched.
    name : str
        A catalogue name (``family:variant``), a user effect's name or a family.

    Returns
    -------
    Candidate or None
        The candidate; None when none matches.
    """
    for pool in (diagnosis.selected, diagnosis.ranking):
        for candidate in pool:
            if candidate.name == name or (candidate.declaration is not None and
                                          candidate.variant == name):
                return candidate
    for pool in (diagnosis.selected, diagnosis.ranking):
        for candidate in pool:
            if candidate.effect == name:
                return candidate
    return None


def model_entry(candidate: Candidate) -> dict:
    """The error-model effect entry of a fitted candidate.

    Parameters
    ----------
    candidate : Candidate
        The fitted candidate.

    Returns
    -------
    dict
        A user effect's declaration with its ``values``; else ``family``, ``variant``,
        ``setting``, ``coefficients`` and ``uncertainties`` (k = 1), SI.
    """
    if candidate.declaration is not None:
        return {**candidate.declaration, "values": dict(candidate.parameters)}
    return {"family": candidate.effect, "variant": candidate.variant,
            "setting": dict(candidate.setting), "coefficients": dict(candidate.parameters),
            "uncertainties": dict(candidate.parameter_uncertainties)}


def add_effect(model: ErrorModel, candidate: Candidate, obs: Observations) -> ErrorModel:
    """The next model version holding the fitted candidate (temperatures referenced as in obs).

    Parameters
    ----------
    model : ErrorModel
        The model.
    candidate : Candidate
        The fitted candidate (a user effect is named by its variant, else
        ``family:variant``).
    obs : Observations
        The readings it was fitted on: a sensor the model has no reference temperature
        for is referenced to its first reading [degC].

    Returns
    -------
    ErrorModel
        The new version.
    """
    name = candidate.variant if candidate.declaration is not None else candidate.name
    new = model.with_effect(name, model_entry(candidate))
    for sensor, values in obs.temperatures.items():
        new.reference_temperatures_c.setdefault(sensor, float(np.asarray(values)[0]))
    return new


def add_effects(model: ErrorModel, candidates: list[Candidate], obs: Observations
                ) -> ErrorModel:
    """The model with every candidate of a joint fit added (one version each, in order).

    Parameters
    ----------
    model : ErrorModel
        The model.
    candidates : list of Candidate
        The joint fit's candidates, in order.
    obs : Observations
        The readings they were fitted on (:func:`add_effect`).

    Returns
    -------
    ErrorModel
        The model after the last one is added.
    """
    for candidate in candidates:
        model = add_effect(model, candidate, obs)
    return model


def blocked_cv(x: NDArray, offsets: NDArray, y: NDArray, sample_of_row: NDArray,
               n_samples: int, k: int = 5) -> float:
    """Time-blocked K-fold CV RMSE of y ~ [offsets, x] (contiguous blocks of samples).

    Parameters
    ----------
    x : ndarray, shape (R, p)
        The candidate's columns (p may be 0).
    offsets : ndarray, shape (R, o)
        The free offsets.
    y : ndarray, shape (R,)
        The residual.
    sample_of_row : ndarray of int, shape (R,)
        Each row's reading, non-decreasing (time order).
    n_samples : int
        N, the readings, cut into ``k`` near-equal blocks (:func:`.selection.folds.time_blocks`).
    k : int
        The blocks.

    Returns
    -------
    float
        The RMS of the held-out errors over the blocks that could be fitted (a block is
        left out when its training rows are no more than the columns), in y's unit.

    Raises
    ------
    InsufficientDataError
        No block could be fitted.
    """
    design = np.column_stack([offsets, x]) if x.size else offsets
    folds = Folds.of_readings(n_samples, k, sample_of_row)

    def solve(fold: int) -> NDArray[np.float64] | None:
        train = folds.training_rows(fold)
        if train.sum() <= design.shape[1]:
            return None
        coefficients, *_ = np.linalg.lstsq(design[train], y[train], rcond=None)
        return coefficients

    error, judged = folds.held_out_residuals(design, y, solve)
    squared, count = 0.0, 0
    for a, b in folds.bounds:
        if judged[a:b].any():
            squared += float(error[a:b] @ error[a:b])
            count += b - a
    if count == 0:
        raise InsufficientDataError("too few reference readings for cross-validation")
    return float(np.sqrt(squared / count))


# --------------------------------------------------------------------------- yaw
def diagnose_yaw(included: dict[str, float], obs: YawObservations, *,
                 min_reduction: float = 0.1, folds: int = 5) -> Diagnosis:
    """Rank the scale effects missing from the yaw corrections (same rules as :func:`diagnose`).

    Parameters
    ----------
    included : dict of str to float
        The effects the estimator already corrects -> their values
        (:func:`..scales.yaw_diagnosis.yaw_corrections`).
    obs : YawObservations
        The N yaw readings [rad].
    min_reduction : float, optional
        Least fraction of the held-out RMSE an effect must cut, dimensionless.
    folds : int, optional
        K of the time-blocked cross-validation.

    Returns
    -------
    Diagnosis
        Its ranking only, best first (each candidate's ``value`` in the effect's unit:
        :data:`YAW_EXPLANATIONS`); the figures in [rad], not [m].

    Raises
    ------
    InsufficientDataError
        Fewer than ``2 * folds`` readings, or too few for the cross-validation.
    """
    n = obs.scale_yaw.size
    if n < 2 * folds:
        raise InsufficientDataError(f"{n} yaw readings; need >= {2 * folds}")
    residual = obs.scale_yaw - yaw_corrections(included, obs) - obs.reference_yaw
    residual = residual - residual.mean()
    offsets = np.ones((n, 1))
    rows = np.arange(n)
    baseline_cv = blocked_cv(np.zeros((n, 0)), offsets, residual, rows, n, folds)
    in_sample = float(np.sqrt(np.mean(residual ** 2)))
    noise_sigma = obs.uncertainty_rad / 2.0
    regressors = yaw_regressors(obs)
    ranking = []
    for effect, column in regressors.items():
        if effect in included or not np.any(column):
            continue
        x = column[:, None]
        cv = blocked_cv(x, offsets, residual, rows, n, folds)
        full = np.column_stack([offsets, x])
        coefficients, *_ = np.linalg.lstsq(full, residual, rcond=None)
        sigma2 = float(np.sum((full @ coefficients - residual) ** 2) / max(1, n - 2))
        standard = float(np.sqrt(max(sigma2 * np.linalg.pinv(full.T @ full)[1, 1], 0.0)))
        reduction = 1.0 - cv / baseline_cv if baseline_cv > 0 else 0.0
        significant = bool(reduction >= min_reduction and abs(coefficients[1]) > 3 * standard
                           and in_sample >= 1.5 * noise_sigma)
        ranking.append(Candidate(effect, {"value": float(coefficients[1])}, cv, reduction,
                                 significant, YAW_EXPLANATIONS[effect]))
    ranking.sort(key=lambda c: c.cv_rmse_after)
    return Diagnosis(in_sample, baseline_cv, float(np.max(np.abs(residual))),
                     float(np.mean(np.abs(residual) > obs.uncertainty_rad)), ranking)


def selection_refusal(candidate: Candidate, min_reduction: float, alpha: float = 0.05,
                      min_share: float = 0.25, block_test: bool = True) -> str:
    """Which of the selection's tests refuses ``candidate`` on its own against the current
    model, with its numbers; "" when it passes them all (the one acceptance rule,
    :class:`.selection.significance.PassRule`). ``block_test=False`` leaves the held-out
    block test out (a log's caller judges on whole later runs instead).

    Parameters
    ----------
    candidate : Candidate
        The candidate, with its refusal, adjusted p-value, reduction, share of the
        excess and parameters with their standard uncertainties.
    min_reduction : float
        Least fraction of the held-out RMSE it must cut, >= 0.
    alpha : float, optional
        Level of the held-out test (adjusted p-values).
    min_share : float, optional
        Least fraction of the error above the noise it must remove.
    block_test : bool, optional
        See above.

    Returns
    -------
    str
        "" or the test that refuses it, with its numbers.

    Raises
    ------
    ParameterError
        ``min_reduction`` below 0.
    """
    values = np.array(list(candidate.parameters.values()), dtype=float)
    errors = np.array([candidate.parameter_uncertainties.get(k, np.nan)
                       for k in candidate.parameters], dtype=float)
    evidence = Evidence(candidate.refusal, candidate.adjusted_p, candidate.error_reduction,
                        candidate.share_of_excess, values, errors)
    return PassRule(alpha, min_reduction, min_share, block_test).refusal(evidence)
