"""Variables and first-order lags: closed forms, an ODE solver, streaming = batch."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mt_accuracy_ros.core.effects.variables import Variables, first_order_lag
from mt_accuracy_ros.core.errors import InputDataError


def test_lag_of_a_step_is_the_exponential():
    t = np.linspace(0.0, 3000.0, 301)
    u = np.where(t > 0, 1.0, 0.0)
    y = first_order_lag(t, u, 600.0, initial=0.0)
    # u is linear between t0 and t1 (0 -> 1), then constant: the closed form after t1.
    after = t >= t[1]
    ramp = t[1] - 600.0 * (1 - np.exp(-t[1] / 600.0))   # integral response of the ramp
    expected = 1.0 - (1.0 - ramp / t[1]) * np.exp(-(t[after] - t[1]) / 600.0)
    np.testing.assert_allclose(y[after], expected, atol=1e-12)


def test_lag_matches_an_ode_solver_on_uneven_samples():
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0, 7200, 400))
    u = 20 + 3 * np.sin(t / 900) + 0.5 * np.cos(t / 170)
    y = first_order_lag(t, u, 1200.0)
    solution = solve_ivp(lambda s, v: (np.interp(s, t, u) - v) / 1200.0, (t[0], t[-1]), [u[0]],
                         t_eval=t, rtol=1e-10, atol=1e-12, max_step=5.0)
    np.testing.assert_allclose(y, solution.y[0], atol=1e-6)


@pytest.mark.parametrize("tau_s", [5.0, 600.0, 1e6])
def test_lag_in_closed_form_equals_the_step_by_step_recurrence(tau_s):
    """The vectorised solution (stretches of bounded decay) against the documented
    recurrence stepped one sample at a time - a long record whose total decay
    underflows, repeated stamps, a time constant far beyond the record."""
    rng = np.random.default_rng(5)
    t = np.cumsum(rng.uniform(0, 30, 20000))
    t[100:104] = t[100]
    u = 20 + np.cumsum(rng.normal(0, 0.05, t.size))
    # The reference in extended precision: with a long time constant the recurrence's
    # own rounding (u - slope tau + ... of nearly cancelling terms) grows to 1e-9 K.
    t_long, u_long = t.astype(np.longdouble), u.astype(np.longdouble)
    dt = np.diff(t_long)
    slope_tau = np.where(dt > 0, np.diff(u_long) / np.where(dt > 0, dt, 1), 0) * tau_s
    decay = np.exp(-dt / tau_s)
    expected = np.empty_like(u_long)
    expected[0] = 18.0
    for k in range(u.size - 1):
        if dt[k] == 0:
            # No time passes between equal stamps: the lag's output cannot move
            # (issue 40; it used to jump with the input).
            expected[k + 1] = expected[k]
            continue
        expected[k + 1] = u_long[k + 1] - slope_tau[k] + \
            (expected[k] - u_long[k] + slope_tau[k]) * decay[k]
    np.testing.assert_allclose(first_order_lag(t, u, tau_s, initial=18.0),
                               expected.astype(float), rtol=0, atol=1e-10)


def test_a_temperature_lag_starts_in_steady_state_not_from_zero():
    t = np.arange(0.0, 600.0, 10.0)
    u = np.full(t.size, 22.0)
    np.testing.assert_allclose(first_order_lag(t, u, 1200.0), 22.0)


def test_a_stream_continues_the_lag_exactly():
    t = np.arange(0.0, 1000.0, 2.0)
    u = np.sin(t / 50.0)
    whole = Variables({"X": t * 0}, t, lag_states={}).lag("u", u, 300.0)
    states: dict = {}
    parts = [Variables({"X": t[s] * 0}, t[s], lag_states=states).lag("u", u[s], 300.0)
             for s in (slice(0, 123), slice(123, 400), slice(400, None))]
    np.testing.assert_allclose(np.concatenate(parts), whole, atol=1e-12)


def test_a_lag_asked_again_is_the_kept_one_and_only_for_the_same_signal(monkeypatch):
    """Readings without live states keep each lag (a selection asks at every step): the
    same key, signal and time constant give the kept, read-only array; another signal
    under the same key, another constant, from rest, or runs, their own; the memo is
    bounded."""
    from mt_accuracy_ros.core.effects import variables as module

    t = np.arange(0.0, 3000.0, 5.0)
    u = np.sin(t / 400.0)
    v = Variables({"X": t * 0}, t)
    first = v.lag("u", u, 600.0)
    np.testing.assert_array_equal(first, first_order_lag(t - t[0], u, 600.0))
    assert v.lag("u", u.copy(), 600.0) is first and not first.flags.writeable
    other = v.lag("u", u + 1e-12, 600.0)
    assert other is not first
    np.testing.assert_array_equal(other, first_order_lag(t - t[0], u + 1e-12, 600.0))
    assert v.lag("u", u, 1200.0) is not first
    np.testing.assert_array_equal(v.lag("u", u, 600.0, from_rest=True),
                                  first_order_lag(t - t[0], u, 600.0, initial=0.0))
    runs = Variables({"X": t * 0}, t, run_starts=np.array([0, 250]))
    np.testing.assert_array_equal(runs.lag("u", u, 600.0)[250:],
                                  first_order_lag(t[250:] - t[250], u[250:], 600.0))
    monkeypatch.setattr(module, "LAG_MEMO_BYTES", 2 * first.nbytes)
    monkeypatch.setattr(module, "LAG_MEMO_KEPT", 1)
    bounded = Variables({"X": t * 0}, t)
    for tau in (100.0, 200.0, 300.0, 400.0):
        bounded.lag("u", u, tau)
    assert bounded._lag_memo.nbytes <= 2 * first.nbytes and len(bounded._lag_memo) == 2
    # A memo that could not hold LAG_MEMO_KEPT of them keeps none.
    monkeypatch.setattr(module, "LAG_MEMO_KEPT", 3)
    unkept = Variables({"X": t * 0}, t)
    unkept.lag("u", u, 600.0)
    assert len(unkept._lag_memo) == 0


def test_variables_by_name_and_clear_errors():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    v = Variables({"X": np.array([0.0, 0.1, 0.3, 0.6]), "B": np.zeros(4)}, t + 100.0,
                  {"X": np.array([0.1, 0.2, 0.3, 0.4])}, temperatures={"column": t + 20.0},
                  spindle_speed_rad_s=np.full(4, 2 * np.pi * 100))
    np.testing.assert_allclose(v.get("t"), t)
    np.testing.assert_allclose(v.get("T_column"), t)              # rise over the first
    np.testing.assert_allclose(v.get("acc_x"), 0.1)                # d v / d t
    np.testing.assert_allclose(v.get("spindle_rpm"), 6000.0)
    assert v.get("b").shape == (4,)
    with pytest.raises(InputDataError, match="unknown variable 'T_bed'.*T_column"):
        v.get("T_bed")
    with pytest.raises(InputDataError, match="must not decrease"):
        first_order_lag(np.array([0.0, 2.0, 1.0]), np.zeros(3), 10.0)
    with pytest.raises(InputDataError, match="NaN"):
        first_order_lag(np.array([0.0, 1.0]), np.array([0.0, np.nan]), 10.0)
