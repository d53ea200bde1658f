"""A lag far longer than the record is a ramp to the data: it is not searched."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from mt_accuracy_ros.core.effects.thermal import (MAX_TAU_PER_SPAN, TIME_CONSTANTS_S, HeatSource,
                                                  ThermalLag)


def _ctx(span_s: float | None):
    time_s = None if span_s is None else np.linspace(100.0, 100.0 + span_s, 50)
    return SimpleNamespace(variables=SimpleNamespace(time_s=time_s))


def test_only_time_constants_the_record_can_tell_from_a_ramp_are_searched():
    # A 3 h survey: every time constant up to 5.3 h stays (4 x 3 h = 12 h).
    assert [s["tau_s"] for s in ThermalLag().settings(_ctx(3 * 3600.0), "spindle")] == \
        list(TIME_CONSTANTS_S)
    # A 90 s demo: only 5 min (<= 4 x 90 s = 6 min); a fitted 5.3 h lag there had a gain of
    # 0.3 m/K and predicted millimetres once the broadcaster's lag had run longer.
    assert [s["tau_s"] for s in HeatSource().settings(_ctx(90.0), "spindle_speed")] == [300.0]
    assert all(s["tau_s"] <= MAX_TAU_PER_SPAN * 1800.0
               for s in ThermalLag().settings(_ctx(1800.0), "column"))
    # Shorter than the shortest: the shortest is still offered; no times: all.
    assert [s["tau_s"] for s in ThermalLag().settings(_ctx(10.0), "column")] == [300.0]
    assert len(ThermalLag().settings(_ctx(None), "column")) == len(TIME_CONSTANTS_S)
