"""The lockstep gate's rules (nodes/_lockstep.py), each against its closed form."""
from __future__ import annotations

import pytest

from mt_accuracy_ros.nodes._lockstep import (LockstepGate, Progress, check_compensation_delay,
                                             parse_participants)

MS = 1_000_000
T0 = 1_000_000 * MS   # the stream's first stamp


def gate(**participants) -> LockstepGate:
    return LockstepGate(participants, lead_ns=20 * MS, compensation_delay_ns=20 * MS)


def test_a_participant_that_never_reported_holds_even_the_first_batch():
    g = gate(estimator="scales")
    assert g.waiting_for(T0, T0 + 10 * MS, None, T0) == ("estimator", "has not reported yet")
    g.update("estimator", Progress())
    assert g.waiting_for(T0, T0 + 10 * MS, None, T0) is None


def test_scales_may_trail_by_the_lead_and_no_more():
    g = gate(estimator="scales")
    g.update("estimator", Progress(handled_ns=T0 + 30 * MS))
    assert g.waiting_for(T0 + 50 * MS, T0 + 60 * MS, None, T0) is None
    assert g.waiting_for(T0 + 60 * MS, T0 + 70 * MS, None, T0)[0] == "estimator"


def test_the_corrections_a_batch_applies_are_in_before_it_goes_out():
    # Batch [start, start + 10 ms) applies corrections stamped before end - delay.
    g = gate(broadcaster="compensation")
    g.update("broadcaster", Progress(handled_ns=T0 + 40 * MS))
    assert g.waiting_for(T0 + 50 * MS, T0 + 60 * MS, None, T0) is None
    assert g.waiting_for(T0 + 60 * MS, T0 + 70 * MS, None, T0)[1] == \
        "the corrections this batch applies are not in"


def test_a_reading_is_handled_only_once_the_check_it_started_is_published():
    g = gate(monitor="reference")
    g.update("monitor", Progress(handled_ns=T0 + 500 * MS))   # the check of 500 ms runs
    assert g.waiting_for(T0 + 900 * MS, T0 + 910 * MS, T0 + 500 * MS, T0)[0] == "monitor"
    g.update("monitor", Progress(handled_ns=T0 + 500 * MS + 1))
    assert g.waiting_for(T0 + 900 * MS, T0 + 910 * MS, T0 + 500 * MS, T0) is None


def test_a_user_acts_on_every_check_and_a_new_version_is_settled_before_the_stream_goes_on():
    g = gate(monitor="reference", user="checks", broadcaster="compensation")
    g.update("monitor", Progress(handled_ns=T0 + 501 * MS, last_check_ns=T0 + 500 * MS,
                                 model_version_published=1))
    g.update("user", Progress(check_handled_ns=T0 + 400 * MS))
    g.update("broadcaster", Progress(handled_ns=T0 + 510 * MS, model_version_settled=1))
    assert g.waiting_for(T0 + 510 * MS, T0 + 520 * MS, T0 + 500 * MS, T0) == \
        ("user", f"check {T0 + 500 * MS} ns not acted on")
    g.update("user", Progress(check_handled_ns=T0 + 500 * MS, model_version_published=2))
    assert g.waiting_for(T0 + 510 * MS, T0 + 520 * MS, T0 + 500 * MS, T0) == \
        ("broadcaster", "model version 2 not settled")
    g.update("broadcaster", Progress(handled_ns=T0 + 510 * MS, model_version_settled=2))
    assert g.waiting_for(T0 + 510 * MS, T0 + 520 * MS, T0 + 500 * MS, T0) is None


def test_reports_never_go_back_and_a_left_out_participant_holds_nothing():
    g = gate(estimator="scales", thermometers="temperatures")
    g.update("estimator", Progress(handled_ns=T0 + 100 * MS))
    g.update("estimator", Progress(handled_ns=T0))   # an old report arriving late
    assert g.progress["estimator"].handled_ns == T0 + 100 * MS
    g.update("thermometers", Progress(handled_ns=T0 + 50 * MS))
    assert g.waiting_for(T0 + 60 * MS, T0 + 70 * MS, None, T0)[0] == "thermometers"
    g.leave_out("thermometers", "silent")
    assert g.waiting_for(T0 + 60 * MS, T0 + 70 * MS, None, T0) is None


def test_the_stream_position_is_awaited_exactly_while_the_temperatures_hold_it():
    # The machine says where its stream is only while a temperatures participant may wait
    # for it: then that participant's report (its next reading's stamp - 1) is the rule.
    g = gate(estimator="scales", thermometers="temperatures")
    assert g.stream_awaited(T0)                       # not reported yet
    g.update("thermometers", Progress(handled_ns=T0 + 500 * MS - 1))
    assert not g.stream_awaited(T0 + 10 * MS)
    assert not g.stream_awaited(T0 + 500 * MS - 1)
    assert g.stream_awaited(T0 + 500 * MS)            # the reading at 500 ms is due
    # ... whenever the gate would hold a batch starting there for the temperatures.
    g.update("estimator", Progress(handled_ns=T0 + 500 * MS))
    for start in (T0 + 490 * MS, T0 + 500 * MS):
        held = g.waiting_for(start, start + 10 * MS, None, T0)
        assert (held is not None and held[0] == "thermometers") == g.stream_awaited(start)
    g.leave_out("thermometers", "silent")
    assert g.stream_awaited(T0 + 500 * MS)            # no follower holds: every position
    assert gate(estimator="scales").stream_awaited(T0)


def test_bad_participants_and_a_delay_shorter_than_a_batch_are_refused():
    assert parse_participants(["a:scales", "", "b:checks"]) == {"a": "scales", "b": "checks"}
    with pytest.raises(ValueError, match="node:stream"):
        parse_participants(["monitor"])
    with pytest.raises(ValueError, match="node:stream"):
        parse_participants(["monitor:readings"])
    with pytest.raises(ValueError, match="named twice"):
        parse_participants(["a:scales", "a:checks"])
    with pytest.raises(ValueError, match="compensation_delay_s"):
        check_compensation_delay(0.005, 0.01, {"b": "compensation"})
    check_compensation_delay(0.005, 0.01, {"b": "scales"})
