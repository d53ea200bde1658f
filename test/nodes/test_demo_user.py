"""The demo's user (nodes/demo_user.py): its rules against their closed forms, and the
node's decision driven by synthetic messages (no graph: its callbacks are called
directly, its change_model client is a stand-in)."""
from __future__ import annotations

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from mt_accuracy_msgs.msg import (EffectScore, ModelCheck, ModelVersion, ReferenceMeasurement,
                                  SystematicProfile)
from mt_accuracy_ros.nodes._common import nanoseconds_to_stamp
from mt_accuracy_ros.nodes._model_client import ChangeOutcome
from mt_accuracy_ros.nodes.demo_user import (ANSWER_S, LOCKSTEP_ANSWER_S, LOOKS_AFTER_S,
                                             action_entry, action_line, effects_to_add,
                                             hear_warnings, is_new_alarm, latest_version,
                                             progress_line, readings_judged, reference_entry)

START_NS = 1_700_000_000 * 1_000_000_000   # the run's time base


def check(time_s: float, *names: str, rmse: float = 2e-6) -> ModelCheck:
    """A check stamped ``time_s`` of data after START_NS, naming ``names``."""
    message = ModelCheck(rmse=rmse, localisation="x along v_y", diagnosis="a pitch error")
    message.header.stamp = nanoseconds_to_stamp(START_NS + round(time_s * 1e9))
    message.named = [EffectScore(name=name) for name in names]
    return message


def version(number: int, reason: str = "start") -> ModelVersion:
    return ModelVersion(version=number, reason=reason)


# ------------------------------------------------------------------ the rules
def test_the_user_acts_once_on_the_first_check_naming_effects_after_the_warm_up():
    named = check(33.0, "structural_thermal_drift:column", "positioning_periodic:EXX")
    # Nothing heard, nothing named, or not yet warmed (30 s of data, strictly after).
    assert effects_to_add([], acted=False) == []
    assert effects_to_add([(33.0, check(33.0))], acted=False) == []
    assert effects_to_add([(29.9, named)], acted=False) == []
    assert effects_to_add([(LOOKS_AFTER_S, named)], acted=False) == []
    # After: every effect named, in the monitor's order (its joint fit), once only.
    assert effects_to_add([(30.1, named)], acted=False) == [
        "structural_thermal_drift:column", "positioning_periodic:EXX"]
    assert effects_to_add([(30.1, named)], acted=True) == []
    # Only the latest check counts: an earlier one that named effects does not.
    assert effects_to_add([(33.0, named), (44.1, check(44.1))], acted=False) == []
    assert effects_to_add([(5.0, check(5.0, "angular:EBX"))], False, looks_after_s=4.0) == \
        ["angular:EBX"]


def test_versions_alarms_and_the_monitors_backlog():
    assert latest_version([]) == 0
    assert latest_version([(0.0, version(1)), (9.0, version(3)), (5.0, version(2))]) == 3
    # An alarm per axis: the first deterioration only.
    assert is_new_alarm([], "y", True)
    assert not is_new_alarm([], "y", False)
    assert not is_new_alarm([(50.2, "y")], "y", True)
    assert is_new_alarm([(50.2, "y")], "x", True)
    # The monitor is done when processed + refused + lost covers every reading (> 0).
    counts = {"/model_monitor": {"reference/tcp_error.processed": "240",
                                 "reference/tcp_error.refused": "3",
                                 "reference/tcp_error.lost": "1", "scales.processed": "9"}}
    assert readings_judged(counts, 244)
    assert not readings_judged(counts, 245)
    assert not readings_judged({}, 0)   # no reading yet is not "every reading judged"
    assert not readings_judged({}, 1)


def test_warnings_are_kept_once_each_in_the_order_said():
    heard: dict[str, list[str]] = {}
    hear_warnings(heard, "/yaw_estimator: delivery",
                  {"warning.1": "niceness -15 refused", "warning.0": "sensor T3 dead",
                   "scales.processed": "10"})
    hear_warnings(heard, "/yaw_estimator: delivery",
                  {"warning.0": "sensor T3 dead", "warning.1": "niceness -15 refused",
                   "warning.2": "late input"})
    assert heard == {"/yaw_estimator": ["sensor T3 dead", "niceness -15 refused",
                                        "late input"]}


