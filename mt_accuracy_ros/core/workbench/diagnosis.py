"""Model versus measurement: where the model fails and which physical effect is missing.

Given reference measurements of the TCP error (laser, probe, ball bar, ...) and
an :class:`~..compensation.error_model.ErrorModel`, the residual r = measured - model is
explained, one candidate effect at a time, by that effect's regressors - the
columns through which its parameters enter the error (the effect is linear in
them to first order). Each candidate is scored by **time-blocked K-fold
cross-validation** (contiguous folds, never in-sample) of the residual fit,
against the same CV of a constant offset alone. The guard against explaining
noise: a candidate counts only if it lowers the CV RMSE by at least
``min_reduction``, its fitted parameters are significant (|p| > 3 sigma), and
the residual is clearly above the instrument's noise (RMSE >= 1.5 sigma, sigma
= the readings' k = 2 uncertainty / 2); otherwise the diagnosis is "no missing
effect found".

Candidates (names as the simulator and the model name them):

=============================  ===================================================
effect                         regressors (per measured component)
=============================  ===================================================
structural_thermal_drift       dT of one structure sensor, per x, y, z (Zhu 3.12)
position_dependent_thermal     (q_a - q_ref) dT on the a component (Zhu 3.13)
spindle_thermal_growth         dT of the spindle sensor on z
squareness                     d e / d S for EC0Y, EB0Z, EA0Z via the kinematic model
abbe_offset                    eps x unit vectors (eps = model orientation error)
reversal                       -sign(v_a) / 2 on the a component
servo_lag                      -v_a on the a component
=============================  ===================================================
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..compensation.error_model import ErrorModel
from ..errors import InsufficientDataError
from ..kinematics.chain import ErrorOverrides, KinematicModel

AXES3 = "XYZ"


@dataclass
class Observations:
    """N reference readings. positions/velocities: axis -> (N,); temperatures: sensor -> (N,)."""

    positions: dict[str, NDArray[np.float64]]
    measured_m: NDArray[np.float64]                 # (N, 3)
    measured_mask: NDArray[np.bool_]                # (N, 3)
    time_s: NDArray[np.float64]
    velocities: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    temperatures: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    uncertainty_m: float = 1e-6                     # k = 2
    #: Optional: (N, 3) position and orientation predictions made elsewhere (e.g. with
    #: the profiles that were live at each reading); used instead of model.tcp_error.
    predicted_m: NDArray[np.float64] | None = None
    predicted_orientation: NDArray[np.float64] | None = None
    #: Optional: axis -> +-1, the direction of the last motion (for reversal at a standstill).
    directions: dict[str, NDArray[np.float64]] = field(default_factory=dict)

    def subset(self, rows) -> "Observations":
        pick = lambda d: {k: np.asarray(v)[rows] for k, v in d.items()}  # noqa: E731
        return Observations(pick(self.positions), self.measured_m[rows], self.measured_mask[rows],
                            self.time_s[rows], pick(self.velocities), pick(self.temperatures),
                            self.uncertainty_m,
                            None if self.predicted_m is None else self.predicted_m[rows],
                            None if self.predicted_orientation is None
                            else self.predicted_orientation[rows], pick(self.directions))

    @property
    def n(self) -> int:
        return self.measured_m.shape[0]


@dataclass
class Candidate:
    """A candidate effect's fit to the residual."""

    effect: str
    parameters: dict
    cv_rmse_after: float
    error_reduction: float
    significant: bool
    explanation: str
    variant: str = ""
    #: Standard (k = 1) uncertainty of each fitted parameter, from the least-squares
    #: covariance sigma^2 (X^T X)^-1 [unit of the parameter].
    parameter_uncertainties: dict = field(default_factory=dict)


@dataclass
class Diagnosis:
    baseline_rmse: float            # in-sample residual RMSE of the current model [m]
    baseline_cv_rmse: float         # CV RMSE of the residual with only a constant offset
    max_abs_error: float
    fraction_outside_band: float
    ranking: list[Candidate]

    @property
    def found(self) -> Candidate | None:
        return next((c for c in self.ranking if c.significant), None)

    def text(self) -> str:
        best = self.found
        if best is None:
            return (f"residual RMSE {self.baseline_rmse * 1e6:.2f} um; no candidate effect "
                    "explains it beyond noise")
        return (f"residual RMSE {self.baseline_rmse * 1e6:.2f} um; most likely missing: "
                f"{best.effect} ({best.explanation}); adding it would leave "
                f"{best.cv_rmse_after * 1e6:.2f} um (cross-validated)")


