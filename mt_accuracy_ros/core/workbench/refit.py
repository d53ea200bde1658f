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
                        solve_normal)

#: A coefficient is said to have moved when |new - old| exceeds this many combined
#: standard uncertainties.
MOVED_SIGMA = 2.0
#: One-sided level of the held-out test a refit must pass.
REFIT_ALPHA = 0.01


@dataclass
class ParameterChange:
    """One coefficient, before and after the refit (SI; uncertainties k = 1)."""

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
        """``bx 1.29 -> 1.02 ± 0.12 µm/K`` in the parameter's physical unit (U, k = 2)."""
        from ..effects.display import format_measured, parameter_unit

        unit, factor = parameter_unit(family, variant, self.parameter)
        new = format_measured(self.new * factor, 2.0 * self.new_uncertainty * factor, unit)
        decimals = new.split(" ± ")[0]
        places = len(decimals.split(".")[1]) if "." in decimals else 0
        return f"{self.parameter} {self.old * factor:.{places}f} -> {new}"


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
        """The next version of ``model``: every refitted effect with its new numbers."""
        new = model
        for candidate in self.candidates:
            new = add_effect(new, candidate, obs)
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
                "changes": [{"effect": c.effect, "parameter": c.parameter, "old": c.old,
                             "new": c.new, "old_uncertainty": c.old_uncertainty,
                             "new_uncertainty": c.new_uncertainty, "z": c.z}
                            for c in self.changes]}


def refittable_effects(model: ErrorModel) -> list[str]:
    """The model's fitted catalogue effects (family, variant, setting and coefficients):
    those a refit can renew. Built-in effects and user expressions stay as given."""
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
                      fold_of_row: NDArray[np.intp], penalties: list[tuple[int, int, float]]
                      ) -> NDArray[np.float64]:
    """Out-of-fold errors (R,) of y ~ x: each fold predicted by a fit on the others
    (``penalties``: ridge (start, stop, strength) of column ranges, as the fit used)."""
    errors = np.empty_like(y)
    for fold in np.unique(fold_of_row):
        held = fold_of_row == fold
        train = ~held
        gram = x[train].T @ x[train]
        for start, stop, strength in penalties:
            gram = penalise(gram, start, stop, strength)
        coefficients = solve_normal(gram, x[train].T @ y[train])
        errors[held] = y[held] - x[held] @ coefficients
    return errors


