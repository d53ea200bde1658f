"""One context, and the designs derived from it, for every look at the same readings.

`check --auto` diagnoses a survey, adds what it names and diagnoses again. Both looks
see the same readings through the same nominal chain; the second gets the first's
context (`ContextMemo`) and with it every design, scalar basis and design product the
first made (`selection._ReadingCaches`). What the second look reports must be what a
look from nothing reports; other readings, another machine or another tool
orientation get a new context."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.kinematics.machine import generic_cartesian
from mt_accuracy_ros.core.workbench import selection
from mt_accuracy_ros.core.workbench.context_memo import ContextMemo
from same_steps import assert_same_steps
from mt_accuracy_ros.core.workbench.diagnosis import (Observations, add_effects,
                                                      candidate_terms, diagnose, residual_frame,
                                                      residuals)

STROKES = {"X": (0.0, 0.5), "Y": (0.0, 0.4), "Z": (0.0, 0.3)}


def _pitch_survey(seed: int = 5, n: int = 500):
    """A generic machine known from its survey (tilts fitted with their arms,
    ``angular_arm``): a 10 mm pitch on X and a Z straightness in X."""
    rng = np.random.default_rng(seed)
    positions = {a: rng.uniform(*STROKES[a], n) for a in "XYZ"}
    measured = rng.normal(0, 0.3e-6, (n, 3))
    measured[:, 0] += 4e-6 * np.sin(2 * np.pi * positions["X"] / 0.01)
    measured[:, 2] += 3e-6 * ((2 * positions["X"] - 0.5) / 0.5) ** 2
    model = ErrorModel(generic_cartesian(STROKES), {})
    obs = Observations(positions, measured, np.ones((n, 3), bool), np.arange(n) * 5.0,
                       uncertainty_m=0.6e-6)
    return model, obs


def _ranking(diagnosis):
    return [(c.name, c.cv_rmse_after, tuple(c.parameters.values())) for c in diagnosis.ranking]


def _assert_same(a, b):
    assert [c.name for c in a.selected] == [c.name for c in b.selected]
    assert [r[0] for r in _ranking(a)] == [r[0] for r in _ranking(b)]
    for (_, cv_a, p_a), (_, cv_b, p_b) in zip(_ranking(a), _ranking(b)):
        assert cv_a == pytest.approx(cv_b, rel=1e-12)
        np.testing.assert_allclose(p_a, p_b, rtol=1e-9, atol=1e-15)
    assert a.text() == b.text()


def test_the_look_after_adding_gets_the_first_looks_context_and_reports_as_a_fresh_look():
    model, obs = _pitch_survey()
    memo = ContextMemo()
    first = diagnose(model, obs, contexts=memo)
    assert memo.reused == 0 and first.selected, "the survey's effects are named"
    added = add_effects(model, first.selected, obs)
    second = diagnose(added, obs, pair_lookahead=False, contexts=memo)
    assert memo.reused == 1, "the second look sees the same readings through the same chain"
    # From nothing: new contexts, new selectors, nothing cached.
    fresh_first = diagnose(model, obs)
    fresh_second = diagnose(add_effects(model, fresh_first.selected, obs), obs,
                            pair_lookahead=False)
    _assert_same(first, fresh_first)
    _assert_same(second, fresh_second)


def test_a_context_is_handed_out_again_only_for_the_same_readings_machine_and_tool():
    model, obs = _pitch_survey()
    memo = ContextMemo()

    def ask(machine=model.machine, variables=None, orientation=None, kinematics=None):
        return memo.context(machine, variables or obs.variables({}),
                            kinematics or model._kinematics, orientation,
                            orientation_lever_m=None, work_point=None, zero_rows=None)

    kept = ask()
    assert ask() is kept and memo.reused == 1
    # Another model of the same machine (its own kinematics object): the same chain.
    assert ask(kinematics=ErrorModel(model.machine, {})._kinematics) is kept
    moved = dict(obs.positions)
    moved["Y"] = moved["Y"] + 1e-9
    other = ask(variables=Variables(moved, obs.time_s))
    assert other is not kept
    assert ask(variables=Variables(moved, obs.time_s)) is other
    assert ask(machine=generic_cartesian(STROKES)) is not other
    tilted = np.full((obs.n, 3), 1e-6)
    assert ask(orientation=tilted) is not ask()
    live = Variables(dict(obs.positions), obs.time_s, lag_states={})
    assert ask(variables=live) is not ask(variables=live), "live lag states are never shared"


def test_selectors_sharing_a_context_score_as_selectors_on_their_own():
    """A selector whose context's caches are warm from another residual's selection
    ranks, scores and fits every candidate as one on a context of its own."""
    model, obs = _pitch_survey()
    frame = residual_frame(model, obs)
    warm = selection.Selector(frame.ctx, frame.residual, frame.mask, 0.3e-6)
    terms = candidate_terms(model, frame.ctx, None)
    warm.run(terms, max_terms=2)
    other = frame.residual * np.array([0.5, -1.0, 2.0]) + 1e-7
    shared = selection.Selector(frame.ctx, other, frame.mask, 0.3e-6)
    assert shared._designs is warm._designs and shared._own_products is warm._own_products
    alone_frame = residual_frame(model, obs)
    alone = selection.Selector(alone_frame.ctx, other, frame.mask, 0.3e-6)
    assert alone._designs is not warm._designs
    steps = shared.run(terms, max_terms=2)
    alone_steps = alone.run(candidate_terms(model, alone_frame.ctx, None), max_terms=2)
    assert_same_steps(steps, alone_steps, coefficients=True)
    # Other rows fitted: caches of their own.
    fewer = frame.mask.copy()
    fewer[::3, 1] = False
    assert selection.Selector(frame.ctx, frame.residual, fewer, 0.3e-6)._designs is not \
        warm._designs


def test_a_tilt_with_its_arm_at_a_lower_order_is_columns_of_the_highest_orders_design():
    """``angular_arm``'s order k is the tilt's first k columns and the arm's first k: the
    selection makes one design and one set of products for every order."""
    model, obs = _pitch_survey()
    frame = residual_frame(model, obs)
    selector = selection.Selector(frame.ctx, frame.residual, frame.mask, 0.3e-6)
    stats = selector.base_statistics(selector.base_columns())
    q = stats.base.shape[1]
    arms = [t for t in candidate_terms(model, frame.ctx, None)
            if t.family.name == "angular_arm"]
    assert arms
    for term in arms:
        for setting in term.settings:
            made = frame.ctx.measured_design(term.family, term.variant, setting)
            made = made.reshape(-1, made.shape[2])[selector.rows]
            np.testing.assert_array_equal(selector.design_rows(term, setting), made)
            gram, rhs, yy = selector._products_of(stats, term, setting)
            e_gram, e_rhs, e_yy = selector._candidate_products(stats, made)
            np.testing.assert_allclose(gram, e_gram, rtol=0, atol=1e-12 * np.abs(e_gram).max())
            np.testing.assert_allclose(rhs, e_rhs, rtol=0, atol=1e-12 * np.abs(e_rhs).max())
            np.testing.assert_allclose(yy, e_yy, rtol=1e-14)
            assert gram.shape[1] == q + len(term.family.parameter_names(term.variant, setting))


def test_what_a_context_and_a_selector_keep_at_a_hundred_thousand_readings_is_kept_once():
    """Memory (issue 41: 500 MB at 1e5 readings): asking which tilts an arm along the
    tool carries keeps no sensitivity, and a base's columns live once, inside [base, y].
    The answers are those of the sensitivities made and kept."""
    model, obs = _pitch_survey()
    frame = residual_frame(model, obs)
    ctx = frame.ctx
    names = [f"E{c}{a}" for a in "XYZ" for c in "ABC"]
    moves = {name: ctx.arm_moves(name) for name in names}
    assert not any(key.startswith(("arm:", "orientation:")) for key in ctx._jacobians)
    fresh = residual_frame(model, obs).ctx
    assert moves == {name: bool(np.any(np.abs(fresh.arm_jacobian(name)) > 1e-12))
                     for name in names}
    assert any(moves.values()) and not all(moves.values())
    # Once made, the kept sensitivity answers.
    assert all(fresh.arm_moves(name) == moves[name] for name in names)
    selector = selection.Selector(ctx, frame.residual, frame.mask, 0.3e-6)
    columns = selector.base_columns()
    stats = selector.base_statistics(columns)
    np.testing.assert_array_equal(stats.base, columns)
    np.testing.assert_array_equal(stats.with_y[:, -1], selector.y)
    assert np.shares_memory(stats.base, stats.with_y)


def test_a_look_handed_its_models_residual_reports_as_one_that_computes_it():
    model, obs = _pitch_survey()
    residual = residuals(model, obs)
    kept = residual.copy()
    _assert_same(diagnose(model, obs, residual=residual), diagnose(model, obs))
    np.testing.assert_array_equal(residual, kept)
