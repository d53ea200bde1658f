"""The workbench for tabular data (CSV): a thermal error model of named inputs.

The model is a linear model (Zhu eq. 3.12) of an intercept and the terms it
holds; the candidate library is, for a target column:

* ``sensor:<col>`` - a temperature input (Zhu eq. 3.12), "sensor term";
* ``difference:<a>-<b>`` - a temperature difference: bending of a link
  (deflection/slope, Zhu Table 4.2);
* ``lag:<driver>:<tau>s`` - a thermal mode of time constant tau driven by an
  operating input such as spindle speed (Zhu eqs. 3.9-3.10).

Ranking is by time-blocked K-fold CV on the training rows only; the judged
error is on the held-out rows that follow them in time.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..errors import InputDataError, InsufficientDataError
from ..thermal.regression import fit_linear, lag_features

DEFAULT_TAUS_S = (600.0, 1800.0, 5400.0, 16200.0)


@dataclass
class Term:
    name: str
    column: NDArray[np.float64]
    explanation: str


@dataclass
class TermScore:
    name: str
    cv_rmse_after: float
    error_reduction: float
    significant: bool
    explanation: str


@dataclass
class TableWorkbench:
    """Target, candidate terms, the terms in the model and the train/judge split."""

    target: NDArray[np.float64]
    candidates: dict[str, Term]
    train: NDArray[np.bool_]
    included: list[str] = field(default_factory=list)
    folds: int = 5

    def design(self, names: list[str]) -> NDArray[np.float64]:
        if not names:
            return np.zeros((self.target.size, 0))
        return np.column_stack([self.candidates[n].column for n in names])

    def cv_rmse(self, names: list[str]) -> float:
        rows = np.flatnonzero(self.train)
        x, y = self.design(names)[rows], self.target[rows]
        errors = []
        for fold in np.array_split(np.arange(rows.size), self.folds):
            keep = np.setdiff1d(np.arange(rows.size), fold)
            if x.shape[1]:
                model = fit_linear(x[keep], y[keep], ridge=1e-9)
                prediction = model.predict(x[fold])
            else:
                prediction = np.full(fold.size, y[keep].mean())
            errors.append(np.mean((prediction - y[fold]) ** 2))
        return float(np.sqrt(np.mean(errors)))

    def fit_predict(self, names: list[str]) -> NDArray[np.float64]:
        """Model of ``names`` fitted on the training rows, predicted on every row."""
        x = self.design(names)
        if not x.shape[1]:
            return np.full(self.target.size, self.target[self.train].mean())
        model = fit_linear(x[self.train], self.target[self.train], ridge=1e-9)
        return model.predict(x)

    def judged_rmse(self, names: list[str]) -> float:
        prediction = self.fit_predict(names)
        judge = ~self.train
        return float(np.sqrt(np.mean((prediction[judge] - self.target[judge]) ** 2)))

    def validation_rmse(self, names: list[str]) -> float:
        """Fitted on the first 70 % of the training rows, judged on their last 30 %: the
        stop rule's data (the held-out rows stay the final judge, never used to choose)."""
        rows = np.flatnonzero(self.train)
        cut = int(0.7 * rows.size)
        fit, check = rows[:cut], rows[cut:]
        x = self.design(names)
        if x.shape[1]:
            model = fit_linear(x[fit], self.target[fit], ridge=1e-9)
            prediction = model.predict(x[check])
        else:
            prediction = np.full(check.size, self.target[fit].mean())
        return float(np.sqrt(np.mean((prediction - self.target[check]) ** 2)))

    def parameters_significant(self, names: list[str]) -> bool:
        """Every coefficient of the newest term above 3 standard errors (training rows)."""
        rows = np.flatnonzero(self.train)
        x = np.column_stack([np.ones(rows.size), self.design(names)[rows]])
        y = self.target[rows]
        coefficients, *_ = np.linalg.lstsq(x, y, rcond=None)
        dof = max(1, rows.size - x.shape[1])
        sigma2 = float(np.sum((x @ coefficients - y) ** 2)) / dof
        standard = np.sqrt(np.clip(np.diag(sigma2 * np.linalg.pinv(x.T @ x)), 0.0, None))
        return bool(abs(coefficients[-1]) > 3.0 * standard[-1])

    def rank(self, min_reduction: float = 0.05) -> list[TermScore]:
        """Candidates by CV error. Significant: the CV error falls by ``min_reduction``
        after a Bonferroni-style penalty for the number tried, the validation rows (fit on
        the earlier training rows) fall too, and the new coefficient stands above 3
        standard errors."""
        base = self.cv_rmse(self.included)
        base_validation = self.validation_rmse(self.included)
        scores = []
        tried = max(1, len(self.candidates) - len(self.included))
        # The best of many noise regressors cuts the CV error by chance ~ sqrt(2 ln M / n).
        chance = float(np.sqrt(2.0 * np.log(tried) / max(1, int(self.train.sum()))))
        for name, term in self.candidates.items():
            if name in self.included:
                continue
            after = self.cv_rmse(self.included + [name])
            reduction = 1.0 - after / base if base > 0 else 0.0
            scores.append(TermScore(name, after, reduction, reduction >= min_reduction + chance,
                                    term.explanation))
        scores.sort(key=lambda s: s.cv_rmse_after)
        for score in scores[:3]:
            if score.significant:
                names = self.included + [score.name]
                score.significant = bool(
                    self.validation_rmse(names) < 0.95 * base_validation and
                    self.parameters_significant(names))
        for score in scores[3:]:
            score.significant = False
        return scores


