"""Headline figures and their uncertainty against closed forms."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.workbench.statistics import format_with_uncertainty, rms_with_uncertainty


def test_rms_uncertainty_matches_the_normal_closed_form():
    sigma, n, u_k2 = 2.0e-6, 2000, 1.0e-6
    values = np.random.default_rng(4).normal(0.0, sigma, n)
    figure = rms_with_uncertainty(values, u_k2)
    assert figure.rms == pytest.approx(np.sqrt(np.mean(values ** 2)), rel=1e-12)
    # Zero-mean normal: s(RMS) -> sigma / sqrt(2 N); plus the instrument u / sqrt(N).
    expected = 2 * np.sqrt(sigma ** 2 / (2 * n) + (u_k2 / 2) ** 2 / n)
    assert figure.rms_u_k2 == pytest.approx(expected, rel=0.15)
    assert figure.max_abs == pytest.approx(np.max(np.abs(values)))
    assert figure.count == n


def test_rms_uncertainty_is_seeded_and_grows_with_the_instrument():
    values = np.random.default_rng(1).normal(0, 1e-6, 50)
    assert rms_with_uncertainty(values, 1e-6) == rms_with_uncertainty(values, 1e-6)
    assert rms_with_uncertainty(values, 5e-6).rms_u_k2 > rms_with_uncertainty(values, 1e-6).rms_u_k2


@pytest.mark.parametrize("value,u,text", [(4.7809, 0.312, "4.78 ± 0.31 µm (k = 2)"),
                                          (12.3, 2.6, "12.3 ± 2.6 µm (k = 2)"),
                                          (0.58512, 0.0473, "0.585 ± 0.047 µm (k = 2)")])
def test_values_are_rounded_to_their_uncertainty(value, u, text):
    assert format_with_uncertainty(value, u, "µm") == text


def test_a_stated_uncertainty_is_taken_and_none_stated_takes_the_documented_default_said():
    from mt_accuracy_ros.core.workbench.statistics import (DEFAULT_POSITION_UNCERTAINTY_M,
                                                           stated_uncertainty)

    assert stated_uncertainty([2e-6, 2e-6, 3e-6], 1e-6, "x", "m") == (2e-6, "")
    # Most readings state none: the median of those that do, not a zero band.
    assert stated_uncertainty([0.0, 0.0, 4e-6], 1e-6, "x", "m") == (4e-6, "")
    value, note = stated_uncertainty([0.0, 0.0], DEFAULT_POSITION_UNCERTAINTY_M,
                                     "reference readings", "m")
    assert value == DEFAULT_POSITION_UNCERTAINTY_M == 1e-6
    assert note == "reference readings: the readings state no uncertainty (0); 1e-06 m (k = 2) " \
                   "assumed"
    assert stated_uncertainty([], 2e-6, "tool direction", "rad")[0] == 2e-6
