"""Thermal FE model and modal analysis (Zhu 3.2) against closed forms and direct integration."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import InputDataError, ParameterError
from mt_accuracy_ros.core.thermal.fem import (ZHU_TABLE_3_1, beam_model, integrate_directly,
                                              place_sensors, rod_model, thermal_modes)


def test_rod_time_constants_match_the_analytic_series():
    """Insulated ends, lateral convection: lambda_n = hP/(rho c A) + kappa (n pi / L)^2."""
    model = rod_model(n_elements=400, end_convection_w_m2k=0.0)
    modes = thermal_modes(model, n_modes=4)
    m = ZHU_TABLE_3_1
    perimeter = 2 * np.sqrt(np.pi * 0.0314)
    kappa = m.conductivity / (m.density * m.specific_heat)
    expected = 20 * perimeter / (m.density * m.specific_heat * 0.0314) + \
        kappa * (np.arange(4) * np.pi / 1.0) ** 2
    np.testing.assert_allclose(modes.eigenvalues, expected, rtol=1e-4)


def test_table_3_1_rod_and_beam_time_constants():
    """The numbers docs/thermal.md reports for Zhu's 22-element element."""
    rod = thermal_modes(rod_model())
    np.testing.assert_allclose(rod.time_constants_s[:3] / 60, [134.9, 54.4, 19.8], atol=0.1)
    beam = thermal_modes(beam_model())
    np.testing.assert_allclose(beam.time_constants_s[:3] / 60, [86.4, 44.3, 18.3], atol=0.1)


def test_modes_are_c_orthonormal_and_diagonalise_k():
    model = beam_model(n_elements=10, n_layers=3)
    modes = thermal_modes(model)
    phi = modes.shapes
    np.testing.assert_allclose(phi.T @ model.capacity @ phi, np.eye(phi.shape[1]),
                               atol=1e-10)  # Zhu eq. 3.6
    np.testing.assert_allclose(phi.T @ model.conductivity @ phi, np.diag(modes.eigenvalues),
                               atol=1e-9 * modes.eigenvalues.max())  # 3.7


@pytest.mark.parametrize("factory", [rod_model, beam_model])
def test_modal_response_equals_direct_integration(factory):
    model = factory()
    modes = thermal_modes(model)
    t = np.arange(240) * 30.0
    power = np.where((t % 2400) < 1200, 300.0, 0.0)
    heat = np.outer(power, model.heat_vector(1.0))
    modal = modes.response(heat, 30.0)                 # eqs. 3.4, 3.9 exact per step
    direct = integrate_directly(model, heat, 30.0, substeps=30)   # eq. 3.1, Crank-Nicolson
    assert np.abs(modal - direct).max() <= 2e-4 * np.abs(direct).max()
    step = modes.step_response(model.heat_vector(300.0), t[1:])  # eq. 3.10
    constant = modes.response(np.tile(model.heat_vector(300.0), (t.size - 1, 1)), 30.0)
    np.testing.assert_allclose(step, constant, atol=1e-9 * np.abs(step).max())


def test_sparse_and_dense_eigensolvers_agree():
    dense = thermal_modes(rod_model(n_elements=600), n_modes=5)
    sparse = thermal_modes(rod_model(n_elements=600, sparse=True), n_modes=5)
    np.testing.assert_allclose(sparse.eigenvalues, dense.eigenvalues, rtol=1e-9)


def test_weights_truncation_and_placement():
    model = rod_model()
    modes = thermal_modes(model)
    q = model.heat_vector(100.0)
    weights = modes.weights(q)
    np.testing.assert_allclose(weights, np.abs((q @ modes.shapes) * modes.time_constants_s))  # 3.11
    dominant = modes.dominant(q)
    share = weights[dominant].sum() / weights.sum()
    assert share >= 0.9 and weights[dominant[:-1]].sum() / weights.sum() < 0.9
    candidates = np.array([1, 4, 6, 9, 11, 13, 16, 18, 21])
    chosen = place_sensors(modes, candidates, dominant)
    assert len(chosen) == dominant.size and len(set(chosen)) == len(chosen)
    # Never at a node: each sensor sees its mode at >= 80 % of the mode's best candidate.
    for mode, index in zip(dominant, chosen):
        column = np.abs(modes.shapes[candidates, mode])
        assert column[index] >= 0.8 * column.max()


def test_beam_bends_towards_the_cooler_face_and_expands():
    model = beam_model()
    modes = thermal_modes(model)
    hot = modes.step_response(model.heat_vector(100.0), [7200.0])
    deformation = model.deformation(hot)
    assert deformation["expansion"][0] > 0
    # The lower face loses heat five times faster (100 vs 20 W/m^2K): the upper face
    # is hotter and longer, so the free end bends down (negative delta and theta).
    assert deformation["deflection"][0] < 0 and deformation["slope"][0] < 0
    # Uniform 1 K: pure expansion alpha L, no bending.
    uniform = model.deformation(np.ones(model.n_nodes))
    assert uniform["expansion"] == pytest.approx(10.8e-6)
    assert abs(uniform["deflection"]) < 1e-18 and abs(uniform["slope"]) < 1e-18


def test_bad_parameters_and_models_without_losses():
    with pytest.raises(ParameterError):
        rod_model(length_m=-1.0)
    with pytest.raises(ParameterError):
        rod_model(heat_at_m=2.0)
    with pytest.raises(InputDataError, match="outside the rod"):
        rod_model().sensor_nodes([0.5, 1.2])
    with pytest.raises(InputDataError, match="outside the beam"):
        beam_model().sensor_nodes([0.5], y_m=0.5)
    assert rod_model().sensor_nodes([0.0, 0.5, 1.0]).tolist() == [0, 11, 22]
    with pytest.raises(InputDataError, match="no heat loss"):
        thermal_modes(rod_model(convection_w_m2k=0.0))
