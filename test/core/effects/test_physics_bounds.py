"""Physics bounds every fitted parameter (issue 26): a fit outside its family's range is
refused with the reason, the same effect inside it is named; user effects declare
their bounds in the model YAML; a periodic finding claims no more than it explains."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel, model_from_dict
from mt_accuracy_ros.core.effects.physics import (GENEROUS_CTE_PER_K, structure_length_m,
                                                  thermal_gain_limit_m_per_k)
from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.core.kinematics.machine import load_machine
from mt_accuracy_ros.core.workbench.diagnosis import Observations, diagnose

MACHINE = load_machine("kidani_hmc")
NOISE = 0.5e-6


def _survey(gain_m_per_k: float, seed: int = 3, n: int = 300):
    """A warm-up of the bed sensor (1.5 K over 40 min) and a TCP drift following it - the
    truth written here, independently of the workbench's design matrices."""
    rng = np.random.default_rng(seed)
    positions = {a: rng.uniform(*MACHINE.axes[a].stroke, n) for a in "XYZ"}
    t = np.arange(n) * 8.0
    bed = 20.0 + 1.5 * (1.0 - np.exp(-t / 900.0)) + rng.normal(0, 0.01, n)
    truth = np.zeros((n, 3))
    truth[:, 1] = gain_m_per_k * (bed - bed[0])
    measured = truth + rng.normal(0, NOISE, truth.shape)
    return Observations(positions, measured, np.ones((n, 3), bool), t,
                        temperatures={"bed": bed}, uncertainty_m=2 * NOISE)


def test_the_thermal_gain_bound_is_the_free_expansion_of_the_structure():
    # Kidani HMC: strokes 0.39 + 0.44 + 0.495 m, offsets, tool 0.15 m and workpiece 0.05 m.
    length = (0.39 + 0.44 + 0.495 + np.linalg.norm([0, 0.35, -0.15])
              + np.linalg.norm([0.12, 0, 0.45]) + np.linalg.norm([0, 0.6, 0.2]) + 0.15 + 0.05)
    assert structure_length_m(MACHINE) == pytest.approx(length, rel=1e-12)
    assert thermal_gain_limit_m_per_k(MACHINE) == pytest.approx(GENEROUS_CTE_PER_K * length)


def test_a_plausible_thermal_drift_is_named():
    diagnosis = diagnose(ErrorModel(MACHINE, {}), _survey(5e-6))
    assert diagnosis.selected and diagnosis.selected[0].name == \
        "structural_thermal_drift:bed"
    assert diagnosis.selected[0].parameters["by"] == pytest.approx(5e-6, rel=0.05)
    assert not diagnosis.selected[0].refusal


def test_a_gain_beyond_free_expansion_is_refused_and_said():
    # 1 mm/K: ten times what 3 m of aluminium could do. It fits the data perfectly, but no
    # structure behaves so: the workbench refuses it and says why.
    diagnosis = diagnose(ErrorModel(MACHINE, {}), _survey(1e-3))
    assert all(c.effect not in ("structural_thermal_drift", "thermal_lag")
               for c in diagnosis.selected)
    drift = next(c for c in diagnosis.ranking if c.name == "structural_thermal_drift:bed")
    assert "exceeds" in drift.refusal and "free expansion" in drift.refusal
    assert not drift.significant and drift.confidence == 0.0
    assert "refused by physics" in diagnosis.text() or diagnosis.selected


def test_user_effects_declare_their_bounds_in_the_model_yaml():
    def model(bound):
        return model_from_dict({"machine": "kidani_hmc", "effects": {"bed_growth": {
            "expression": "k * T_bed", "parameters": ["k"], "acts_on": "y",
            "bounds": {"k": bound}}}})

    obs = _survey(5e-6)
    named = diagnose(model(1e-4), obs)
    assert [c.variant for c in named.selected][:1] == ["bed_growth"]
    refused = diagnose(model(1e-6), obs)   # the user says: at most 1 um/K
    entry = next(c for c in refused.ranking if c.variant == "bed_growth")
    assert "the bound declared with the effect" in entry.refusal
    assert "bed_growth" not in [c.variant for c in refused.selected]
    with pytest.raises(ParameterError, match="bounds"):
        model_from_dict({"machine": "kidani_hmc", "effects": {"g": {
            "expression": "k * T_bed", "parameters": ["k"], "bounds": {"q": 1.0}}}})


def test_a_periodic_peak_claims_no_more_amplitude_than_its_share_supports():
    rng = np.random.default_rng(5)
    n = 400
    positions = {a: rng.uniform(*MACHINE.axes[a].stroke, n) for a in "XYZ"}
    measured = rng.normal(0, NOISE, (n, 3))
    measured[:, 2] += 3e-6 * np.sin(2 * np.pi * positions["X"] / 0.012)
    obs = Observations(positions, measured, np.ones((n, 3), bool), np.arange(n) * 10.0,
                       uncertainty_m=2 * NOISE)
    where = diagnose(ErrorModel(MACHINE, {}), obs).localisation
    for peak in where.peaks:
        variance = where.component_rms[peak.component] ** 2
        assert peak.amplitude <= np.sqrt(2 * peak.share * variance) * (1 + 1e-12)
    top = where.peaks[0]
    assert (top.axis, top.component) == ("X", "z")
    assert "z component repeats every 12.0 mm of X travel" in where.sentence()
