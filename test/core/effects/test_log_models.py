"""What a thermal engineer fits to a log: grey relational grades, correlated groups, sensor
sets and principal components (issue 40)."""
from __future__ import annotations

import numpy as np
import pytest
import yaml

from mt_accuracy_ros.core.compensation.error_model import ErrorModel, model_to_dict
from mt_accuracy_ros.core.effects import Context, families
from mt_accuracy_ros.core.effects.log_models import (SensorLeastSquares, TemperatureComponents,
                                                     correlation_clusters,
                                                     grey_relational_grades, sensor_groups)
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.workbench.diagnosis import Observations, candidate_terms
from mt_accuracy_ros.core.workbench.thermal_log import log_model, log_observations


def test_grey_relational_grades_by_hand():
    # Deng's grade with rho = 0.5 (worked in the test's docstring terms): x1 equals the
    # reference (grade 1); x3 = [0, 1, 0.5]: deltas [0, .5, .5], d_max .5, xi = [1, 1/3, 1/3]
    # -> 5/9; reversed they relate less (4/9 for x3), so the larger is kept.
    grades = grey_relational_grades(np.array([0.0, 0.5, 1.0]),
                                    np.array([[0.0, 0.5, 1.0], [0.0, 1.0, 0.5]]))
    assert grades == pytest.approx([1.0, 5.0 / 9.0], abs=1e-12)
    # A sensor falling as the error rises is related too (its reverse equals it).
    assert grey_relational_grades(np.array([0.0, 0.5, 1.0]),
                                  np.array([[2.0, 1.0, 0.0]]))[0] == pytest.approx(1.0)


def test_sensors_that_move_together_are_grouped_and_the_most_related_represents_them():
    rng = np.random.default_rng(0)
    slow, fast = rng.normal(0, 1, 300).cumsum(), rng.normal(0, 1, 300).cumsum()
    t = {"a1": slow, "a2": slow + rng.normal(0, 0.5, 300),
         "b1": fast, "b2": fast + rng.normal(0, 0.5, 300)}
    labels = correlation_clusters(np.array([t[k] for k in sorted(t)]), 2)
    assert labels[0] == labels[1] and labels[2] == labels[3] and labels[0] != labels[2]
    error = 2.0 * slow - 1.0 * fast
    groups = sensor_groups(t, error, counts=range(2, 3))
    grades = dict(zip(sorted(t), grey_relational_grades(error, np.array([t[k] for k in
                                                                          sorted(t)]))))
    expected = "+".join(sorted([max(("a1", "a2"), key=grades.get),
                                max(("b1", "b2"), key=grades.get)]))
    assert list(groups) == [expected] and "grey relational grade" in groups[expected]


def _log(n: int = 200):
    rng = np.random.default_rng(4)
    time_s = np.arange(n) * 60.0
    base = rng.normal(0, 0.1, (n, 4)).cumsum(axis=0) + 20.0
    temperatures = {f"t{k}": base[:, k] for k in range(4)}
    target = 1e-6 * (3.0 * (base[:, 0] - base[0, 0]) - 2.0 * (base[:, 2] - base[0, 2]))
    return log_observations(time_s, target, temperatures)


def test_principal_components_two_formulations_and_a_model_that_keeps_them():
    obs = _log()
    model = log_model(obs)
    ctx = Context(model.machine, obs.variables(model.reference_temperatures_c))
    family = TemperatureComponents()
    (setting,) = family.settings(ctx, "2")
    scores = family.design(ctx, "2", setting)[:, 2, 2::3]         # bz_pc1, bz_pc2 (N, 2)
    # Second formulation: the eigenvectors of the sensors' correlation matrix.
    t = np.column_stack([obs.temperatures[s] for s in sorted(obs.temperatures)])
    z = (t - t.mean(axis=0)) / t.std(axis=0)
    values, vectors = np.linalg.eigh(np.corrcoef(t, rowvar=False))
    reference = z @ vectors[:, np.argsort(values)[::-1][:2]]
    for j in range(2):
        assert abs(np.corrcoef(scores[:, j], reference[:, j])[0, 1]) == pytest.approx(1.0,
                                                                                   abs=1e-12)
    # Kept in a model (YAML), the same columns evaluate later.
    entry = {"family": family.name, "variant": "2", "setting": setting,
             "coefficients": {"bx_pc1": 0.0, "by_pc1": 0.0, "bz_pc1": 1e-6,
                              "bx_pc2": 0.0, "by_pc2": 0.0, "bz_pc2": -2e-6}}
    fitted = model.with_effect("temperature_components:2", entry)
    stored = yaml.safe_load(yaml.safe_dump(model_to_dict(fitted)))
    again = ErrorModel(model.machine, stored["effects"])
    again.reference_temperatures_c.update(stored["reference_temperatures_c"])
    first = fitted.tcp_error(obs.positions, **obs.model_inputs(), fresh=True)[0]
    second = again.tcp_error(obs.positions, **obs.model_inputs(), fresh=True)[0]
    assert np.allclose(first, second, rtol=0, atol=1e-15)
    assert np.allclose(first[:, 2], scores @ [1e-6, -2e-6], rtol=0, atol=1e-15)


def test_log_models_are_candidates_only_where_a_log_asks_for_them():
    obs = _log()
    model = log_model(obs)
    ctx = Context(model.machine, obs.variables(model.reference_temperatures_c))
    assert not [t for t in candidate_terms(model, ctx) if t.family.log_only]
    asked = [f for f in families() if not f.log_only] + \
        [SensorLeastSquares({"t0+t2": "by hand"}), TemperatureComponents()]
    names = {t.name for t in candidate_terms(model, ctx, asked)}
    assert {"sensor_least_squares:t0+t2", "temperature_components:1",
            "temperature_components:3"} <= names
    assert isinstance(obs, Observations) and isinstance(ctx.variables, Variables)
