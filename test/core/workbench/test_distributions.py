"""The workbench's own tail probabilities against scipy.stats (a second formulation)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from mt_accuracy_ros.core.workbench.distributions import chi2_sf, t_sf


@pytest.mark.parametrize("dof", [1, 2, 3, 4, 7, 19, 59, 400, 3000, 299999])
def test_chi2_sf_equals_scipy(dof):
    for q in (1e-9, 0.001, 0.1, 0.5, 0.9, 0.999, 1 - 1e-9):
        value = float(stats.chi2.ppf(q, dof))
        assert chi2_sf(value, dof) == pytest.approx(float(stats.chi2.sf(value, dof)),
                                                    rel=1e-9, abs=1e-15)
    assert chi2_sf(0.0, dof) == 1.0


@pytest.mark.parametrize("dof", [1, 2, 3, 5, 19, 59, 1000])
def test_t_sf_equals_scipy(dof):
    for value in np.concatenate([np.linspace(-8, 8, 41), [1e-12, 40.0, -40.0]]):
        assert t_sf(float(value), dof) == pytest.approx(float(stats.t.sf(value, dof)),
                                                        rel=1e-10, abs=1e-300)
    assert t_sf(np.inf, dof) == 0.0 and t_sf(-np.inf, dof) == 1.0


def test_the_workbench_does_not_import_scipy_stats():
    """Importing scipy.stats costs ~0.5 s, more than a small check: the engine avoids it."""
    import subprocess
    import sys

    code = ("import sys; import mt_accuracy_ros.core.workbench.diagnosis; "
            "print('scipy.stats' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True).stdout.strip()
    assert out == "False"


@pytest.mark.parametrize("function, low, high", [
    (lambda x: (x - 0.3) ** 2, 0.0, 1.0),
    (lambda x: -np.sinc(8.0 * (x - 0.0123)) ** 2, 0.0, 0.1),        # a periodogram-like peak
    (lambda x: np.exp(x), -1.0, 2.0),                                 # minimum on the bound
    (lambda x: np.cos(3 * x) + 0.1 * x, 0.5, 1.6),
])
def test_minimise_bounded_equals_scipy(function, low, high):
    from scipy.optimize import minimize_scalar

    from mt_accuracy_ros.core.workbench.line_search import minimise_bounded

    tolerance = (high - low) * 1e-8
    x, fx = minimise_bounded(function, low, high, x_tolerance=tolerance)
    reference = minimize_scalar(function, bounds=(low, high), method="bounded",
                                options={"xatol": tolerance})
    assert x == pytest.approx(reference.x, abs=10 * tolerance)
    assert fx == pytest.approx(function(x))
    assert fx <= reference.fun + 1e-12