def refit_effects(model: ErrorModel, obs: Observations, names: list[str] | None = None, *,
                  folds: int = 5, min_reduction: float = 0.05, alpha: float = REFIT_ALPHA,
                  moved_sigma: float = MOVED_SIGMA) -> Refit:
    """Refit ``names`` (default: every refittable effect) of ``model`` on ``obs`` jointly.

    Parameters
    ----------
    model : the live model; its other effects (and profiles) stay as they are.
    obs : N readings in time order (``predicted_m`` / ``predicted_orientation``, when
        set, are the live model's predictions and are kept for everything else).
    names : effects of ``model`` to refit (each a fitted catalogue entry).
    folds : K of the time-blocked cross-validation.

    Raises
    ------
    ParameterError : a name that is not a fitted catalogue effect of the model.
    InsufficientDataError : fewer than 4 * folds readings.
    """
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
    absolute = bool(model.datum)
    base = _model_without(model, names)
    base_obs = _without_contribution(model, base, obs)
    frame = residual_frame(base, base_obs, absolute=absolute)
    live_frame = residual_frame(model, obs, absolute=absolute)
    noise_sigma = obs.uncertainty_m / 2.0
    # The readings as they would be without the effects: the designs, and the residual
    # physics judges each refitted effect against (what it explains).
    selector = Selector(frame.ctx, frame.residual, frame.mask, noise_sigma, folds=folds)
    terms = []
    for name in names:
        entry = model.effects[name]
        setting = dict(entry.get("setting") or {})
        terms.append((Term(family_named(entry["family"]), str(entry.get("variant", "")),
                           [setting]), setting))
    component = selector.component_of_row
    position_rows = component < 3
    blocks = []
    for name, (term, setting) in zip(names, terms):
        block = selector.design_rows(term, setting)
        if absolute:
            # Referred to the datum like the model's error (the direction stays absolute).
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
    # Zeroed at the datum: no free offset; otherwise the instrument's zero per component.
    leading = [] if absolute else [selector.offsets]
    x = np.column_stack(leading + blocks)
    penalties, start = [], sum(b.shape[1] for b in leading)
    for (term, setting), block in zip(terms, blocks):
        penalties.append((start, start + block.shape[1], penalty_of(term, setting)))
        start += block.shape[1]
    # The change of the coefficients is fitted to the live model's residual: the live
    # prediction stays exact and only the change is linear; a combination these
    # readings cannot see (minimum norm: no change) keeps its old value.
    live_y = live_frame.residual.ravel()[selector.rows]
    old_values = [np.array([float((model.effects[name].get("coefficients") or {}).get(p, 0.0))
                            for p in term.family.parameter_names(term.variant, setting)])
                  for name, (term, setting) in zip(names, terms)]
    change, standard, _ = penalised_fit(x, live_y, penalties)
    coefficients, standard_errors, start = [], [], penalties[0][0]
    for block, old in zip(blocks, old_values):
        coefficients.append(old + change[start:start + block.shape[1]])
        standard_errors.append(standard[start:start + block.shape[1]])
        start += block.shape[1]
    refit_errors = blocked_cv_errors(x, live_y, selector.fold_of_row, penalties)
    live_errors = live_y.copy() if absolute else \
        blocked_cv_errors(selector.offsets, live_y, selector.fold_of_row, [])
    per_sample = lambda e: np.bincount(selector.sample_of_row, weights=e * e,  # noqa: E731
                                       minlength=selector.n)
    p_value = selector.held_out_p_value(per_sample(live_errors), per_sample(refit_errors))

    def rms(errors, rows=slice(None)) -> float:
        picked = errors[rows]
        return float(np.sqrt(np.mean(picked ** 2))) if picked.size else 0.0

    direction_cv = None
    if frame.lever:
        direction_rows = ~position_rows
        direction_cv = (rms(live_errors, direction_rows) / frame.lever,
                        rms(refit_errors, direction_rows) / frame.lever)
    candidates, changes, refusals = [], [], []
    for name, (term, setting), values, errors in zip(names, terms, coefficients,
                                                      standard_errors):
        entry = model.effects[name]
        parameter_names = term.family.parameter_names(term.variant, setting)
        refusal = selector.physics_refusal(term, setting, values)
        if refusal:
            refusals.append(f"{name}: {refusal}")
        old = entry.get("coefficients") or {}
        old_u = entry.get("uncertainties") or {}
        for parameter, value, error in zip(parameter_names, values, errors):
            changes.append(ParameterChange(name, parameter, float(old.get(parameter, 0.0)),
                                           float(value), float(old_u.get(parameter, 0.0)),
                                           float(error)))
        candidates.append(Candidate(
            term.family.name, dict(zip(parameter_names, map(float, values))),
            rms(refit_errors), 0.0, True, term.family.explanation(term.variant, setting),
            term.variant, dict(zip(parameter_names, map(float, errors))), setting,
            group=term.family.group, refusal=refusal))
    return Refit(names, candidates, obs.n, absolute, rms(live_errors), rms(refit_errors),
                 (rms(live_errors, position_rows), rms(refit_errors, position_rows)),
                 direction_cv, changes, "; ".join(refusals), p_value, min_reduction, alpha,
                 moved_sigma)


__all__ = ["MOVED_SIGMA", "REFIT_ALPHA", "ParameterChange", "Refit", "blocked_cv_errors",
           "refit_effects", "refittable_effects"]