def _rises(obs: Observations, sensor: str) -> NDArray[np.float64]:
    values = np.asarray(obs.temperatures[sensor], dtype=np.float64)
    return values - values[0]


def candidate_designs(model: ErrorModel, obs: Observations) -> list[tuple[str, str, list[str],
                                                                          NDArray]]:
    """(effect, variant, parameter names, design (N, 3, p)) for every candidate not in the model."""
    n = obs.n
    out = []
    structure = [s for s in obs.temperatures if not any(
        s.startswith(f"{a.lower()}{i}_s") for a in AXES3 for i in (1, 2))]
    if "structural_thermal_drift" not in model.effects:
        for sensor in structure:
            rise = _rises(obs, sensor)
            design = np.zeros((n, 3, 3))
            for c in range(3):
                design[:, c, c] = rise
            out.append(("structural_thermal_drift", sensor, ["bx", "by", "bz"], design))
    kinematics = KinematicModel(model.machine)
    q = {a: np.asarray(obs.positions.get(a, np.zeros(n)), float) for a in model.machine.axis_order}
    if "position_dependent_thermal" not in model.effects:
        for axis in AXES3:
            if axis not in obs.positions:
                continue
            for sensor in structure:
                design = np.zeros((n, 3, 1))
                along = model.axis_direction(axis, q)
                design[:, :, 0] = (obs.positions[axis] * _rises(obs, sensor))[:, None] * along
                out.append(("position_dependent_thermal", f"{axis}:{sensor}", ["alpha"], design))
    if "spindle_thermal_growth" not in model.effects and "spindle" in obs.temperatures:
        design = np.zeros((n, 3, 1))
        design[:, 2, 0] = _rises(obs, "spindle")
        out.append(("spindle_thermal_growth", "spindle", ["m_per_k"], design))
    if "squareness" not in model.effects:
        names = [nm for nm in ("EC0Y", "EB0Z", "EA0Z") if nm[-1] in model.machine.axes]
        design = np.zeros((n, 3, len(names)))
        base = kinematics.tcp_error(q, overrides=ErrorOverrides(use_description=False),
                                    check_stroke=False)["position"]
        for j, name in enumerate(names):
            moved = kinematics.tcp_error(q, overrides=ErrorOverrides(
                location={name: 1e-6}, use_description=False), check_stroke=False)["position"]
            design[:, :, j] = (moved - base) / 1e-6
        out.append(("squareness", "", names, design))
    if "abbe_offset" not in model.effects and ("geometric" in model.effects or model.profiles):
        orientation = obs.predicted_orientation if obs.predicted_orientation is not None else \
            model.tcp_error(q, obs.temperatures, obs.velocities or None)[1]
        design = np.stack([np.cross(orientation, unit) for unit in np.eye(3)], axis=2)
        out.append(("abbe_offset", "", ["ox", "oy", "oz"], design))
    for effect, form in (("reversal", "sign"), ("servo_lag", "velocity")):
        if effect in model.effects or not obs.velocities:
            continue
        axes = [a for a in AXES3 if a in obs.velocities and a in model.machine.axes]
        design = np.zeros((n, 3, len(axes)))
        for j, axis in enumerate(axes):
            v = np.asarray(obs.velocities[axis], float)
            sign = np.asarray(obs.directions[axis], float) if axis in obs.directions \
                else np.sign(v)
            along = model.axis_direction(axis, q)
            design[:, :, j] = (-0.5 * sign if form == "sign" else -v)[:, None] * along
        out.append((effect, "", [f"{a}" for a in axes], design))
    return out


