"""The one acceptance rule (``selection.significance.PassRule``): what it refuses and why,
and that the selection and a log's judge of a single candidate both ask it."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.core.workbench.diagnosis import Candidate, selection_refusal
from mt_accuracy_ros.core.workbench.selection import Evidence, PassRule, Selector

from test_selection_engine import _selector


def _evidence(**changes) -> Evidence:
    """A candidate that passes every test of the default rule, with ``changes``."""
    values = dict(refusal="", adjusted_p=0.01, reduction=0.2, share_of_excess=0.6,
                  coefficients=np.array([4e-6, 1e-7]), standard_errors=np.array([1e-6, 1e-6]))
    values.update(changes)
    return Evidence(**values)


def test_a_candidate_that_shows_itself_passes():
    assert PassRule().refusal(_evidence()) == ""
    assert PassRule().passes(_evidence())


@pytest.mark.parametrize("changes, reason", [
    ({"refusal": "gain above 50 um/K"}, "physics refuses its fit (gain above 50 um/K)"),
    ({"adjusted_p": 0.2}, "the held-out block test: p = 0.2 after adjusting for every "
                          "candidate tried (max-T), above 0.05"),
    ({"reduction": -0.03}, "it raises the CV error by 3.0 %"),
    ({"reduction": 0.04}, "it cuts the CV error by 4.0 %, below 5 %"),
    ({"share_of_excess": 0.2}, "it removes 20 % of the error above the noise, below 25 %"),
    ({"coefficients": np.array([2.9e-6, 0.0])}, "no parameter is above 3 standard errors"),
    # Physics is asked first, then the held-out test.
    ({"refusal": "x", "adjusted_p": 0.9}, "physics refuses its fit (x)"),
    ({"adjusted_p": 0.9, "reduction": -1.0}, "the held-out block test"),
])
def test_each_test_refuses_with_its_numbers_in_order(changes, reason):
    assert PassRule().refusal(_evidence(**changes)).startswith(reason)


def test_the_bounds_are_inclusive_and_a_nan_never_passes():
    rule = PassRule(alpha=0.05, min_reduction=0.1, min_share=0.3)
    assert rule.passes(_evidence(reduction=0.1, share_of_excess=0.3))
    assert not rule.passes(_evidence(adjusted_p=0.05))
    assert not rule.passes(_evidence(reduction=float("nan")))
    assert not rule.passes(_evidence(share_of_excess=float("nan")))
    assert not rule.passes(_evidence(standard_errors=np.array([np.nan, np.nan])))


def test_the_full_data_coefficients_stand_in_for_the_block_test_only_where_allowed():
    weak = _evidence(adjusted_p=0.3)
    assert not PassRule().passes(weak)
    assert PassRule().passes(_evidence(adjusted_p=0.3, coefficient_p=0.001))
    # Without the block test (a log judged on its later runs) the p-values are not asked.
    assert PassRule(block_test=False).passes(weak)


def test_a_negative_least_reduction_is_refused():
    with pytest.raises(ParameterError, match="min_reduction"):
        PassRule(min_reduction=-0.1)


def test_a_logs_judge_of_one_candidate_asks_the_same_rule():
    candidate = Candidate("straightness", {"a": 4e-6, "b": 1e-7}, 1e-6, 0.2, True, "",
                          parameter_uncertainties={"a": 1e-6, "b": 1e-6},
                          share_of_excess=0.6, adjusted_p=0.01)
    assert selection_refusal(candidate, 0.05) == ""
    candidate.share_of_excess = 0.2
    assert selection_refusal(candidate, 0.05) == PassRule().refusal(_evidence(
        share_of_excess=0.2))
    candidate.share_of_excess, candidate.adjusted_p = 0.6, 0.5
    assert selection_refusal(candidate, 0.05).startswith("the held-out block test")
    assert selection_refusal(candidate, 0.05, block_test=False) == ""
    # A parameter whose uncertainty is not stated shows no strength.
    candidate.adjusted_p, candidate.parameter_uncertainties = 0.01, {}
    assert selection_refusal(candidate, 0.05) == "no parameter is above 3 standard errors"


def _asks_the_rule(selector, terms) -> bool:
    """One step of ``selector``: its first candidate is named exactly when the rule passes
    it (on its full-data coefficients where it is the held-out data's own first), and no
    other candidate is. Returns whether it was named."""
    step = selector.step(terms)
    best = step.ranking[0]
    first_by_error = sorted((s for s in step.ranking if not s.refusal),
                            key=lambda s: s.cv_rmse)[0]
    assert best.significant == selector.rule.passes(best.evidence(best is first_by_error))
    assert (step.added is best) == best.significant
    assert not any(s.significant for s in step.ranking[1:])
    return best.significant


def test_the_selection_names_what_the_rule_passes_and_nothing_it_refuses():
    selector, terms = _selector()
    assert _asks_the_rule(selector, terms)
    noise = np.random.default_rng(3).normal(0.0, 0.5e-6, selector.residual.shape)
    assert not _asks_the_rule(Selector(selector.ctx, noise, selector.mask, 0.5e-6), terms)