def test_a_reference_reading_is_held_in_data_time_with_its_direction_or_a_gap():
    m = ReferenceMeasurement(uncertainty=1e-6, compensation_model_version=2)
    m.header.stamp = nanoseconds_to_stamp(START_NS + 12_370_000_000)
    m.error.x, m.error.y, m.error.z = 1e-6, -2e-6, 3e-6
    m.applied_correction.x = 4e-6
    reading, orientation = reference_entry(m, START_NS)
    assert reading[0] == pytest.approx(12.37, abs=1e-12)
    assert reading[1].tolist() == [1e-6, -2e-6, 3e-6]
    assert reading[2].tolist() == [4e-6, 0.0, 0.0]
    assert reading[3:] == (2, 1e-6)
    assert orientation is None
    m.orientation_measured, m.orientation_uncertainty = True, 2e-6
    m.orientation_error.z, m.applied_orientation_correction.y = 5e-6, -6e-6
    _, orientation = reference_entry(m, START_NS)
    assert orientation[0].tolist() == [0.0, 0.0, 5e-6]
    assert orientation[1].tolist() == [0.0, -6e-6, 0.0]
    assert orientation[2] == 2e-6


def test_what_the_user_did_is_kept_and_said():
    latest = check(32.9, "a", "b", rmse=3.5e-6)
    action = action_entry(32.9, latest, ["a", "b"], True, "")
    assert action == {"time_s": 32.9, "added": "a, b", "effects": ["a", "b"],
                      "accepted": True, "reason": "", "rmse_before_m": 3.5e-6,
                      "where": "x along v_y", "diagnosis": "a pitch error"}
    assert action_line(action) == ("  data 32.9 s: the monitor names a, b; the user adds "
                                   "them - accepted")
    refused = action_entry(40.04, latest, ["a"], False, "no gain")
    assert action_line(refused) == ("  data 40.0 s: the monitor names a; the user adds it - "
                                    "refused: no gain")


def test_the_progress_line_says_where_the_run_is():
    assert progress_line(6.2, [], [], 0, {}) == (
        "  [    6 s wall] data   -   | waiting for the machine | checks 0 | corrections "
        "applied 0, stale 0")
    readings = [(5.94, None, None, 0, 1e-6)]
    assert "| no compensation applied yet |" in progress_line(11.0, readings, [], 0, {})
    readings.append((38.1, None, None, 2, 1e-6))
    line = progress_line(36.0, readings, [(1.0, version(1)), (2.0, version(2, "added a"))], 4,
                         {"applied": "3793", "stale": "2"})
    assert line == ("  [   36 s wall] data  38.1 s | v2 live at the machine (added a) | checks 4 "
                    "| corrections applied 3793, stale 2")


# ------------------------------------------------------------------ the node
@pytest.fixture
def user_node():
    """A DemoUser on a private context, with a stand-in for the monitor's change_model
    service that records each request and answers as told (an outcome)."""
    import rclpy
    from rclpy.parameter import Parameter

    from mt_accuracy_ros.nodes._common import node_executor
    from mt_accuracy_ros.nodes.demo_user import DemoUser

    context = rclpy.Context()
    rclpy.init(context=context)
    made = []

    def make(lockstep: bool, answer=ChangeOutcome(True, "added (user)", 2), stand_in=True):
        asked = []

        def ask(*, add_effects, executor, timeout_s):
            asked.append(("add_effects", list(add_effects), executor is node.executor,
                          timeout_s))
            return answer

        node = DemoUser(ask if stand_in else None, context=context, parameter_overrides=[
            Parameter("lockstep", value=lockstep)])
        executor = node_executor(node)
        made.append((node, executor))
        node.start(START_NS)
        return node, asked

    yield make
    for node, executor in made:
        executor.shutdown()
        node.destroy_node()
    rclpy.try_shutdown(context=context)


