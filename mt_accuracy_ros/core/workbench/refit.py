"""The live model's fitted effects refitted on the readings held now.

An effect is fitted once, on the readings the monitor held when it was added:
a column drift named after 33 s of a warming machine was fitted over 2 K of
warming and then drives the compensation at 3 K. As readings accumulate, the
same effects fitted on all of them may predict better. :func:`refit_effects`
refits them jointly - their families, variants and settings (period, order,
time constant) kept: the physics the user accepted stays, only its numbers
move - and says whether that is worth a new model version. It is when

* the refit predicts the readings it did not see better: its time-blocked
  K-fold cross-validated RMSE (each block predicted by a fit on the others,
  the instrument's zero free per component as in :mod:`.selection`) is below
  the live model's by at least ``min_reduction`` (a fraction), and
* not by chance: the share of the error it removes, taken per time block, is
  above zero in a one-sided t-test at ``alpha`` (the selection's block test);
* physics does not refuse the refit (:meth:`.selection.Selector.physics_refusal`).

Whether a coefficient "moved" is said (in combined standard uncertainties of its
old and new value) but not asked: a drift coefficient within its uncertainty of
the truth can still leave a micrometre when extrapolated over a warm-up, and the
held-out error is what the machine feels.

**What the live fit could not tell from zero is taken as zero.** A coefficient
whose value lies within its stated expanded uncertainty (|value| < 2 u) was not
identified by the fit that made it (an error parameter's nominal is zero, as in a
kinematic calibration's identification); a refit takes it as zero and fits the
others without it, unless the readings show it now: the refit with it free predicts
the held-out readings better than the refit without it (the same block test at
``alpha``, by ``min_reduction``). On the few poses of an early record collinear
parameters take up each other's error - the trunnion's refit after 44 s gave the
column drift an x gain of -0.35 um/K and the A line tilts of -1.9 and -1.4 urad that
the truth lacks (each "3 sigma", every one from the others' and the calibration's
error), which the compensation then extrapolated.

Where the instrument measured the tool's direction too, both quantities are
judged together, in the selection's noise-scaled rows (:func:`.diagnosis.residual_frame`).

**Absolute where the instrument was zeroed at the datum.** A model with a
``datum`` says where its reference instrument was zeroed (an R-test touched off
at the work offset, cold). Its readings are then absolute: the model's error
e(q) - e(datum) (at the reference temperatures, at rest) must match them
without a free offset. The refit then fits no offset, and each effect's design
is referred to the datum like the model's error: D(q) - D(datum). A drift
coefficient is then pinned by how far the machine has moved from its datum,
not only by how the error varies during the record - which is what a
compensation at the machine needs (a slope 0.3 um/K off leaves 0.8 um of
absolute error at 2.8 K, a spread of only 0.2 um about the mean).

**The model's own error at the datum.** What the model computes at the datum
comes from its calibrated tables at that one pose, known only to the
calibration's uncertainty (a few tenths of a micrometre for a laser calibration,
:func:`..compensation.datum.calibration_uncertainty_at`). What they miss there is
one constant in every absolute reading, which no effect holds: taken as exact,
a refit over a warm-up puts it into the drift's gain (the VMC's main job: by 2.0
-> 2.4 um/K, bx 1.0 -> 0.64 um/K for a calibration 0.5 um off at the datum), and
the compensation extrapolates it. Where the model states that uncertainty
(``datum_uncertainty_m``), the refit fits the constant with the effects within it
(a Gaussian prior, :class:`DatumCorrection`): free where the warm-up tells it
apart from a gain, the datum's word where it cannot (a warm plateau). A version
made from it carries it (``datum_correction_m``).
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..compensation.error_model import ErrorModel
from ..effects import family_named
from ..errors import InsufficientDataError, ParameterError
from .diagnosis import Candidate, Observations, add_effect, residual_frame
from .selection import (Selector, Term, penalise, penalised_fit, penalty_of,
                        ridge_standard_errors, solve_normal)
from .selection.folds import Folds

#: A coefficient is said to have moved when |new - old| exceeds this many combined
#: standard uncertainties.
MOVED_SIGMA = 2.0
#: One-sided level of the held-out test a refit must pass.
REFIT_ALPHA = 0.01


@dataclass
class ParameterChange:
    """One coefficient, before and after the refit (SI; uncertainties k = 1).

    Attributes
    ----------
    effect : str
        The refitted effect's name in the model (``family:variant`` as the workbench
        adds it).
    parameter : str
        The coefficient's name, as its family names it.
    old, new : float
        Its value in the live model and refitted, SI (the parameter's own unit, e.g.
        [m/K], [rad]).
    old_uncertainty, new_uncertainty : float
        Their standard uncertainties (k = 1), same unit.
    """

    effect: str
    parameter: str
    old: float
    new: float
    old_uncertainty: float
    new_uncertainty: float

    @property
    def z(self) -> float:
        """|new - old| in combined standard uncertainties (inf when both are zero)."""
        combined = float(np.hypot(self.old_uncertainty, self.new_uncertainty))
        difference = abs(self.new - self.old)
        return difference / combined if combined > 0 else (np.inf if difference else 0.0)

    def text(self, family: str, variant: str) -> str:
        """``bx 1.29 -> 1.02 ± 0.12 µm/K`` in the parameter's physical unit (U, k = 2).

        Parameters
        ----------
        family : str
            The effect's family, e.g. ``structural_thermal_drift`` (it sets the unit:
            :func:`..effects.display.parameter_unit`).
        variant : str
            Its variant, e.g. ``EXB``.

        Returns
        -------
        str
            The parameter's name, its old value, and the new one ± U (k = 2), both to the
            new value's decimal place, in the physical unit.
        """
        from ..effects.display import format_measured, parameter_unit

        unit, factor = parameter_unit(family, variant, self.parameter)
        new = format_measured(self.new * factor, 2.0 * self.new_uncertainty * factor, unit)
        decimals = new.split(" ± ")[0]
        places = len(decimals.split(".")[1]) if "." in decimals else 0
        return f"{self.parameter} {self.old * factor:.{places}f} -> {new}"


@dataclass
class DatumCorrection:
    """The model's error at its datum as the readings show it (SI; (3,) each).

    An instrument zeroed at the datum reads e(q) - e(datum). The model refers its error
    to what it computes at the datum: its calibrated tables there, known only to the
    calibration's uncertainty (a laser calibration: a few tenths of a micrometre at one
    pose). What they miss there is one constant in every reading, which no effect
    holds; refitted without it, it goes into whichever effect follows the readings'
    order - a drift's gain over a warm-up, extrapolated beyond it. It is fitted with
    the effects, within the uncertainty the model states (a Gaussian prior): free where
    the readings tell it apart, the datum's word where they cannot (a warm plateau)."""

    old: NDArray[np.float64]
    new: NDArray[np.float64]
    #: Standard uncertainty of ``new`` (k = 1).
    uncertainty: NDArray[np.float64]
    #: The model's stated uncertainty of its error at the datum (k = 2): the prior.
    stated: NDArray[np.float64]

    def text(self) -> str:
        values = ", ".join(f"{v * 1e6:+.2f}" for v in self.new)
        within = ", ".join(f"{v * 1e6:.2f}" for v in self.stated)
        return (f"the model's error at the datum corrected by ({values}) ± "
                f"{2.0 * float(np.max(self.uncertainty)) * 1e6:.2f} um (what its calibration "
                f"missed there, stated to ({within}) um: a constant in every reading)")

    def as_dict(self) -> dict:
        return {"old_m": self.old.tolist(), "new_m": self.new.tolist(),
                "uncertainty_m": self.uncertainty.tolist(),
                "stated_uncertainty_k2_m": self.stated.tolist()}


