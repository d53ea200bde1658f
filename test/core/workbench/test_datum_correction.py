"""The model's own error at its datum: what its calibration knows there, and what a refit
from the datum makes of a constant the calibration missed.

An instrument zeroed at the datum reads e(q) - e(datum); a calibrated model refers its
error to what its tables give at the datum, known only to the calibration's uncertainty.
Refitted without that, the one constant the tables missed there goes into a drift's gain
over a warm-up (and is extrapolated beyond it); refitted within the stated uncertainty, the
gain and the constant both come back. Truth written out here, not by the package."""
from __future__ import annotations

import copy

import numpy as np
import pytest
import yaml

from mt_accuracy_ros.core.compensation.datum import calibration_uncertainty_at
from mt_accuracy_ros.core.compensation.error_model import (ErrorModel, model_from_dict,
                                                           model_to_dict)
from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.core.kinematics.chain import KinematicModel
from mt_accuracy_ros.core.kinematics.machine import (BUNDLED_MACHINES, load_machine,
                                                     machine_from_dict)
from mt_accuracy_ros.core.workbench.diagnosis import Observations
from mt_accuracy_ros.core.workbench.refit import prior_fit, refit_effects

MACHINE = load_machine("kidani_hmc")
NOISE = 0.5e-6
BETA = np.array([1.0e-6, 2.0e-6, 3.0e-6])      # column drift [m/K]
#: The calibration's error at the datum [m]: the model's tables there off by this much.
MISSED = np.array([0.45e-6, -0.30e-6, 0.20e-6])
DATUM = {"X": 0.2, "Y": -0.2, "Z": 0.25}


def _vmc_with_tables(rng: np.random.Generator) -> dict:
    """The bundled VMC's description with a calibrated table of every motion error and
    the squareness of Y and Z - a calibration's shape, values drawn here."""
    data = yaml.safe_load((BUNDLED_MACHINES / "vmc.yaml").read_text())
    for letter, spec in data["axes"].items():
        low, high = spec["stroke"]
        grid = np.linspace(low, high, 21)
        spec["errors"] = {f"E{c}{letter}": {"table": {
            "positions": grid.tolist(),
            "values": (rng.normal(0.0, 2e-6 if c in "XYZ" else 5e-6, grid.size)).tolist()}}
            for c in "XYZABC"}
    data["axes"]["Y"]["location_errors"] = {"EC0Y": 8e-6}
    data["axes"]["Z"]["location_errors"] = {"EA0Z": -5e-6, "EB0Z": 3e-6}
    return data


LINEAR_U, ANGULAR_U, SQUARENESS_U = 0.4e-6, 0.6e-6, 1.0e-6


def _table_u(name: str, position: float) -> float:
    return ANGULAR_U if name[1] in "ABC" else LINEAR_U


def test_the_datum_uncertainty_is_each_table_carried_through_its_lever():
    """Closed form on a chain of one rotation-free branch: a table of the Z head acts at
    the tool point through the lever from the head's frame; summed in quadrature."""
    data = _vmc_with_tables(np.random.default_rng(1))
    machine = machine_from_dict(data, "vmc with tables")
    datum = {"Y": 0.05, "X": -0.1, "Z": -0.3}
    got = calibration_uncertainty_at(machine, datum, _table_u, SQUARENESS_U)
    # By hand, from the machine's own frames (each axis' frame origin and the tool point):
    frames = KinematicModel(machine).error_frames({a: np.array([v]) for a, v in datum.items()})
    variance = np.zeros(3)
    for name, (sign, rotation, lever) in frames.items():
        axis, component = name[-1], name[1]
        calibrated = name[2] != "0" and not machine.axes[axis].motion_errors[component].is_zero
        square = name[2] == "0" and component in machine.axes[axis].location_errors
        if not (calibrated or square):
            continue
        u = (SQUARENESS_U if square else _table_u(name, 0.0)) / 2.0
        if component in "XYZ":
            variance += (u * np.eye(3)["XYZ".index(component)]) ** 2   # no frame turns here
        else:
            unit = np.eye(3)["ABC".index(component)]
            variance += (u * np.cross(unit, lever[0])) ** 2
    np.testing.assert_allclose(got, 2.0 * np.sqrt(variance), rtol=1e-12)
    # Every table adds: more than the three positioning tables alone.
    assert np.all(got > LINEAR_U)