def _flatten(design: NDArray, residual: NDArray, mask: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Rows = measured (sample, component) pairs; one offset column per component."""
    rows = np.flatnonzero(mask.ravel())
    x = design.reshape(-1, design.shape[2])[rows] if design.size else np.zeros((rows.size, 0))
    offsets = np.zeros((mask.size, 3))
    offsets[np.arange(mask.size), np.tile(np.arange(3), mask.shape[0])] = 1.0
    return x, offsets[rows], residual.ravel()[rows]


def blocked_cv(x: NDArray, offsets: NDArray, y: NDArray, sample_of_row: NDArray,
               n_samples: int, k: int = 5) -> float:
    """Time-blocked K-fold CV RMSE of y ~ [offsets, x] (contiguous blocks of samples)."""
    design = np.column_stack([offsets, x]) if x.size else offsets
    folds = np.array_split(np.arange(n_samples), k)
    squared, count = 0.0, 0
    for fold in folds:
        test = np.isin(sample_of_row, fold)
        train = ~test
        if test.sum() == 0 or train.sum() <= design.shape[1]:
            continue
        coefficients, *_ = np.linalg.lstsq(design[train], y[train], rcond=None)
        error = design[test] @ coefficients - y[test]
        squared += float(error @ error)
        count += int(test.sum())
    if count == 0:
        raise InsufficientDataError("too few reference readings for cross-validation")
    return float(np.sqrt(squared / count))


EXPLANATIONS = {
    "structural_thermal_drift": "the residual follows the temperature of the {variant} sensor "
                                "in every direction at once, independent of position - the "
                                "structure grows as it warms (Zhu eq. 3.12)",
    "position_dependent_thermal": "the {axis} error grows with the {axis} position times the "
                                  "{sensor} temperature - a structure expanding along the axis "
                                  "relative to its scale (Zhu eq. 3.13)",
    "spindle_thermal_growth": "the z error follows the spindle temperature - the spindle grows "
                              "along the tool axis as it warms",
    "squareness": "the residual grows linearly with the other axes' positions - two axes are "
                  "out of square (location errors {names})",
    "abbe_offset": "the residual follows the measured angular errors times a lever - the tool "
                   "or workpiece is offset from the scales' line (Abbe)",
    "reversal": "the residual jumps with the direction of motion - backlash in the drive",
    "servo_lag": "the residual is proportional to the feed speed - following error",
}


def residuals(model: ErrorModel, obs: Observations) -> NDArray[np.float64]:
    """measured - model (N, 3), each measured component's mean removed.

    Reference instruments measure from a zero reference of their own, so a
    constant offset per component carries no information about the model.
    """
    predicted = obs.predicted_m if obs.predicted_m is not None else \
        model.tcp_error(obs.positions, obs.temperatures, obs.velocities or None,
                        obs.directions or None)[0]
    residual = obs.measured_m - predicted
    for c in range(3):
        measured = obs.measured_mask[:, c]
        if measured.any():
            residual[measured, c] -= residual[measured, c].mean()
    residual[~obs.measured_mask] = 0.0
    return residual


def add_effect(model: ErrorModel, candidate: Candidate, obs: Observations) -> ErrorModel:
    """The next model version holding the fitted candidate (temperatures referenced as in obs)."""
    new = model.with_effect(candidate.effect, model_parameters(candidate))
    for sensor, values in obs.temperatures.items():
        new.reference_temperatures_c.setdefault(sensor, float(np.asarray(values)[0]))
    return new


def diagnose(model: ErrorModel, obs: Observations, *, min_reduction: float = 0.1,
             folds: int = 5) -> Diagnosis:
    """Rank the candidate effects by cross-validated reduction of the residual."""
    if obs.n < 2 * folds:
        raise InsufficientDataError(f"{obs.n} reference readings; need >= {2 * folds}")
    residual = residuals(model, obs)
    mask = obs.measured_mask
    sample_of_row = np.repeat(np.arange(obs.n), 3)[mask.ravel()]
    _, offsets, y = _flatten(np.zeros((obs.n, 3, 0)), residual, mask)
    baseline_cv = blocked_cv(np.zeros((y.size, 0)), offsets, y, sample_of_row, obs.n, folds)
    in_sample = float(np.sqrt(np.mean(residual[mask] ** 2)))
    band = obs.uncertainty_m
    noise_sigma = band / 2.0  # the instrument's k = 2 uncertainty
    candidates: dict[str, Candidate] = {}
    for effect, variant, names, design in candidate_designs(model, obs):
        x, offsets, y = _flatten(design, residual, mask)
        if not np.any(x):
            continue
        cv = blocked_cv(x, offsets, y, sample_of_row, obs.n, folds)
        full = np.column_stack([offsets, x])
        coefficients, *_ = np.linalg.lstsq(full, y, rcond=None)
        dof = max(1, y.size - full.shape[1])
        sigma2 = float(np.sum((full @ coefficients - y) ** 2) / dof)
        try:
            covariance = sigma2 * np.linalg.pinv(full.T @ full)
            standard = np.sqrt(np.clip(np.diag(covariance)[3:], 0.0, None))
        except np.linalg.LinAlgError:
            standard = np.full(len(names), np.inf)
        values = coefficients[3:]
        reduction = 1.0 - cv / baseline_cv if baseline_cv > 0 else 0.0
        # Guard against explaining noise: a real reduction, parameters well above their
        # standard errors, and a residual clearly above the instrument's own noise.
        significant = bool(reduction >= min_reduction and np.any(np.abs(values) > 3 * standard)
                           and in_sample >= 1.5 * noise_sigma)
        axis, _, sensor = variant.partition(":")
        text = EXPLANATIONS[effect].format(variant=variant, axis=axis, sensor=sensor,
                                           names=", ".join(names))
        candidate = Candidate(effect, dict(zip(names, values.tolist())), cv, reduction,
                              significant, text, variant,
                              dict(zip(names, np.broadcast_to(standard, values.shape).tolist())))
        if effect not in candidates or cv < candidates[effect].cv_rmse_after:
            candidates[effect] = candidate
    ranking = sorted(candidates.values(), key=lambda c: c.cv_rmse_after)
    return Diagnosis(in_sample, baseline_cv, float(np.max(np.abs(residual[mask]), initial=0.0)),
                     float(np.mean(np.abs(residual[mask]) > band)) if mask.any() else 0.0,
                     ranking)


def model_parameters(candidate: Candidate) -> dict:
    """The :class:`ErrorModel` parameters of a fitted candidate (to add it to the model)."""
    p = candidate.parameters
    if candidate.effect == "structural_thermal_drift":
        return {"beta_m_per_k": [p["bx"], p["by"], p["bz"]], "sensor": candidate.variant}
    if candidate.effect == "position_dependent_thermal":
        axis, _, sensor = candidate.variant.partition(":")
        return {"axis": axis, "alpha_per_k": p["alpha"], "sensor": sensor, "reference_m": 0.0}
    if candidate.effect == "spindle_thermal_growth":
        return {"m_per_k": p["m_per_k"], "sensor": "spindle", "direction": [0.0, 0.0, 1.0]}
    if candidate.effect == "squareness":
        return {"errors_rad": dict(p)}
    if candidate.effect == "abbe_offset":
        return {"offset_m": [p["ox"], p["oy"], p["oz"]]}
    if candidate.effect == "reversal":
        axes = list(p)
        return {"backlash_m": float(np.mean([p[a] for a in axes])), "axes": axes}
    if candidate.effect == "servo_lag":
        axes = list(p)
        return {"lag_s": float(np.mean([p[a] for a in axes])), "axes": axes}
    raise KeyError(candidate.effect)


# --------------------------------------------------------------------------- yaw
@dataclass
class YawObservations:
    """Scale-pair yaw against a reference (laser) yaw at N readings of one axis.

    ``thermal_per_c`` is (dL1 - dL2)/D computed from the thermocouples with C = 1
    (Kidani eq. 3.17): the relative-expansion term per unit expansion coefficient.
    All yaws relative to the same zero reference [rad].
    """

    axis: str
    scale_yaw: NDArray[np.float64]
    reference_yaw: NDArray[np.float64]
    travel_m: NDArray[np.float64]
    velocity: NDArray[np.float64]
    thermal_per_c: NDArray[np.float64]
    time_s: NDArray[np.float64]
    distance_m: float
    uncertainty_rad: float


YAW_EXPLANATIONS = {
    "scale_thermal_expansion": "the scale yaw drifts from the reference as the two scales' "
                               "temperatures part - one scale expands more than the other "
                               "(Kidani eq. 3.17); parameter: C [1/K]",
    "timing_skew": "the difference is proportional to the feed - the two heads are sampled at "
                   "different instants (Kidani eq. 2.20); parameter: skew [s]",
    "scale_parallelism": "the difference grows linearly with travel - the scales are not "
                         "parallel (Kidani eq. 3.5); parameter: 1/cos(delta) - 1",
}


def yaw_corrections(included: dict[str, float], obs: YawObservations) -> NDArray[np.float64]:
    """The apparent yaw the estimator's corrections remove, for the included effects."""
    out = np.zeros_like(obs.scale_yaw)
    # The pair's linear difference from the laser found at installation (Kidani 3.3.1):
    # relative graduation slope, indistinguishable from parallelism in one run.
    out += included.get("installation_slope", 0.0) * obs.travel_m / obs.distance_m
    if "scale_thermal_expansion" in included:
        out += included["scale_thermal_expansion"] * obs.thermal_per_c
    if "timing_skew" in included:
        out += included["timing_skew"] * obs.velocity / obs.distance_m
    if "scale_parallelism" in included:
        out += included["scale_parallelism"] * obs.travel_m / obs.distance_m
    return out


def diagnose_yaw(included: dict[str, float], obs: YawObservations, *,
                 min_reduction: float = 0.1, folds: int = 5) -> Diagnosis:
    """Rank the scale effects missing from the yaw corrections (same rules as :func:`diagnose`)."""
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
    regressors = {"scale_thermal_expansion": obs.thermal_per_c,
                  "timing_skew": obs.velocity / obs.distance_m,
                  "scale_parallelism": obs.travel_m / obs.distance_m}
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
