"""A lag longer than the record is a ramp to the data: it is not searched (issue 26)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.effects.thermal import (MAX_TAU_PER_SPAN, TIME_CONSTANTS_S, HeatSource,
                                                  ThermalLag)


def _ctx(span_s: float | None, run_starts=None):
    time_s = None if span_s is None else np.linspace(100.0, 100.0 + span_s, 50)
    return SimpleNamespace(variables=Variables({"X": np.zeros(50)}, time_s,
                                               run_starts=run_starts))


def test_a_log_of_runs_searches_what_its_longest_run_sees():
    # 3 h cut into runs of 1 h 15 min and the rest: lags up to the longest run, not 3 h.
    ctx = _ctx(3 * 3600.0, run_starts=[0, 25])
    longest = max(np.ptp(ctx.variables.time_s[:25]), np.ptp(ctx.variables.time_s[25:]))
    taus = [s["tau_s"] for s in ThermalLag().settings(ctx, "column")]
    assert taus == [t for t in TIME_CONSTANTS_S if t <= longest] and max(taus) < 3 * 3600.0


def test_only_time_constants_the_record_supports_are_searched():
    # A 3 h survey: every time constant up to 3 h (2.7 h on the grid), none longer.
    taus = [s["tau_s"] for s in ThermalLag().settings(_ctx(3 * 3600.0), "spindle")]
    assert taus == [t for t in TIME_CONSTANTS_S if t <= 3 * 3600.0]
    assert max(taus) == TIME_CONSTANTS_S[10] and TIME_CONSTANTS_S[11] > 3 * 3600.0
    assert all(s["tau_s"] <= MAX_TAU_PER_SPAN * 1800.0
               for s in ThermalLag().settings(_ctx(1800.0), "column"))


def test_a_record_shorter_than_the_shortest_lag_searches_no_lag():
    # The demo's 46 s window once fitted a 5 min bed lag at -5.5 mm/K: a record that never
    # saw a time constant cannot name one, so the family offers nothing there.
    assert ThermalLag().settings(_ctx(90.0), "column") == []
    assert HeatSource().settings(_ctx(46.0), "spindle_speed") == []
    assert ThermalLag().settings(_ctx(None), "column") == []
