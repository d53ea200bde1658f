"""A model version judged at the machine (issue 26): worse beyond the uncertainty of both
phases is worse; within it is not."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import InputDataError
from mt_accuracy_ros.core.workbench.closed_loop import judge_version


def _readings(rms_um, n=15, seed=0):
    rng = np.random.default_rng(seed)
    return rng.normal(0.0, 1.0, (n, 3)) * np.asarray(rms_um) * 1e-6


def test_a_version_that_raised_the_error_is_worse():
    judgement = judge_version(_readings([0.6, 0.7, 0.5]), _readings([0.6, 6.0, 0.5], seed=1),
                              1e-6)
    assert judgement.worse == "y"
    before, after = judgement.rise
    assert before == pytest.approx(np.sqrt(np.mean(_readings([0.6, 0.7, 0.5])[:, 1] ** 2)))
    assert after > 4 * before
    assert judgement.sentence().startswith("measured error rose from")


def test_a_change_within_the_uncertainty_is_not_worse():
    judgement = judge_version(_readings([0.6, 0.7, 0.5]), _readings([0.7, 0.8, 0.6], seed=1),
                              1e-6)
    assert judgement.worse is None
    assert "not worse" in judgement.sentence()


def test_too_few_readings_cannot_judge():
    with pytest.raises(InputDataError, match="need 5"):
        judge_version(_readings([1, 1, 1], n=3), _readings([1, 1, 1]), 1e-6)