def test_the_node_adds_what_the_first_naming_check_names_once(user_node):
    user, asked = user_node(lockstep=False)
    assert (user.rate_factor, user.lockstep, user.looks_after_s) == (1.0, False, LOOKS_AFTER_S)
    user._on_model(version(1))
    user._on_check(check(22.2, "angular:EBX"))
    assert user.act() is None and asked == []   # still warming
    user._on_check(check(33.3, "angular:EBX", "angular:EAY"))
    action = user.act()
    assert asked == [("add_effects", ["angular:EBX", "angular:EAY"], True, ANSWER_S)]
    assert action == user.actions[0]
    assert (action["time_s"], action["added"], action["accepted"]) == \
        (pytest.approx(33.3, abs=1e-9), "angular:EBX, angular:EAY", True)
    user._on_check(check(44.4, "positioning_periodic:EXX"))
    assert user.act() is None and len(asked) == 1 and len(user.actions) == 1
    assert [t for t, _ in user.checks] == pytest.approx([22.2, 33.3, 44.4], abs=1e-9)


def test_a_lockstep_user_says_each_check_looked_at_and_the_version_it_saw(user_node):
    # The answer names the version made; the user need not have seen it on 'model'.
    user, asked = user_node(lockstep=True, answer=ChangeOutcome(True, "added (user)", 2))
    user._on_model(version(1))
    first = check(11.1)
    user._on_check(first)
    assert user.act() is None
    assert user.progress.state.check_handled_ns == START_NS + 11_100_000_000
    assert user.progress.state.model_version_published == 0
    user._on_check(check(33.3, "angular:EBX"))
    user.act()
    # The lockstep bound on the answer; the version the request made, then the check.
    assert asked[0][3] == LOCKSTEP_ANSWER_S
    assert user.progress.state.model_version_published == 2
    assert user.progress.state.check_handled_ns == START_NS + 33_300_000_000


def test_the_user_holds_its_change_model_client_from_its_start(user_node):
    # Made with the node, so discovery has matched it long before the one request
    # (sent once: a change is not idempotent).
    user, _ = user_node(lockstep=False, stand_in=False)
    assert [client.srv_name for client in user.clients] == ["/model_monitor/change_model"]


def test_a_refused_request_is_kept_and_not_waited_on(user_node):
    user, asked = user_node(lockstep=True,
                            answer=ChangeOutcome(False, "no significant gain", 1))
    user._on_check(check(33.3, "warp"))
    action = user.act()
    assert (action["accepted"], action["reason"]) == (False, "no significant gain")
    assert user.progress.state.model_version_published == 0   # no version to wait for
    assert user.act() is None and len(asked) == 1


def test_the_node_keeps_alarms_statuses_and_readings_in_data_time(user_node):
    user, _ = user_node(lockstep=False)
    for axis, at_s, deteriorated in (("y", 49.0, False), ("y", 50.5, True), ("y", 52.0, True),
                                     ("x", 60.0, True)):
        profile = SystematicProfile(axis=axis, deterioration=deteriorated)
        profile.header.stamp = nanoseconds_to_stamp(START_NS + round(at_s * 1e9))
        user._on_profile(profile)
    assert user.alarms == [(pytest.approx(50.5, abs=1e-9), "y"),
                           (pytest.approx(60.0, abs=1e-9), "x")]

    def status(name, level=DiagnosticStatus.OK, message="", **values):
        return DiagnosticStatus(name=name, level=level, message=message,
                                values=[KeyValue(key=k, value=v) for k, v in values.items()])

    reading = ReferenceMeasurement()
    reading.header.stamp = nanoseconds_to_stamp(START_NS + 1_000_000_000)
    user._on_reference(reading)
    assert not user.monitor_done()
    user._on_diagnostics(DiagnosticArray(status=[
        status("/model_monitor: delivery", **{"reference/tcp_error.processed": "1",
                                              "warning.0": "slow search"}),
        status("/encoder_publisher: compensation", applied="5", stale="0"),
        status("/model_monitor: model", search_wall_s="1.5", search_cpu_s="1.25"),
        status("/model_monitor: inputs", DiagnosticStatus.ERROR, "temperatures stopped")]))
    assert user.monitor_done()
    assert user.delivery["/encoder_publisher:compensation"] == {"applied": "5", "stale": "0"}
    assert user.node_warnings == {"/model_monitor": ["slow search"]}
    assert user.searches == [(1.5, 1.25)]
    assert [text for _, text in user.model_alarms] == ["temperatures stopped"]
    assert user.references[0][0] == pytest.approx(1.0, abs=1e-12)
    assert user.orientations == [None]
