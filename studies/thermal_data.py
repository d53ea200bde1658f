"""Thermal error models on real data: ``data/fl_thermal`` (issue 5).

46 h of a spindle at stepped speeds: 16 temperatures, 5 displacement
channels, 15 s steps. Train on the first half, judge on the second - the
second half holds speeds (5,000 rpm) the first never reached, so this is an
extrapolation test, as a machine's next day is.

Models compared per channel (held-out RMSE [um]):

* ``mean`` - no model: the training mean (the yardstick);
* ``all16`` - eq. 3.12 with every sensor and an intercept;
* ``all16_ridge`` - the same with ridge chosen by time-blocked CV on training;
* ``selected`` - forward selection of <= 4 sensors by time-blocked CV;
* ``lag`` - operating-condition model: first-order responses of spindle speed
  (eq. 3.9) with the three time constants fitted to a temperature record by
  eq. 3.17;
* ``selected+lag`` - both.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mt_accuracy_ros.core.errors import InputDataError
from mt_accuracy_ros.core.thermal.regression import fit_linear, fit_time_constants, lag_features


@dataclass
class ThermalRecord:
    time_s: np.ndarray
    spindle_rpm: np.ndarray
    displacements_um: np.ndarray      # (n, channels)
    temperatures_c: np.ndarray        # (n, sensors)
    channel_names: list[str]
    sensor_names: list[str]


def load_thermal_csv(path: str | Path) -> ThermalRecord:
    """Read ``fl_thermal.csv`` (time_s, spindle_rpm, ch*_um, t*_C)."""
    path = Path(path)
    try:
        data = np.genfromtxt(path, delimiter=",", names=True)
    except (OSError, ValueError) as exc:
        raise InputDataError(f"{path}: cannot read thermal CSV ({exc})") from exc
    names = list(data.dtype.names or [])
    channels = [n for n in names if n.startswith("ch")]
    sensors = [n for n in names if n.startswith("t") and n.endswith("_C")]
    if "time_s" not in names or "spindle_rpm" not in names or not channels or not sensors:
        raise InputDataError(f"{path}: needs time_s, spindle_rpm, ch*_um and t*_C columns")
    return ThermalRecord(data["time_s"], data["spindle_rpm"],
                         np.column_stack([data[c] for c in channels]),
                         np.column_stack([data[s] for s in sensors]), channels, sensors)


def blocked_folds(n: int, k: int = 5) -> list[np.ndarray]:
    """k contiguous blocks of sample indices - CV folds that never interleave in time."""
    return np.array_split(np.arange(n), k)


def blocked_cv_rmse(design: np.ndarray, target: np.ndarray, ridge: float = 0.0,
                    k: int = 5) -> float:
    errors = []
    for fold in blocked_folds(target.size, k):
        train = np.setdiff1d(np.arange(target.size), fold)
        model = fit_linear(design[train], target[train], ridge=ridge)
        errors.append(np.mean((model.predict(design[fold]) - target[fold]) ** 2))
    return float(np.sqrt(np.mean(errors)))


def forward_select(design: np.ndarray, target: np.ndarray, max_terms: int = 4) -> list[int]:
    """Greedy forward selection by time-blocked CV RMSE; stops when CV stops improving."""
    chosen: list[int] = []
    best = float("inf")
    while len(chosen) < max_terms:
        scores = {j: blocked_cv_rmse(design[:, chosen + [j]], target)
                  for j in range(design.shape[1]) if j not in chosen}
        j, score = min(scores.items(), key=lambda item: item[1])
        if score >= best * 0.99:
            break
        chosen.append(j)
        best = score
    return chosen


@dataclass
class StudyResult:
    held_out_rmse_um: dict[str, dict[str, float]]   # model -> channel -> RMSE
    selected_sensors: dict[str, list[str]]          # channel -> sensors
    time_constants_s: np.ndarray
    split_s: float
    predictions: dict[str, dict[str, np.ndarray]] = field(repr=False, default_factory=dict)


def study(record: ThermalRecord, *, train_fraction: float = 0.5,
          max_speed_rpm: float | None = None) -> StudyResult:
    """Train on the first ``train_fraction`` of the record, judge every model on the rest."""
    n = record.time_s.size
    split = int(n * train_fraction)
    train, test = slice(0, split), slice(split, n)
    temps = record.temperatures_c
    speed = record.spindle_rpm / (max_speed_rpm or max(record.spindle_rpm.max(), 1.0))
    # Time constants (eq. 3.17) from the first warm-up of the sensor that rises most.
    start = int(np.argmax(record.spindle_rpm > 0))
    end = start + int(np.argmax(record.spindle_rpm[start:] != record.spindle_rpm[start])) or split
    end = min(end, split)
    rise = temps[start:end] - temps[start]
    sensor = int(np.argmax(np.abs(rise[-1])))
    fit = fit_time_constants(record.time_s[start:end] - record.time_s[start],
                             temps[start:end, sensor])
    lags = lag_features(record.time_s, speed, fit.time_constants_s)
    results: dict[str, dict[str, float]] = {m: {} for m in
                                            ("mean", "all16", "all16_ridge", "selected", "lag",
                                             "selected+lag")}
    predictions: dict[str, dict[str, np.ndarray]] = {m: {} for m in results}
    selected: dict[str, list[str]] = {}
    for c, channel in enumerate(record.channel_names):
        y = record.displacements_um[:, c]

        def judge(name: str, design: np.ndarray | None, ridge: float = 0.0) -> None:
            if design is None:
                prediction = np.full(n - split, y[train].mean())
            else:
                model = fit_linear(design[train], y[train], ridge=ridge)
                prediction = model.predict(design[test])
            predictions[name][channel] = prediction
            results[name][channel] = float(np.sqrt(np.mean((prediction - y[test]) ** 2)))

        judge("mean", None)
        judge("all16", temps)
        ridges = [0.0, 1e-4, 1e-3, 1e-2, 1e-1, 1.0]
        best_ridge = min(ridges, key=lambda r: blocked_cv_rmse(temps[train], y[train], r))
        judge("all16_ridge", temps, best_ridge)
        chosen = forward_select(temps[train], y[train])
        selected[channel] = [record.sensor_names[j] for j in chosen]
        judge("selected", temps[:, chosen])
        judge("lag", lags)
        judge("selected+lag", np.column_stack([temps[:, chosen], lags]))
    return StudyResult(results, selected, fit.time_constants_s, float(record.time_s[split]),
                       predictions)
