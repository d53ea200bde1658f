"""Thermal-model studies on the finite-element element of Zhu Table 3.1 (issue 5).

* :func:`robustness_extrapolation` - train on the first hour, predict the second
  (Zhu 3.4.3, "linear extrapolation");
* :func:`robustness_frequency` - train on a heat cycle of period 20 min, test on
  10 and 40 min (Zhu 3.4.3, "frequency sensitivity");
* :func:`placement_comparison` - modal vs Gaussian vs statistical (exhaustive)
  sensor selection, trained on full and on reduced (every 20th sample) data,
  judged on independent runs (Krulewich Tables 1-2).

All runs are the rod of :func:`~mt_accuracy_ros.core.thermal.fem.rod_model` heated at its fixed end;
the measured thermal error is the free-end expansion epsilon; thermocouples
carry white noise.
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from mt_accuracy_ros.core.thermal.sensor_placement import gauss_points
from mt_accuracy_ros.core.thermal.fem import (ALUMINIUM, ThermalFEModel, ThermalModes,
                                              place_sensors, rod_model, thermal_modes)
from mt_accuracy_ros.core.thermal.regression import fit_linear

#: Nine candidate sensor positions along the element (Zhu Fig. 3.1: positions 1-9), at the
#: centres of nine equal segments - not on the heated end face itself.
CANDIDATE_FRACTIONS = (2 * np.arange(9) + 1) / 18.0
STEP_S = 15.0


@dataclass
class Run:
    """One simulated run: node temperatures (steps, nodes) [K], expansion (steps,) [m]."""

    time_s: np.ndarray
    temperatures: np.ndarray
    expansion_m: np.ndarray


def run(model: ThermalFEModel, modes: ThermalModes, power_w: np.ndarray) -> Run:
    """Response of the element to a heat power history (one value per 15 s step)."""
    heat = np.outer(power_w, model.heat_vector(1.0))
    temperatures = modes.response(heat, STEP_S)
    return Run(np.arange(1, power_w.size + 1) * STEP_S, temperatures,
               model.deformation(temperatures)["expansion"])


def square_wave(period_s: float, duration_s: float, power_w: float = 400.0) -> np.ndarray:
    """Heat on for the first half of each period, off for the second."""
    t = np.arange(int(duration_s / STEP_S)) * STEP_S
    return np.where((t % period_s) < period_s / 2, power_w, 0.0)


def candidate_nodes(model: ThermalFEModel) -> np.ndarray:
    x = model.nodes[:, 0]
    return np.array([int(np.argmin(np.abs(x - f * model.length_m))) for f in CANDIDATE_FRACTIONS])


def modal_sensors(model: ThermalFEModel, modes: ThermalModes,
                  count: int | None = None) -> np.ndarray:
    """Candidate nodes chosen by the modal rule (Zhu 3.3.1), one per dominant mode.

    ``count`` None: as many sensors as modes holding 90 % of the weight (3.2.2).
    """
    candidates = candidate_nodes(model)
    dominant = modes.dominant(model.heat_vector(1.0))
    order = dominant[np.argsort(modes.weights(model.heat_vector(1.0))[dominant])[::-1]]
    chosen = place_sensors(modes, candidates, order, max_sensors=count)
    return candidates[chosen]


def gauss_sensors(model: ThermalFEModel, order: int = 3) -> np.ndarray:
    """Candidate nodes nearest the Gauss points of an order-k field (Krulewich eq. 8)."""
    points, _ = gauss_points(order, model.length_m)
    return model.sensor_nodes(points)


def krulewich_tube() -> ThermalFEModel:
    """Krulewich set-up 1: 305 mm aluminium tube on a granite block, wire heater at 8.75 in.

    Tube section and sink conductance are not published: a 25 mm tube with 2 mm
    wall, h = 10 W/m^2 K, 2 W/K to the granite.
    """
    outer, wall = 0.025, 0.002
    area = np.pi * (outer * wall - wall ** 2)
    return rod_model(length_m=0.305, area_m2=area, n_elements=61, convection_w_m2k=10.0,
                     material=ALUMINIUM, perimeter_m=np.pi * outer, heat_at_m=8.75 * 0.0254,
                     base_conductance_w_k=2.0)


def _measure(r: Run, nodes: np.ndarray, rng: np.random.Generator, noise_k: float) -> np.ndarray:
    return r.temperatures[:, nodes] + rng.normal(0.0, noise_k, (r.time_s.size, nodes.size))


@dataclass
class Robustness:
    train_rmse_m: float
    test_rmse_m: dict[str, float]
    peak_error_m: dict[str, float]
    sensors: np.ndarray


def robustness_extrapolation(noise_k: float = 0.01, seed: int = 0) -> Robustness:
    """Two hours of warm-up, pause and re-heat; fit on hour 1, predict hour 2 (eq. 3.12)."""
    model = rod_model()
    modes = thermal_modes(model)
    t = np.arange(int(7200 / STEP_S)) * STEP_S
    power = np.where((t < 2400) | (t >= 4200), 400.0, 0.0)
    result = run(model, modes, power)
    nodes = modal_sensors(model, modes)
    rng = np.random.default_rng(seed)
    temps = _measure(result, nodes, rng, noise_k)
    first = result.time_s <= 3600
    fit = fit_linear(temps[first], result.expansion_m[first], intercept=False)
    error = fit.predict(temps[~first]) - result.expansion_m[~first]
    return Robustness(fit.train_rmse, {"second_hour": float(np.sqrt(np.mean(error ** 2)))},
                      {"second_hour": float(np.abs(result.expansion_m[~first]).max())}, nodes)


def robustness_frequency(noise_k: float = 0.01, seed: int = 0) -> Robustness:
    """Fit on a 20-min heat cycle, test on 10- and 40-min cycles (Zhu Fig. 3.14)."""
    model = rod_model()
    modes = thermal_modes(model)
    nodes = modal_sensors(model, modes)
    rng = np.random.default_rng(seed)
    train = run(model, modes, square_wave(1200, 4 * 3600))
    fit = fit_linear(_measure(train, nodes, rng, noise_k), train.expansion_m, intercept=False)
    tests, peaks = {}, {}
    for period in (600, 2400):
        other = run(model, modes, square_wave(period, 4 * 3600))
        error = fit.predict(_measure(other, nodes, rng, noise_k)) - other.expansion_m
        tests[f"{period // 60}_min"] = float(np.sqrt(np.mean(error ** 2)))
        peaks[f"{period // 60}_min"] = float(np.abs(other.expansion_m).max())
    return Robustness(fit.train_rmse, tests, peaks, nodes)


@dataclass
class PlacementComparison:
    sensors: dict[str, np.ndarray]              # method -> node indices
    mse_um2: dict[str, dict[str, float]]        # "full"/"reduced" -> method -> total MSE [um^2]
    per_run_um2: dict[str, dict[str, list[float]]]


def placement_comparison(noise_k: float = 0.02, seed: int = 0, n_sensors: int = 2,
                         reduce_every: int = 20) -> PlacementComparison:
    """Krulewich's comparison on the element: which two sensors, how well they predict.

    The element is Krulewich's set-up 1 (:func:`krulewich_tube`). Training run:
    20 min heating at full power, 20 min cooling. Five verification runs at
    equal or lower power and other timings, as his. The
    statistical (exhaustive) method picks the pair with the lowest training
    RMSE among all candidate pairs; the Gaussian method takes the points of an
    order-3 field (n = 2, eq. 8); the modal method Zhu's rule.
    """
    model = krulewich_tube()
    modes = thermal_modes(model)
    rng = np.random.default_rng(seed)
    t = np.arange(int(2400 / STEP_S)) * STEP_S
    training = run(model, modes, np.where(t < 1200, 10.0, 0.0))
    verification = [run(model, modes, np.where((t >= start) & (t < start + length), power, 0.0))
                    for start, length, power in ((0, 1200, 10.0), (300, 900, 8.0),
                                                 (0, 1500, 6.0), (600, 1200, 9.0),
                                                 (0, 600, 10.0))]
    candidates = candidate_nodes(model)
    measured_training = training.temperatures + rng.normal(0, noise_k, training.temperatures.shape)
    measured_verification = [v.temperatures + rng.normal(0, noise_k, v.temperatures.shape)
                             for v in verification]
    sensors = {"modal": modal_sensors(model, modes, n_sensors), "gaussian": gauss_sensors(model)}
    mse: dict[str, dict[str, float]] = {}
    per_run: dict[str, dict[str, list[float]]] = {}
    for label, rows in (("full", slice(None)), ("reduced", slice(None, None, reduce_every))):
        x_all = measured_training[rows]
        y = training.expansion_m[rows]
        best = min(combinations(candidates, n_sensors),
                   key=lambda pair: fit_linear(x_all[:, list(pair)], y).train_rmse)
        chosen = dict(sensors, statistical=np.array(best))
        if label == "full":
            sensors = dict(chosen)
        mse[label], per_run[label] = {}, {}
        for method, nodes in chosen.items():
            fit = fit_linear(x_all[:, nodes], y)
            errors = [float(np.mean(((fit.predict(m[:, nodes]) - v.expansion_m) * 1e6) ** 2))
                      for m, v in zip(measured_verification, verification)]
            per_run[label][method] = errors
            mse[label][method] = float(np.sum(errors))
        sensors[f"statistical_{label}"] = np.array(best)
    return PlacementComparison(sensors, mse, per_run)
