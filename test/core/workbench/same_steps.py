"""One assertion shared by the selection tests: two selections took the same steps."""
from __future__ import annotations

import numpy as np
import pytest


def assert_same_steps(steps, expected, coefficients: bool = False) -> None:
    """The same terms added, every ranking in the same order with CV scores within 1e-12
    (and, with ``coefficients``, every candidate's coefficients within 1e-9)."""
    assert [s.added and s.added.term.name for s in steps] == \
        [s.added and s.added.term.name for s in expected]
    for a, b in zip(steps, expected):
        assert [s.term.name for s in a.ranking] == [s.term.name for s in b.ranking]
        assert [s.cv_rmse for s in a.ranking] == pytest.approx([s.cv_rmse for s in b.ranking],
                                                               rel=1e-12)
        if coefficients:
            for s, t in zip(a.ranking, b.ranking):
                np.testing.assert_allclose(
                    s.coefficients, t.coefficients, rtol=1e-9,
                    atol=1e-12 * np.abs(t.coefficients).max(initial=1e-30))