def test_the_datum_uncertainty_agrees_with_perturbed_calibrations():
    """A second formulation: calibrations drawn within their uncertainty (each table off
    by a constant, each squareness by its own), the datum's error from the full chain
    (matrix products, not the first-order frames); their spread is the stated U / 2."""
    rng = np.random.default_rng(2)
    data = _vmc_with_tables(rng)
    machine = machine_from_dict(data, "vmc with tables")
    datum = {"Y": -0.12, "X": 0.25, "Z": -0.4}
    stated = calibration_uncertainty_at(machine, datum, _table_u, SQUARENESS_U)
    pose = {a: np.array([v]) for a, v in datum.items()}
    draws = []
    for _ in range(600):
        drawn = copy.deepcopy(data)
        for letter, spec in drawn["axes"].items():
            for name, entry in spec["errors"].items():
                shift = rng.normal(0.0, _table_u(name, 0.0) / 2.0)
                entry["table"]["values"] = [v + shift for v in entry["table"]["values"]]
            for name in spec.get("location_errors", {}):
                spec["location_errors"][name] += rng.normal(0.0, SQUARENESS_U / 2.0)
        draws.append(KinematicModel(machine_from_dict(drawn)).tcp_error(pose)["position"][0])
    spread = np.std(np.array(draws), axis=0, ddof=1)
    # 600 draws: the spread within 12 % of its value (about 4 of its standard errors).
    np.testing.assert_allclose(spread, stated / 2.0, rtol=0.12)


def _warm_up(seed: int, n: int = 240) -> tuple[Observations, np.ndarray]:
    """An instrument zeroed at the datum, cold; the column warms (3 K, tau 30 s) over a
    90 s record read every 0.37 s; the model's tables miss ``MISSED`` at the datum, so
    every reading holds -MISSED beside the drift."""
    rng = np.random.default_rng(seed)
    positions = {a: rng.uniform(*MACHINE.axes[a].stroke, n) for a in "XYZ"}
    t = np.arange(n) * 0.37
    rise = 3.0 * (1.0 - np.exp(-t / 30.0))
    measured = rise[:, None] * BETA[None, :] - MISSED[None, :] + rng.normal(0.0, NOISE, (n, 3))
    obs = Observations(positions, measured, np.ones((n, 3), bool), t,
                       temperatures={"column": 20.0 + rise}, uncertainty_m=2 * NOISE)
    return obs, rise


def _named_early(stated: np.ndarray | None) -> ErrorModel:
    """The model after the drift was named on the first third: right gains (as if the
    search had been lucky), the datum's constant not known."""
    entry = {"family": "structural_thermal_drift", "variant": "column", "setting": {},
             "coefficients": dict(zip(("bx", "by", "bz"), map(float, BETA))),
             "uncertainties": {"bx": 0.2e-6, "by": 0.2e-6, "bz": 0.2e-6}}
    return ErrorModel(MACHINE, {"structural_thermal_drift:column": entry},
                      reference_temperatures_c={"column": 20.0}, datum=dict(DATUM),
                      datum_uncertainty_m=stated)


