"""Columns several candidates share at one context (the harmonics of an axis' position
at one period): made once, read-only, bounded, and exactly the family's own."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.effects import base
from mt_accuracy_ros.core.effects.base import Context
from mt_accuracy_ros.core.effects.geometric import ComponentError
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.kinematics.machine import generic_cartesian


def _context(n: int = 2000) -> Context:
    rng = np.random.default_rng(4)
    machine = generic_cartesian({"X": (0.0, 0.5), "Y": (0.0, 0.4), "Z": (0.0, 0.3)})
    return Context(machine, Variables({a: rng.uniform(0.0, 0.3, n) for a in "XYZ"}))


def test_the_axis_harmonics_are_made_once_for_every_periodic_error_of_the_axis():
    ctx = _context()
    setting = {"period_m": 0.0123}
    families = [ComponentError(kind, True) for kind in ("positioning", "straightness",
                                                        "angular")]
    variants = ["EXX", "EYX", "EBX"]
    bases = [f.separable_design(ctx, v, setting)[1] for f, v in zip(families, variants)]
    assert bases[1] is bases[0] and bases[2] is bases[0] and not bases[0].flags.writeable
    own = families[0]._basis(ctx.variables.positions["X"], None, setting)
    np.testing.assert_array_equal(bases[0], own)
    # Another axis or period: their own columns.
    assert families[0].separable_design(ctx, "EYY", setting)[1] is not bases[0]
    assert families[0].separable_design(ctx, "EXX", {"period_m": 0.02})[1] is not bases[0]
    with pytest.raises(ValueError):
        bases[0][0, 0] = 1.0


def test_the_store_is_bounded_and_keeps_nothing_it_cannot_hold_enough_of(monkeypatch):
    ctx = _context()
    made = []

    def make(size):
        def f():
            made.append(size)
            return np.ones((size, 4))
        return f

    monkeypatch.setattr(base, "SHARED_COLUMNS_BYTES", 3 * 2000 * 4 * 8)
    monkeypatch.setattr(base, "SHARED_COLUMNS_KEPT", 2)
    first = ctx.shared_columns(("a",), make(2000))
    assert ctx.shared_columns(("a",), make(2000)) is first and made == [2000]
    for key in ("b", "c", "d"):
        ctx.shared_columns((key,), make(2000))
    assert ctx._shared.nbytes <= 3 * 2000 * 4 * 8
    assert ("a",) not in ctx._shared, "the least recently used went first"
    # Too large for the store to hold SHARED_COLUMNS_KEPT of them: made, not kept.
    ctx.shared_columns(("big",), make(4000))
    assert ("big",) not in ctx._shared


def test_a_preselection_asked_again_for_the_same_targets_is_the_choice_made_before(
        monkeypatch):
    """The period a periodogram chooses depends on the variant's readings, weights, folds
    and the targets alone: asked again with the same residual (another look, a step that
    left it unchanged) the kept choice comes back without a periodogram, equal to a
    fresh context's; another residual is computed anew."""
    from mt_accuracy_ros.core.effects import geometric

    ctx = _context(400)
    family = ComponentError("positioning", True)
    settings = family.settings(ctx, "EXX")
    rng = np.random.default_rng(9)
    x = ctx.variables.positions["X"]
    residual = np.zeros((400, 3))
    residual[:, 0] = 4e-6 * np.sin(2 * np.pi * x / settings[5]["period_m"]) + \
        rng.normal(0.0, 1e-6, 400)
    mask = np.ones((400, 3), dtype=bool)
    trains = np.ones((5, 400), dtype=bool)
    for fold, rows in enumerate(np.array_split(np.arange(400), 5)):
        trains[fold, rows] = False
    residuals = np.repeat(residual[None], 5, axis=0)
    computed = []
    strongest = geometric.strongest_frequencies

    def counted(*args, **kwargs):
        computed.append(1)
        return strongest(*args, **kwargs)

    monkeypatch.setattr(geometric, "strongest_frequencies", counted)
    first = family.preselect_folds(ctx, "EXX", settings, residuals, mask, trains)
    again = family.preselect_folds(ctx, "EXX", settings, residuals.copy(), mask, trains)
    assert again == first and len(computed) == 1
    fresh = family.preselect_folds(_context(400), "EXX", settings, residuals, mask, trains)
    assert fresh == first and len(computed) == 2
    assert all(c["period_m"] == pytest.approx(settings[5]["period_m"]) for c in first)
    family.preselect_folds(ctx, "EXX", settings, 0.5 * residuals, mask, trains)
    assert len(computed) == 3