def table_workbench(columns: dict[str, NDArray], time_s: NDArray, target: str,
                    inputs: list[str], drivers: list[str] | None = None,
                    train_fraction: float = 0.5, differences: bool = True,
                    time_constants_s=DEFAULT_TAUS_S, included: list[str] | None = None
                    ) -> TableWorkbench:
    """Build the candidate library from a table's columns."""
    if target not in columns:
        raise InputDataError(f"no target column {target!r}; have {', '.join(columns)}")
    y = np.asarray(columns[target], dtype=np.float64)
    t = np.asarray(time_s, dtype=np.float64)
    good = np.isfinite(y) & np.isfinite(t)
    for name in inputs + (drivers or []):
        if name not in columns:
            raise InputDataError(f"no input column {name!r}")
        good &= np.isfinite(columns[name])
    if good.sum() < 20:
        raise InsufficientDataError(f"only {int(good.sum())} complete rows")
    if not np.all(np.diff(t[good]) > 0):
        raise InputDataError("the time column must increase (sort the file or fix the stamps)")
    y, t = y[good], t[good]
    candidates: dict[str, Term] = {}
    for name in inputs:
        values = np.asarray(columns[name], dtype=np.float64)[good]
        if np.ptp(values) <= 0:
            continue  # a constant (dead) sensor explains nothing
        candidates[f"sensor:{name}"] = Term(
            f"sensor:{name}", values - values[0],
            f"temperature {name} as a regressor - the part of the structure it sits on "
            "expands with it (Zhu eq. 3.12)")
    if differences:
        names = [n for n in inputs if f"sensor:{n}" in candidates]
        for i, a in enumerate(names):
            for b in names[i + 1:]:
                candidates[f"difference:{a}-{b}"] = Term(
                    f"difference:{a}-{b}",
                    candidates[f"sensor:{a}"].column - candidates[f"sensor:{b}"].column,
                    f"the difference {a} - {b}: a temperature gradient that bends a link "
                    "(deflection and slope, Zhu Table 4.2)")
    for driver in drivers or []:
        u = np.asarray(columns[driver], dtype=np.float64)[good]
        scale = np.max(np.abs(u)) or 1.0
        uniform_t = np.linspace(t[0], t[-1], t.size)
        if not np.allclose(np.diff(t), np.diff(t)[0], rtol=1e-3):
            raise InputDataError("lag terms need uniformly sampled rows")
        lags = lag_features(uniform_t, u / scale, time_constants_s, initial="steady")
        for j, tau in enumerate(time_constants_s):
            candidates[f"lag:{driver}:{tau:g}s"] = Term(
                f"lag:{driver}:{tau:g}s", lags[:, j],
                f"a thermal mode with time constant {tau / 60:g} min driven by {driver} - "
                "heat that takes that long to arrive (Zhu eqs. 3.9-3.10)")
    train = np.arange(y.size) < int(train_fraction * y.size)
    unknown = [n for n in (included or []) if n not in candidates]
    if unknown:
        raise InputDataError(f"model terms not available: {', '.join(unknown)}")
    return TableWorkbench(y, candidates, train, list(included or []))