def test_a_refit_from_the_datum_keeps_the_drift_and_finds_what_the_calibration_missed():
    obs, rise = _warm_up(3)
    exact = refit_effects(_named_early(None), obs)
    stated = refit_effects(_named_early(np.full(3, 0.5e-6)), obs)
    assert exact.datum is None and stated.datum is not None
    drift = lambda r: next(c for c in r.candidates  # noqa: E731
                           if c.name == "structural_thermal_drift:column")
    # Taken as exact, the datum's constant goes into the gains: each moves by about
    # -MISSED over the rise's weighted mean (least squares of a constant on the rise).
    pulled = -MISSED * np.sum(rise) / np.sum(rise ** 2)
    for k, name in enumerate(("bx", "by", "bz")):
        moved = drift(exact).parameters[name] - BETA[k]
        assert moved == pytest.approx(pulled[k], abs=3 * drift(exact).parameter_uncertainties[name])
        assert abs(moved) > 3 * drift(exact).parameter_uncertainties[name] or k == 2
    # Within the stated uncertainty both come back: the gains within 3 standard
    # uncertainties of the truth, the constant within 3 of its own.
    for k, name in enumerate(("bx", "by", "bz")):
        assert abs(drift(stated).parameters[name] - BETA[k]) < \
            3 * drift(stated).parameter_uncertainties[name], (name, drift(stated).parameters)
    np.testing.assert_array_less(np.abs(stated.datum.new - MISSED), 3 * stated.datum.uncertainty)
    # The refit made live carries it; its referred error then holds the constant.
    live = stated.apply(_named_early(np.full(3, 0.5e-6)), obs)
    np.testing.assert_allclose(live.datum_correction_m, stated.datum.new)
    cold = {a: np.array([DATUM[a]]) for a in "XYZ"}
    at_datum, _ = live.tcp_error(cold, {"column": np.array([20.0])})
    np.testing.assert_allclose(at_datum[0], -stated.datum.new, atol=1e-15)
    assert "the model's error at the datum corrected by (" in stated.sentence()
    # The end of the record, extrapolated: the stated refit's error there is the noise's.
    end = slice(-80, None)
    late = obs.subset(np.arange(obs.n)[end])
    for refit, model in ((stated, _named_early(np.full(3, 0.5e-6))),
                         (exact, _named_early(None))):
        predicted = refit.apply(model, obs).tcp_error(late.positions, **late.model_inputs(),
                                                      fresh=True)[0]
        refit.end_rms = np.sqrt(np.mean((late.measured_m - predicted) ** 2, axis=0))
    assert np.all(stated.end_rms < 1.15 * NOISE), stated.end_rms
    assert exact.end_rms[0] > stated.end_rms[0]


def test_the_prior_is_the_bayesian_posterior_mean():
    """The penalised solve against the Gaussian posterior written out: (X'X + L) b =
    X'y + L m, L the prior's precision on its columns."""
    rng = np.random.default_rng(5)
    x = rng.normal(size=(50, 4))
    y = x @ np.array([0.3, -1.0, 2.0, 0.5]) + rng.normal(0.0, 0.1, 50)
    precision, mean = np.array([4.0, 9.0]), np.array([1.0, -2.0])
    got, standard = prior_fit(x, y, [], (precision, mean))
    a = x.T @ x + np.diag(np.r_[precision, 0.0, 0.0])
    want = np.linalg.solve(a, x.T @ y + np.r_[precision * mean, 0.0, 0.0])
    np.testing.assert_allclose(got, want, rtol=1e-10)
    assert np.all(standard > 0)


def test_the_datum_keys_round_trip_and_refuse_what_is_no_calibration():
    model = ErrorModel(MACHINE, datum=dict(DATUM), datum_uncertainty_m=[0.5e-6, 0.5e-6, 0.4e-6],
                       datum_correction_m=[0.3e-6, -0.1e-6, 0.0])
    data = model_to_dict(model)
    assert data["datum_uncertainty_m"] == [0.5e-6, 0.5e-6, 0.4e-6]
    assert data["datum_correction_m"] == [0.3e-6, -0.1e-6, 0.0]
    again = model_from_dict(data)
    np.testing.assert_array_equal(again.datum_correction_m, model.datum_correction_m)
    np.testing.assert_array_equal(again.datum_uncertainty_m, model.datum_uncertainty_m)
    # Nothing stated: nothing written, the datum's error taken as exact.
    plain = model_to_dict(ErrorModel(MACHINE, datum=dict(DATUM)))
    assert "datum_uncertainty_m" not in plain and "datum_correction_m" not in plain
    for bad, match in (({"datum_correction_m": [1e-6, 0.0]}, "three finite"),
                       ({"datum_correction_m": [2e-3, 0.0, 0.0]}, "within 1 mm"),
                       ({"datum_uncertainty_m": [-1e-6, 0.0, 0.0]}, "non-negative"),
                       ({"datum_uncertainty_m": "0.5 um"}, "three finite")):
        with pytest.raises(ParameterError, match=match):
            model_from_dict({"machine": "kidani_hmc", "datum": dict(DATUM), **bad})
    with pytest.raises(ParameterError, match="give the datum"):
        model_from_dict({"machine": "kidani_hmc", "datum_correction_m": [1e-6, 0.0, 0.0]})