def _datum_prior(model: ErrorModel, noise_sigma: float
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """The datum correction's prior on the first three columns (the position offsets),
    in the fit's units: (precision (3,), mean (3,)) of the *change* of the readings'
    constant, for a total correction ~ N(0, (U/2)^2) per component, U the model's
    stated uncertainty at the datum; the readings' noise ``noise_sigma`` [m] sets the
    scale. None when the model states none (its error at the datum taken as exact)."""
    if model.datum_uncertainty_m is None:
        return None
    sigma = np.maximum(np.asarray(model.datum_uncertainty_m, dtype=np.float64) / 2.0, 1e-12)
    precision = (max(noise_sigma, 1e-12) / sigma) ** 2
    # The change c of the constant moves the correction to old - c: c ~ N(old, sigma^2).
    return precision, np.asarray(model.datum_correction_m, dtype=np.float64)


def _normal_equations(x: NDArray[np.float64], y: NDArray[np.float64],
                      penalties: list[tuple[int, int, float]], prior=None):
    """(X'X, the penalised X'X with the prior's precision, the right side)."""
    gram = x.T @ x
    penalised = gram
    for start, stop, strength in penalties:
        penalised = penalise(penalised, start, stop, strength)
    right = x.T @ y
    if prior is not None:
        precision, mean = prior
        index = np.arange(precision.size)
        penalised = np.array(penalised, copy=True)
        penalised[index, index] += precision
        right = right.copy()
        right[index] += precision * mean
    return gram, penalised, right


def prior_fit(x: NDArray[np.float64], y: NDArray[np.float64],
              penalties: list[tuple[int, int, float]], prior=None
              ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Least squares y ~ x (minimum norm) with the ridge ``penalties`` (as
    :func:`.selection.penalised_fit`) and a Gaussian ``prior`` ((precision (P,), mean
    (P,)) on the first P columns, in y's units): (coefficients, standard errors - the
    sandwich where anything is penalised).

    Parameters
    ----------
    x : ndarray, shape (R, p)
        The design, y's unit per coefficient's unit.
    y : ndarray, shape (R,)
        The readings (the refit's: [m], directions scaled to metres).
    penalties : list of (start, stop, strength)
        Ridge strengths of column ranges (:func:`.selection.penalise`).
    prior : (ndarray, ndarray) or None, optional
        (precision, mean), each shape (P,), P <= p: precision added to the diagonal of
        X'X, in its unit (y's noise variance over the prior's; dimensionless for the
        refit's offset columns of 0 and 1: so many readings' weight), mean in the first P
        coefficients' unit. None: no prior.

    Returns
    -------
    coefficients : ndarray, shape (p,)
        The fit, each in its column's coefficient unit.
    standard_errors : ndarray, shape (p,)
        Their standard errors (k = 1), same units.
    """
    if prior is None:
        coefficients, standard, _ = penalised_fit(x, y, penalties)
        return coefficients, standard
    gram, penalised, right = _normal_equations(x, y, penalties, prior)
    coefficients = solve_normal(penalised, right)
    residual = y - x @ coefficients
    sigma2 = float(residual @ residual) / max(1, y.size - x.shape[1])
    return coefficients, ridge_standard_errors(gram, penalised, sigma2)


@dataclass
class Refit:
    """The refit of a model's fitted effects and whether it is worth a version."""

    names: list[str]
    candidates: list[Candidate]
    readings: int
    #: Fitted without a free offset: the instrument was zeroed at the model's datum.
    absolute: bool
    #: Time-blocked cross-validated RMSE of the live model's residual (offsets only)
    #: and of the refitted effects, over the rows judged (position [m] and, where
    #: measured, the tool's direction scaled to metres).
    cv_rmse_live: float
    cv_rmse_refit: float
    #: The same split by quantity: position [m] and tool direction [rad] (None if
    #: not measured).
    position_cv_rmse: tuple[float, float]
    direction_cv_rmse: tuple[float, float] | None
    changes: list[ParameterChange] = field(default_factory=list)
    refusal: str = ""
    #: One-sided p-value of the held-out improvement (block t-test).
    p_value: float = 1.0
    min_reduction: float = 0.05
    alpha: float = REFIT_ALPHA
    moved_sigma: float = MOVED_SIGMA
    #: The controller gate's verdict on :meth:`apply` of the model it was fitted to
    #: ("" passes, else the reason; None: not evaluated). The search worker evaluates it
    #: beside the refit, so that the node making it live need not (seconds of CPU on a
    #: five-axis machine, which would hold its executor and delay the next check).
    gate_problem: str | None = None
    #: The datum correction fitted with the effects (absolute refits of a model that
    #: states its uncertainty at the datum), else None.
    datum: DatumCorrection | None = None
    #: Parameters the live fit could not tell from zero, taken as zero (these readings do
    #: not show them, held out), and those the readings now show (refitted too).
    held: list[str] = field(default_factory=list)
    released: list[str] = field(default_factory=list)

    @property
    def reduction(self) -> float:
        """Fraction of the live model's held-out RMSE the refit removes."""
        return 1.0 - self.cv_rmse_refit / self.cv_rmse_live if self.cv_rmse_live > 0 else 0.0

    @property
    def moved(self) -> list[ParameterChange]:
        return [c for c in self.changes if c.z > self.moved_sigma]

    @property
    def recommended(self) -> bool:
        return not self.refusal and self.reduction >= self.min_reduction and \
            self.p_value < self.alpha

    def apply(self, model: ErrorModel, obs: Observations) -> ErrorModel:
        """The next version of ``model``: every refitted effect with its new numbers.

        Parameters
        ----------
        model : ErrorModel
            The model the refit was made of (the live one).
        obs : Observations
            The readings refitted; their temperature sensors absent from the model's
            reference temperatures are referenced to the first reading [degC]
            (:func:`.diagnosis.add_effect`).

        Returns
        -------
        ErrorModel
            ``model.version + 1`` with the refitted effects' coefficients and
            uncertainties (SI) and, where one was fitted, the datum correction [m].
        """
        new = model
        for candidate in self.candidates:
            new = add_effect(new, candidate, obs)
        if self.datum is not None:
            new.datum_correction_m = self.datum.new.copy()
        new.version = model.version + 1
        return new

    def sentence(self) -> str:
        """What a refit would change, and what it would leave (held out)."""
        live, refit = (v * 1e6 for v in self.position_cv_rmse)
        text = (f"refitting {', '.join(self.names)} on {self.readings} readings would leave "
                f"{refit:.2f} um held out (now {live:.2f} um"
                + (", both from the datum)" if self.absolute else ")"))
        if self.direction_cv_rmse is not None:
            live_d, refit_d = (v * 1e6 for v in self.direction_cv_rmse)
            text += f" and {refit_d:.2f} urad of tool direction (now {live_d:.2f} urad)"
        by_name = {c.name: c for c in self.candidates}
        moved = self.moved
        if moved:
            text += "; moved most: " + ", ".join(
                change.text(by_name[change.effect].effect, by_name[change.effect].variant)
                for change in sorted(moved, key=lambda c: -c.z)[:3])
        if self.held:
            text += (f"; taken as zero (not told from zero when fitted, not shown held out "
                     f"now): {', '.join(self.held)}")
        if self.released:
            text += f"; {', '.join(self.released)} refitted too (the readings now show them)"
        if self.datum is not None:
            text += f"; {self.datum.text()}"
        if self.refusal:
            return f"{text}; refused by physics: {self.refusal}"
        if not self.recommended:
            why = f"it would remove {self.reduction:.0%} of the held-out error" + (
                f", not significantly (p = {self.p_value:.2g})"
                if self.reduction >= self.min_reduction else "")
            return f"{text}; not worth a new version ({why})"
        return f"{text}: worth a new version (p = {self.p_value:.2g})"

    def as_dict(self) -> dict:
        return {"effects": self.names, "readings": self.readings, "absolute": self.absolute,
                "cv_rmse_live_m": self.cv_rmse_live, "cv_rmse_refit_m": self.cv_rmse_refit,
                "reduction": self.reduction, "p_value": self.p_value,
                "recommended": self.recommended,
                "refusal": self.refusal, "sentence": self.sentence(),
                "datum_correction": self.datum.as_dict() if self.datum is not None else None,
                "held": list(self.held), "released": list(self.released),
                "changes": [{"effect": c.effect, "parameter": c.parameter, "old": c.old,
                             "new": c.new, "old_uncertainty": c.old_uncertainty,
                             "new_uncertainty": c.new_uncertainty, "z": c.z}
                            for c in self.changes]}


def refittable_effects(model: ErrorModel) -> list[str]:
    """The model's fitted catalogue effects (family, variant, setting and coefficients):
    those a refit can renew. Built-in effects and user expressions stay as given.

    Parameters
    ----------
    model : ErrorModel
        The model whose effects are read.

    Returns
    -------
    list of str
        The effects' names, in the model's order.
    """
    return [name for name, entry in model.effects.items()
            if isinstance(entry, dict) and "family" in entry and "coefficients" in entry]


def _model_without(model: ErrorModel, names: list[str]) -> ErrorModel:
    for name in names:
        model = model.without_effect(name)
    return model


def _without_contribution(model: ErrorModel, base: ErrorModel, obs: Observations
                          ) -> Observations:
    """``obs`` with its predictions made by ``base``: the live predictions (which may
    hold what only the live run knew, e.g. the profiles live at each reading) minus
    what the removed effects contribute."""
    out = copy.copy(obs)
    if obs.predicted_m is None and obs.predicted_orientation is None:
        return out
    inputs = obs.model_inputs()
    with_position, with_orientation = model.tcp_error(obs.positions, **inputs, fresh=True)
    without_position, without_orientation = base.tcp_error(obs.positions, **inputs, fresh=True)
    if obs.predicted_m is not None:
        out.predicted_m = obs.predicted_m - (with_position - without_position)
    if obs.predicted_orientation is not None:
        out.predicted_orientation = obs.predicted_orientation - \
            (with_orientation - without_orientation)
    return out


def _datum_design(model: ErrorModel, base: ErrorModel, name: str, names: list[str]
                  ) -> NDArray[np.float64]:
    """(3, P) what each parameter of effect ``name`` (order ``names``) contributes at the
    datum [m per unit], by the model's own datum evaluation (the design is linear in its
    coefficients: one evaluation per parameter at a small unit)."""
    unit = 1e-6
    entry = model.effects[name]
    zero = base.datum_error()
    columns = []
    for parameter in names:
        coefficients = {p: (unit if p == parameter else 0.0) for p in names}
        probe = base.with_effect(name, {**entry, "coefficients": coefficients})
        columns.append((probe.datum_error() - zero) / unit)
    return np.column_stack(columns) if columns else np.zeros((3, 0))


def blocked_cv_errors(x: NDArray[np.float64], y: NDArray[np.float64],
                      fold_of_row: NDArray[np.intp], penalties: list[tuple[int, int, float]],
                      prior=None) -> NDArray[np.float64]:
    """Out-of-fold errors of y ~ x, each fold predicted by a fit on the others.

    Parameters
    ----------
    x : ndarray, shape (R, p)
        The design.
    y : ndarray, shape (R,)
        The readings [m].
    fold_of_row : ndarray of int, shape (R,)
        Each row's time block, non-decreasing (:class:`.selection.folds.Folds`).
    penalties : list of (start, stop, strength)
        Ridge strengths of column ranges, as the fit used.
    prior : (precision (P,), mean (P,)) or None
        A Gaussian prior on the first P columns, as the fit used (:func:`prior_fit`).

    Returns
    -------
    ndarray, shape (R,)
        y - the held-out prediction [m].
    """
    folds = Folds(fold_of_row)

    def solve(fold: int) -> NDArray[np.float64]:
        train = folds.training_rows(fold)
        _, penalised, right = _normal_equations(x[train], y[train], penalties, prior)
        return solve_normal(penalised, right)

    errors, _ = folds.held_out_residuals(x, y, solve)
    return errors


def held_parameters(model: ErrorModel, name: str, parameter_names: list[str]
                    ) -> NDArray[np.bool_]:
    """(P,) which parameters of effect ``name`` its live fit could not tell from zero:
    |value| below twice its stated standard uncertainty (within its U, k = 2). A refit
    takes them as zero unless the readings show them (:func:`refit_effects`).

    Parameters
    ----------
    model : ErrorModel
        The live model.
    name : str
        One of its fitted catalogue effects (:func:`refittable_effects`); a coefficient
        or uncertainty it does not state counts as 0 (not held).
    parameter_names : list of str, length P
        The effect's parameters, in the order wanted.

    Returns
    -------
    ndarray of bool, shape (P,)
        True where |value| < 2 u (value and u in the parameter's SI unit).
    """
    entry = model.effects[name]
    values = entry.get("coefficients") or {}
    uncertainties = entry.get("uncertainties") or {}
    return np.array([abs(float(values.get(p, 0.0))) < 2.0 * float(uncertainties.get(p, 0.0))
                     for p in parameter_names], dtype=bool)


@dataclass
class _Fit:
    """One joint fit of the change: its design, the change, its standard errors and the
    time-blocked held-out errors."""

    x: NDArray[np.float64]
    penalties: list[tuple[int, int, float]]
    change: NDArray[np.float64]
    standard: NDArray[np.float64]
    errors: NDArray[np.float64]


def _joint_fit(leading: list, blocks: list, terms: list, live_y: NDArray[np.float64],
               fold_of_row: NDArray[np.intp], prior, held: list | None = None,
               old_values: list | None = None) -> _Fit:
    """The change of every refitted coefficient (and the leading offsets) fitted to the
    live residual; ``held`` ((P,) bool per block): those taken as zero (their change is
    minus their ``old_values``; the others fitted to what that leaves)."""
    fixed = np.zeros(0)
    if held is not None:
        fixed = np.concatenate([np.zeros(sum(b.shape[1] for b in leading))] + [
            np.where(mask, -np.asarray(old, dtype=np.float64), 0.0)
            for mask, old in zip(held, old_values)])
        live_y = live_y - np.column_stack(leading + blocks) @ fixed
        blocks = [np.where(mask[None, :], 0.0, block) for block, mask in zip(blocks, held)]
    x = np.column_stack(leading + blocks)
    penalties, start = [], sum(b.shape[1] for b in leading)
    for (term, setting), block in zip(terms, blocks):
        penalties.append((start, start + block.shape[1], penalty_of(term, setting)))
        start += block.shape[1]
    change, standard = prior_fit(x, live_y, penalties, prior)
    if fixed.size:
        change = change + fixed
    return _Fit(x, penalties, change, standard,
                blocked_cv_errors(x, live_y, fold_of_row, penalties, prior))


def _design_blocks(model: ErrorModel, base: ErrorModel, names: list[str], terms: list,
                   selector: Selector, absolute: bool) -> list[NDArray[np.float64]]:
    """Each refitted effect's design on the selector's rows, referred to the datum like
    the model's error when ``absolute`` (the direction stays absolute)."""
    component = selector.component_of_row
    position_rows = component < 3
    blocks = []
    for name, (term, setting) in zip(names, terms):
        block = selector.design_rows(term, setting)
        if absolute:
            at_datum = _datum_design(model, base, name,
                                     term.family.parameter_names(term.variant, setting))
            referred = block - np.where(position_rows[:, None],
                                        at_datum[np.minimum(component, 2)], 0.0)
            # A parameter that only moves the part rigidly (a pure offset) is nothing
            # once referred: its column is rounding noise, not a direction to fit.
            vanished = np.linalg.norm(referred, axis=0) <= \
                1e-9 * np.maximum(np.linalg.norm(block, axis=0), 1e-300)
            block = np.where(vanished[None, :], 0.0, referred)
        blocks.append(block)
    return blocks


def _checked_request(model: ErrorModel, obs: Observations, names: list[str] | None,
                     folds: int) -> list[str]:
    available = refittable_effects(model)
    names = list(available if names is None else names)
    wrong = [n for n in names if n not in available]
    if wrong:
        raise ParameterError(f"cannot refit {', '.join(wrong)}: not a fitted catalogue effect "
                             f"of the model (those are: {', '.join(available) or 'none'})")
    if not names:
        raise ParameterError("the model holds no fitted catalogue effect to refit")
    if obs.n < 4 * folds:
        raise InsufficientDataError(f"{obs.n} reference readings; need >= {4 * folds}")
    return names


def refit_effects(model: ErrorModel, obs: Observations, names: list[str] | None = None, *,
                  folds: int = 5, min_reduction: float = 0.05, alpha: float = REFIT_ALPHA,
                  moved_sigma: float = MOVED_SIGMA) -> Refit:
    """Refit ``names`` (default: every refittable effect) of ``model`` on ``obs`` jointly.

    Parameters
    ----------
    model : ErrorModel
        the live model; its other effects (and profiles) stay as they are.
    obs : Observations
        N readings in time order (``predicted_m`` / ``predicted_orientation``, when
        set, are the live model's predictions and are kept for everything else).
    names : list of str or None, optional
        effects of ``model`` to refit (each a fitted catalogue entry).
    folds : int, optional
        K of the time-blocked cross-validation.
    min_reduction : float, optional
        The fraction of the live model's held-out RMSE the refit must remove to be
        recommended (and a held parameter's release must remove), dimensionless.
    alpha : float, optional
        One-sided level of the held-out block tests.
    moved_sigma : float, optional
        Combined standard uncertainties beyond which a coefficient is said to have moved.

    Returns
    -------
    Refit
        The refitted effects, each coefficient's change (SI), the held-out RMSEs (live and
        refitted; position [m], tool direction [rad]), the p-value and the verdict.

    Raises
    ------
    ParameterError
        a name that is not a fitted catalogue effect of the model; or none to refit (the
        model holds no fitted catalogue effect).
    InsufficientDataError
        fewer than 4 * folds readings.
    """
    names = _checked_request(model, obs, names, folds)
    absolute = bool(model.datum)
    base = _model_without(model, names)
    frame = residual_frame(base, _without_contribution(model, base, obs), absolute=absolute)
    live_frame = residual_frame(model, obs, absolute=absolute)
    # The readings as they would be without the effects: the designs, and the residual
    # physics judges each refitted effect against (what it explains).
    selector = Selector(frame.ctx, frame.residual, frame.mask, obs.uncertainty_m / 2.0,
                        folds=folds)
    terms = []
    for name in names:
        entry = model.effects[name]
        setting = dict(entry.get("setting") or {})
        terms.append((Term(family_named(entry["family"]), str(entry.get("variant", "")),
                           [setting]), setting))
    parameter_names = [term.family.parameter_names(term.variant, setting)
                       for term, setting in terms]
    blocks = _design_blocks(model, base, names, terms, selector, absolute)
    # The change of the coefficients is fitted to the live model's residual: the live
    # prediction stays exact and only the change is linear; a combination these
    # readings cannot see (minimum norm: no change) keeps its old value.
    live_y = live_frame.residual.ravel()[selector.rows]
    per_sample = lambda e: np.bincount(selector.sample_of_row, weights=e * e,  # noqa: E731
                                       minlength=selector.n)
    # Zeroed at the datum: no free offset - but the model's own error at the datum is
    # known only to its calibration's uncertainty, where it states it: a constant per
    # position component within that (a Gaussian prior), the datum correction.
    # Otherwise the instrument's zero per component, free.
    prior = _datum_prior(model, obs.uncertainty_m / 2.0) if absolute else None
    leading = [selector.offsets] if not absolute or prior is not None else []
    # What the live fit could not tell from zero is taken as zero, unless the readings show
    # it now: the refit with it free predicts the held-out readings better than without
    # (the block test at alpha, by min_reduction). On a few poses of a warm-up, the
    # collinear (a drift's gain, a line's tilts) take up each other's error.
    held = [held_parameters(model, name, p) for name, p in zip(names, parameter_names)]
    fit = _joint_fit(leading, blocks, terms, live_y, selector.fold_of_row, prior)
    held_names, released = [], []
    if any(mask.any() for mask in held):
        old_values = [[float((model.effects[name].get("coefficients") or {}).get(p, 0.0))
                       for p in ps] for name, ps in zip(names, parameter_names)]
        holding = _joint_fit(leading, blocks, terms, live_y, selector.fold_of_row, prior, held,
                             old_values)
        named = [f"{name}: " + ", ".join(p for p, h in zip(ps, mask) if h)
                 for name, ps, mask in zip(names, parameter_names, held) if mask.any()]
        gain = 1.0 - _rms(fit.errors) / _rms(holding.errors) if _rms(holding.errors) > 0 \
            else 0.0
        if gain >= min_reduction and selector.held_out_p_value(
                per_sample(holding.errors), per_sample(fit.errors)) < alpha:
            released = named
        else:
            fit, held_names = holding, named
    refit_errors = fit.errors
    live_errors = live_y.copy() if absolute else \
        blocked_cv_errors(selector.offsets, live_y, selector.fold_of_row, [])
    p_value = selector.held_out_p_value(per_sample(live_errors), per_sample(refit_errors))
    position_rows = selector.component_of_row < 3
    direction_cv = None
    if frame.lever:
        direction_cv = (_rms(live_errors[~position_rows]) / frame.lever,
                        _rms(refit_errors[~position_rows]) / frame.lever)
    datum = None
    if prior is not None:
        # The readings' constant beyond every effect's: the model's error at the datum
        # is that much less than it held (its referred prediction rises by it).
        old_correction = np.asarray(model.datum_correction_m, dtype=np.float64)
        datum = DatumCorrection(old_correction, old_correction - fit.change[:3],
                                fit.standard[:3],
                                np.asarray(model.datum_uncertainty_m, dtype=np.float64))
    candidates, changes, refusals = _refitted(model, selector, names, terms, parameter_names,
                                              fit, sum(b.shape[1] for b in leading),
                                              held if held_names else None, _rms(refit_errors))
    return Refit(names, candidates, obs.n, absolute, _rms(live_errors), _rms(refit_errors),
                 (_rms(live_errors[position_rows]), _rms(refit_errors[position_rows])),
                 direction_cv, changes, "; ".join(refusals), p_value, min_reduction, alpha,
                 moved_sigma, datum=datum, held=held_names, released=released or [])


def _rms(errors: NDArray[np.float64]) -> float:
    return float(np.sqrt(np.mean(errors ** 2))) if errors.size else 0.0


def _refitted(model: ErrorModel, selector: Selector, names: list[str], terms: list,
              parameter_names: list, fit: _Fit, start: int, held: list | None,
              cv_rmse: float) -> tuple[list[Candidate], list[ParameterChange], list[str]]:
    """The refitted effects as candidates, each coefficient's change, physics' refusals.
    A coefficient taken as zero keeps its stated uncertainty (the bound the readings
    left it within)."""
    candidates, changes, refusals = [], [], []
    fitted = []
    for k, parameters in enumerate(parameter_names):
        entry = model.effects[names[k]]
        old = entry.get("coefficients") or {}
        width = len(parameters)
        values = np.array([float(old.get(p, 0.0)) for p in parameters]) + \
            fit.change[start:start + width]
        errors = np.array(fit.standard[start:start + width], dtype=np.float64)
        if held is not None:
            old_u = entry.get("uncertainties") or {}
            errors = np.where(held[k], [float(old_u.get(p, 0.0)) for p in parameters], errors)
        start += width
        fitted.append((values, errors))
    # Judged as the joint fit they are: each beside what the others move.
    reasons = selector.joint_refusals(terms, [values for values, _ in fitted])
    for name, (term, setting), parameters, (values, errors), refusal in zip(
            names, terms, parameter_names, fitted, reasons):
        entry = model.effects[name]
        old = entry.get("coefficients") or {}
        old_u = entry.get("uncertainties") or {}
        if refusal:
            refusals.append(f"{name}: {refusal}")
        for parameter, value, error in zip(parameters, values, errors):
            changes.append(ParameterChange(name, parameter, float(old.get(parameter, 0.0)),
                                           float(value), float(old_u.get(parameter, 0.0)),
                                           float(error)))
        candidates.append(Candidate(
            term.family.name, dict(zip(parameters, map(float, values))), cv_rmse, 0.0, True,
            term.family.explanation(term.variant, setting), term.variant,
            dict(zip(parameters, map(float, errors))), setting, group=term.family.group,
            refusal=refusal))
    return candidates, changes, refusals


__all__ = ["MOVED_SIGMA", "REFIT_ALPHA", "DatumCorrection", "ParameterChange", "Refit",
           "blocked_cv_errors", "held_parameters", "prior_fit", "refit_effects",
           "refittable_effects"]
