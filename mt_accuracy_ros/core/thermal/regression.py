"""Thermal error regression models (Zhu eqs. 3.12-3.15, 3.17; Krulewich eq. 3).

* position independent, E(t) = sum_i beta_i T_i(t)                       (3.12)
* position dependent, E(x, t) = sum_i [beta_0i + beta_1i P(x) + ...] T_i(t)  (3.13)
* lag terms: first-order responses h_tau(t) of a heat input (spindle speed),
  tau h' = u - h, the modal coordinates of Zhu eq. 3.9, as extra regressors;
* the three-mode time-constant fit of a temperature record (3.17).

Least squares (3.15) is solved on centred and scaled columns (QR via
``lstsq``), never by forming (T'T)^-1; the condition number of the scaled
design is reported and an optional ridge term regularises it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares
from scipy.signal import lfilter

from ..errors import CalibrationError, InputDataError, InsufficientDataError, ParameterError

#: Above this condition number of the scaled design the fit is called ill-conditioned.
ILL_CONDITIONED = 1e8


@dataclass
class LinearThermalModel:
    """A fitted linear model E = X beta + intercept on named regressors.

    Attributes
    ----------
    names : list of str        regressor names (columns of X)
    coefficients : (p,)         beta in the unit of E per unit of each regressor
    intercept : float           E at zero regressors (0 when fitted without)
    condition_number : float    of the centred, scaled design
    train_rmse : float
    """

    names: list[str]
    coefficients: NDArray[np.float64]
    intercept: float
    condition_number: float
    train_rmse: float
    ridge: float = 0.0

    def predict(self, design: ArrayLike) -> NDArray[np.float64]:
        """E = X beta + intercept at new samples.

        Parameters
        ----------
        design : array_like, shape (n, p)
            Regressors, each in the unit it was fitted in (e.g. [degC] or [K]).

        Returns
        -------
        ndarray, shape (n,)
            Predicted E, the target's unit (e.g. [m]).

        Raises
        ------
        InputDataError
            A design not (n, p).
        """
        x = np.asarray(design, dtype=np.float64)
        if x.ndim != 2 or x.shape[1] != self.coefficients.size:
            raise InputDataError(f"design must be (n, {self.coefficients.size}), got {x.shape}")
        return x @ self.coefficients + self.intercept


def _check_design(design: NDArray, target: NDArray, names: list[str]) -> None:
    if design.ndim != 2:
        raise InputDataError(f"design must be 2-D (samples, regressors), got {design.shape}")
    if target.shape != (design.shape[0],):
        raise InputDataError(f"target must have {design.shape[0]} values, got {target.shape}")
    bad_rows = ~np.isfinite(design).all(axis=1) | ~np.isfinite(target)
    if bad_rows.any():
        columns = [names[j] for j in np.flatnonzero(~np.isfinite(design).all(axis=0))]
        raise InputDataError(f"{int(bad_rows.sum())} samples hold NaN/inf"
                             + (f" (regressors {', '.join(columns)})" if columns else " (target)")
                             + "; drop or interpolate them before fitting")


def fit_linear(design: ArrayLike, target: ArrayLike, names: list[str] | None = None, *,
               intercept: bool = True, ridge: float = 0.0) -> LinearThermalModel:
    """Least squares (Zhu eq. 3.15) done soundly: centre, scale, QR, optional ridge.

    Parameters
    ----------
    design : array_like, shape (n, p)
        Regressors (unit-agnostic, e.g. temperatures [degC]).
    target : array_like, shape (n,)
        E (unit-agnostic, e.g. [m]).
    names : list of str, optional
        Regressor names (default ``x0, x1, ...``).
    intercept : bool, optional
        Fit an intercept.
    ridge : float, optional
        Ridge strength on the scaled regressors (dimensionless, >= 0).

    Returns
    -------
    LinearThermalModel
        beta in the target's unit per regressor unit, the intercept, the condition
        number and the training RMSE.

    Raises
    ------
    InsufficientDataError
        Fewer samples than parameters.
    InputDataError
        NaN/inf values, a constant regressor, or shapes that do not match.
    ParameterError
        A negative or non-finite ridge.
    CalibrationError
        A rank-deficient design without ridge.
    """
    x = np.asarray(design, dtype=np.float64)
    y = np.asarray(target, dtype=np.float64)
    names = list(names) if names is not None else [f"x{j}" for j in range(x.shape[-1])]
    _check_design(x, y, names)
    n, p = x.shape
    parameters = p + (1 if intercept else 0)
    if n < parameters:
        raise InsufficientDataError(f"{n} samples for {parameters} parameters: under-determined")
    if not np.isfinite(ridge) or ridge < 0:
        raise ParameterError(f"ridge must be finite and >= 0, got {ridge}")
    centre = x.mean(axis=0) if intercept else np.zeros(p)
    spread = (x - centre).std(axis=0) if intercept else np.sqrt(np.mean(x ** 2, axis=0))
    constant = spread <= 1e-12 * np.maximum(1.0, np.abs(x).max(axis=0))
    if constant.any():
        raise InputDataError(f"regressor(s) {', '.join(np.asarray(names)[constant])} are constant "
                             "over the training data (a dead or disconnected sensor?)")
    scaled = (x - centre) / spread
    y_centre = y.mean() if intercept else 0.0
    singular = np.linalg.svd(scaled, compute_uv=False)
    condition = float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")
    if ridge > 0:
        augmented = np.vstack([scaled, np.sqrt(ridge * n) * np.eye(p)])
        rhs = np.concatenate([y - y_centre, np.zeros(p)])
    else:
        if not np.isfinite(condition) or condition > 1e12:
            raise CalibrationError(f"the design is singular (condition {condition:.3g}): "
                                   "regressors are linearly dependent; drop one or use ridge > 0")
        augmented, rhs = scaled, y - y_centre
    solution, *_ = np.linalg.lstsq(augmented, rhs, rcond=None)
    beta = solution / spread
    offset = float(y_centre - centre @ beta) if intercept else 0.0
    residual = y - (x @ beta + offset)
    return LinearThermalModel(names, beta, offset, condition,
                              float(np.sqrt(np.mean(residual ** 2))), float(ridge))


def position_independent_design(temperatures: ArrayLike, names: list[str] | None = None
                                ) -> tuple[NDArray[np.float64], list[str]]:
    """Columns T_i(t) of Zhu eq. 3.12; ``temperatures`` (n, N) [K or degC].

    Parameters
    ----------
    temperatures : array_like, shape (n, N) or (n,)
        Sensor temperatures [K or degC].
    names : list of str, optional
        Sensor names (default ``T1 ... TN``).

    Returns
    -------
    design : ndarray, shape (n, N)
        The temperatures as columns.
    names : list of str
        Column names.
    """
    t = np.asarray(temperatures, dtype=np.float64)
    if t.ndim == 1:
        t = t[:, None]
    return t, list(names) if names is not None else [f"T{i + 1}" for i in range(t.shape[1])]


def position_dependent_design(temperatures: ArrayLike, position: ArrayLike, degree: int = 1,
                              names: list[str] | None = None
                              ) -> tuple[NDArray[np.float64], list[str]]:
    """Columns P(x)^j T_i(t), j = 0 ... degree, of Zhu eq. 3.13 (P(x) = x).

    Parameters
    ----------
    temperatures : array_like, shape (n, N) or (n,)
        Sensor temperatures [K or degC].
    position : array_like, shape (n,)
        Axis position x [m].
    degree : int, optional
        Highest power j (>= 0).
    names : list of str, optional
        Sensor names.

    Returns
    -------
    design : ndarray, shape (n, N (degree + 1))
        Columns [temperature unit x m^j].
    names : list of str
        Column names (``T1*x^2`` ...).

    Raises
    ------
    InputDataError
        A position of the wrong length.
    ParameterError
        A negative degree.
    """
    t, base = position_independent_design(temperatures, names)
    x = np.asarray(position, dtype=np.float64)
    if x.shape != (t.shape[0],):
        raise InputDataError(f"position must have {t.shape[0]} values, got {x.shape}")
    if int(degree) < 0:
        raise ParameterError(f"degree must be >= 0, got {degree}")
    columns, labels = [], []
    for j in range(int(degree) + 1):
        for i, name in enumerate(base):
            columns.append(t[:, i] * x ** j)
            labels.append(name if j == 0 else f"{name}*x^{j}")
    return np.column_stack(columns), labels


def lag_features(time_s: ArrayLike, heat_input: ArrayLike, time_constants_s: ArrayLike,
                 *, initial: str = "rest") -> NDArray[np.float64]:
    """First-order responses h_tau of ``heat_input`` (Zhu eq. 3.9), one column per tau.

    tau h' = u - h, exact for u piecewise constant between samples; needs
    uniformly spaced ``time_s``. ``initial``: ``"rest"`` starts at h(0) = 0 (a heat
    input switched on at t = 0); ``"steady"`` at h(0) = u(0), the state the
    record started in - the right start for a temperature, whose lag from 0
    would carry a start-up ramp of the whole temperature.

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Uniformly spaced times [s].
    heat_input : array_like, shape (n,)
        Input u (unit-agnostic: a power [W], a temperature [K] ...).
    time_constants_s : array_like, shape (m,)
        Time constants tau [s] (> 0).
    initial : {"rest", "steady"}, optional
        The start state.

    Returns
    -------
    ndarray, shape (n, m)
        h_tau, the input's unit.

    Raises
    ------
    ParameterError
        An unknown ``initial`` or a time constant not positive.
    InputDataError
        Mismatched, too short, non-uniform or non-finite inputs.
    """
    if initial not in ("rest", "steady"):
        raise ParameterError(f"initial must be 'rest' or 'steady', got {initial!r}")
    t = np.asarray(time_s, dtype=np.float64)
    u = np.asarray(heat_input, dtype=np.float64)
    if t.shape != u.shape or t.ndim != 1 or t.size < 2:
        raise InputDataError("time_s and heat_input must be equal-length 1-D arrays (>= 2)")
    steps = np.diff(t)
    if not np.allclose(steps, steps[0], rtol=1e-6):
        raise InputDataError("lag_features needs uniformly spaced samples")
    if not np.all(np.isfinite(u)):
        raise InputDataError("heat_input holds NaN/inf")
    out = []
    for tau in np.atleast_1d(np.asarray(time_constants_s, dtype=np.float64)):
        if not np.isfinite(tau) or tau <= 0:
            raise ParameterError(f"time constants must be finite and > 0, got {tau}")
        a = np.exp(-steps[0] / tau)
        start = u[0] if initial == "steady" else 0.0
        shifted = np.concatenate([[0.0], u[:-1] - start])
        out.append(lfilter([1.0 - a], [1.0, -a], shifted) + start)
    return np.column_stack(out)


@dataclass
class TimeConstantFit:
    """T(t) = T0 + sum_i A_i (1 - exp(-t/tau_i)) (Zhu eq. 3.17; T0 added for raw records)."""

    amplitudes: NDArray[np.float64]
    time_constants_s: NDArray[np.float64]
    offset: float
    rmse: float

    def __call__(self, time_s: ArrayLike) -> NDArray[np.float64]:
        t = np.asarray(time_s, dtype=np.float64)[:, None]
        rises = self.amplitudes * (1 - np.exp(-t / self.time_constants_s))  # Zhu eq. 3.17
        return self.offset + rises.sum(axis=1)


def fit_time_constants(time_s: ArrayLike, temperature: ArrayLike, n_modes: int = 3,
                       initial_s: ArrayLike | None = None) -> TimeConstantFit:
    """Fit Zhu eq. 3.17 to a step-response temperature record (log-tau parametrisation).

    Sorted slowest first, like Zhu's tau_1 = 363.6, tau_2 = 61.7, tau_3 = 27.0 min.

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Times from the step [s].
    temperature : array_like, shape (n,)
        Temperature record [K or degC].
    n_modes : int, optional
        Number of exponentials.
    initial_s : array_like, shape (n_modes,), optional
        Starting time constants [s].

    Returns
    -------
    TimeConstantFit
        Amplitudes [K], time constants [s] slowest first, offset T0 and RMSE
        (the temperature's unit).

    Raises
    ------
    InputDataError
        Mismatched or non-finite inputs.
    InsufficientDataError
        Fewer than 2 n_modes + 2 samples.
    """
    t = np.asarray(time_s, dtype=np.float64)
    y = np.asarray(temperature, dtype=np.float64)
    if t.shape != y.shape or t.ndim != 1:
        raise InputDataError("time_s and temperature must be equal-length 1-D arrays")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise InputDataError("time_s/temperature hold NaN/inf")
    if t.size < 2 * n_modes + 2:
        raise InsufficientDataError(f"{t.size} samples for {2 * n_modes + 1} parameters")
    span = t.max() - t.min()
    guess = np.geomspace(span / 2, span / 50, n_modes) if initial_s is None else \
        np.asarray(initial_s, dtype=np.float64)

    def basis(log_tau):
        return 1.0 - np.exp(-t[:, None] / np.exp(log_tau)[None, :])

    def residual(log_tau):
        # Amplitudes and offset are linear: solve them for every tau (variable projection).
        design = np.column_stack([np.ones_like(t), basis(log_tau)])
        coefficients, *_ = np.linalg.lstsq(design, y, rcond=None)
        return design @ coefficients - y

    solution = least_squares(residual, np.log(guess), method="trf")
    design = np.column_stack([np.ones_like(t), basis(solution.x)])
    coefficients, *_ = np.linalg.lstsq(design, y, rcond=None)
    tau = np.exp(solution.x)
    order = np.argsort(tau)[::-1]
    return TimeConstantFit(coefficients[1:][order], tau[order], float(coefficients[0]),
                           float(np.sqrt(np.mean(solution.fun ** 2))))
