"""No input kills a node: bad messages and parameters to real node processes are
counted refusals with their reason on /diagnostics, and the node keeps working."""
from __future__ import annotations

import math
import os
import time

import pytest

from graph_helpers import scale_batch as _batch
from graph_helpers import set_parameter_again_until_answered, spin_until
from mt_accuracy_ros.commands.processes import start_node

BAD_MODELS = [
    "machine: kidani_hmc\neffects: [squareness]\n",       # effects a list
    "machine: kidani_hmc\nversion: two\n",                 # version not a number
    "machine: /bin/ls\n",                                  # a binary machine file
    "{machine: kidani_hmc, effects: {squareness: 3}}\n",  # effect parameters not a mapping
    # User effects: a syntax error, a forbidden construct, an unknown variable.
    "{machine: kidani_hmc, effects: {mine: {expression: 'k * (x +', parameters: [k]}}}\n",
    "{machine: kidani_hmc, effects: {mine: {expression: 'k * x.real', parameters: [k]}}}\n",
    "{machine: kidani_hmc, effects: {mine: {expression: 'k * q', parameters: [k]}}}\n",
]


def _refusals(diagnostics, stream):
    return [s.message for array in diagnostics for s in array.status
            if s.name.endswith("delivery") and s.message.startswith(f"{stream}: refused")]


def _broadcaster_and_peer(name: str):
    """A broadcaster process (input_delay_s 0: temperatures and profiles need not come
    first) and a peer node that hears its /diagnostics and compensation and publishes
    scales and models: (node, diagnostics, compensation, scales, model, broadcaster)."""
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray

    from mt_accuracy_msgs.msg import ModelVersion, ScaleBatch, VolumetricCompensation
    from mt_accuracy_ros.nodes._common import LATCHED_QOS, SENSOR_QOS
    from mt_accuracy_ros.nodes.compensation_broadcaster import COMPENSATION_QOS

    node = rclpy.create_node(name)
    diagnostics, compensation = [], []
    node.create_subscription(DiagnosticArray, "/diagnostics", diagnostics.append, 100)
    node.create_subscription(VolumetricCompensation, "compensation", compensation.append,
                             COMPENSATION_QOS)
    scales = node.create_publisher(ScaleBatch, "scales", SENSOR_QOS)
    model = node.create_publisher(ModelVersion, "model", LATCHED_QOS)
    broadcaster = start_node("compensation_broadcaster", {"input_delay_s": 0.0}, quiet=True)
    return node, diagnostics, compensation, scales, model, broadcaster


def test_broadcaster_survives_bad_batches_and_models_and_says_why(rclpy_context):
    from mt_accuracy_msgs.msg import ModelVersion

    node, diagnostics, compensation, scales, model, broadcaster = \
        _broadcaster_and_peer("fuzzer")
    try:
        assert spin_until(node, lambda: scales.get_subscription_count() > 0
                          and node.count_publishers("compensation") > 0, 30)
        assert spin_until(node, lambda: bool(diagnostics), 15)  # its 1 Hz report is flowing
        stamp = 1_000_000_000
        for index, period in enumerate([0.0, math.nan, -0.001, math.inf]):
            scales.publish(_batch(index * 50, stamp + index, period))
        assert spin_until(node, lambda: len(_refusals(diagnostics, "scales")) >= 4, 20)
        reasons = _refusals(diagnostics, "scales")
        assert all("sample_period" in r for r in reasons[:4]), reasons
        for sequence, text in enumerate(BAD_MODELS):
            model.publish(ModelVersion(version=5, model_yaml=text, sequence=sequence))
            assert spin_until(node, lambda: sum("model refused" in r for r in
                                                _refusals(diagnostics, "model"))
                              >= BAD_MODELS.index(text) + 1, 20), text
        # A good model with a version below the live one (1) is refused as old.
        model.publish(ModelVersion(version=0, model_yaml="machine: kidani_hmc\neffects: "
                                   "{squareness: {}}\n", sequence=len(BAD_MODELS)))
        assert spin_until(node, lambda: any("older than the live version 1" in r for r in
                                            _refusals(diagnostics, "model")), 20)
        assert broadcaster.popen.poll() is None, "the broadcaster died"
        # Still working: a good batch gives compensation with the starting model.
        scales.publish(_batch(1000, 2_000_000_000, 0.001))
        assert spin_until(node, lambda: bool(compensation), 20)
        assert compensation[0].model_version == 1
        # The counters say what happened.
        def counted():
            for array in diagnostics:
                for status in array.status:
                    values = {v.key: v.value for v in status.values}
                    if values.get("scales.refused") == "4" and \
                            values.get("model.refused") == str(len(BAD_MODELS) + 1):
                        return True
            return False
        assert spin_until(node, counted, 15)
    finally:
        broadcaster.stop()
        node.destroy_node()


@pytest.mark.parametrize("value", ["machine: kidani_hmc\neffects: [squareness]\n",
                                   "machine: kidani_hmc\nversion: two\n",
                                   BAD_MODELS[-3], BAD_MODELS[-1]])
def test_a_bad_model_parameter_is_refused_and_the_monitor_lives(rclpy_context, value):
    import rclpy

    node = rclpy.create_node("setter")
    # Every setting here is refused or repeats a plain value: asking again is safe, and
    # needed when this monitor has just replaced the previous case's one under the
    # same name (the graph still lists the old one's service for a moment).
    _set_parameter = set_parameter_again_until_answered
    monitor = start_node("model_monitor", quiet=True)
    try:
        successful, reason = _set_parameter(node, "model_monitor", "model", value)
        assert not successful and "model refused" in reason, reason
        if "mine" in value:
            assert "user effect 'mine'" in reason, reason   # the effect is named
        # An effect name nobody knows is refused, named, and the monitor lives on.
        successful, reason = _set_parameter(node, "model_monitor", "add_effects", ["warp"])
        assert not successful and "unknown effect 'warp'" in reason, reason
        assert monitor.popen.poll() is None
        successful, reason = _set_parameter(node, "model_monitor", "min_reduction", 0.2)
        assert successful, reason
    finally:
        monitor.stop()
        node.destroy_node()


def test_a_network_model_opens_no_file_and_quotes_none(rclpy_context, tmp_path):
    """Issue 29: paths on the model topic and in a run-time model parameter are refused
    before anything is opened (a FIFO, /dev/zero, a secret, a valid model elsewhere);
    no refusal quotes a file; the broadcaster keeps compensating with its model."""
    from mt_accuracy_msgs.msg import ModelVersion

    secret = tmp_path / "secret.yaml"
    secret.write_text('user: root\npassword: "hunter2\n')
    elsewhere = tmp_path / "valid.yaml"
    elsewhere.write_text("machine: kidani_hmc\neffects: {squareness: {errors_rad: "
                         "{EC0Y: 1.0e-5}}}\n")
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    probes = ["/etc/passwd", "/proc/self/environ", "/dev/zero", str(fifo), str(elsewhere),
              str(secret), f"{{machine: {secret}}}", "{machine: ../../../../etc/passwd}"]
    node, diagnostics, compensation, scales, model, broadcaster = _broadcaster_and_peer("peer")
    try:
        assert spin_until(node, lambda: node.count_subscribers("model") > 0
                          and node.count_publishers("compensation") > 0, 30)
        for sequence, text in enumerate(probes):
            model.publish(ModelVersion(version=5, model_yaml=text, sequence=sequence))
            assert spin_until(node, lambda: sum("model refused" in r for r in
                                                _refusals(diagnostics, "model"))
                              >= sequence + 1, 20), text
        for text in probes:
            ok, reason = set_parameter_again_until_answered(node, "compensation_broadcaster",
                                                            "model", text)
            assert not ok and "never a path" in reason, (text, reason)
            assert "hunter2" not in reason
        refusals = _refusals(diagnostics, "model")
        assert all("never a path" in r for r in refusals), refusals
        every_text = " ".join(s.message + " ".join(v.value for v in s.values)
                              for array in diagnostics for s in array.status)
        assert "hunter2" not in every_text and "root:" not in every_text
        assert broadcaster.popen.poll() is None, "the broadcaster died"
        scales.publish(_batch(0, 2_000_000_000, 0.001))
        assert spin_until(node, lambda: bool(compensation), 20)
        assert compensation[-1].model_version == 1    # nothing from elsewhere went live
    finally:
        broadcaster.stop()
        node.destroy_node()


def test_a_live_model_that_fails_at_the_machine_gives_way_to_the_last_good_one(rclpy_context):
    """Issue 29: a version that passed every load-time check (finite on the machine's
    travel and temperature range) but overflows on what the machine then meets - a
    temperature beyond the checked range - does not stop compensation: the last version
    that evaluated is live again, counted, with an ERROR on /diagnostics."""
    from mt_accuracy_msgs.msg import ModelVersion, TemperatureArray
    from mt_accuracy_ros.io.fields import nanoseconds_to_stamp
    from mt_accuracy_ros.nodes._common import SENSOR_QOS

    # T_bed is the rise above the first reading: exp(40 T) is 1e260 at the checked +15 K,
    # inf at the +25 K the machine then meets.
    fragile = ("{machine: kidani_hmc, effects: {warm: {expression: 'k * x * exp(40 * T_bed)', "
               "parameters: [k], values: {k: 1.0e-300}}}}")
    node, diagnostics, compensation, scales, model, broadcaster = _broadcaster_and_peer("peer")
    temperatures = node.create_publisher(TemperatureArray, "temperatures", SENSOR_QOS)

    def temperature(stamp_ns, value):
        message = TemperatureArray(sensor_names=["bed"], temperatures=[value])
        message.header.stamp = nanoseconds_to_stamp(stamp_ns)
        temperatures.publish(message)

    try:
        assert spin_until(node, lambda: scales.get_subscription_count() > 0
                          and node.count_subscribers("model") > 0
                          and node.count_publishers("compensation") > 0, 30)
        sent = {"index": 0, "at": 0.0}

        def live(version):
            # Best-effort batches: the first after discovery may be dropped - send on,
            # one batch per 50 ms of waiting.
            if time.monotonic() - sent["at"] > 0.05:
                sent["index"] += 1
                sent["at"] = time.monotonic()
                stamp = 1_000_000_000 + sent["index"] * 50_000_000   # 50 samples of 1 ms
                temperature(stamp - 1, 20.0)
                scales.publish(_batch(sent["index"] * 50, stamp, 0.001))
            return any(c.model_version == version for c in compensation)
        assert spin_until(node, lambda: live(1), 30), \
            [s.message for array in diagnostics for s in array.status][-5:]
        model.publish(ModelVersion(version=2, model_yaml=fragile, sequence=0))
        assert spin_until(node, lambda: live(2), 30), "version 2 never went live"
        # The warm reading first (another topic: it must be in before the data it precedes).
        following = sent["index"] + 1
        stamp = 1_000_000_000 + following * 50_000_000
        temperature(stamp - 1, 45.0)
        deadline = time.monotonic() + 1.0
        spin_until(node, lambda: time.monotonic() > deadline, 5)
        count = len(compensation)
        scales.publish(_batch(following * 50, stamp, 0.001))
        assert spin_until(node, lambda: len(compensation) > count, 20), \
            [s.message for array in diagnostics for s in array.status
             if s.message != "all streams complete"]
        assert all(c.model_version == 1 for c in compensation[count:]), (
            [c.model_version for c in compensation[count - 3:]],
            [s.message for array in diagnostics for s in array.status][-4:])
        assert all(math.isfinite(c.correction.x) for c in compensation[count:])
        assert spin_until(node, lambda: any(
            s.level == b"\x02" and "version 2 failed at the machine" in s.message
            for array in diagnostics for s in array.status), 15)
        assert broadcaster.popen.poll() is None
    finally:
        broadcaster.stop()
        node.destroy_node()


def test_forged_indices_and_stamps_going_back_are_refused_and_counted(rclpy_context):
    """Issue 29: a batch index of 2**64 - 1 and a stamp an hour ahead are refused by the
    estimator and the broadcaster (counted, with the reason), the lost counters stay
    true, and the estimator counts a stamp that went back as refused."""
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray

    from mt_accuracy_msgs.msg import ScaleBatch
    from mt_accuracy_ros.nodes._common import SENSOR_QOS

    node = rclpy.create_node("forger")
    diagnostics = []
    node.create_subscription(DiagnosticArray, "/diagnostics", diagnostics.append, 100)
    scales = node.create_publisher(ScaleBatch, "scales", SENSOR_QOS)
    nodes = [start_node("yaw_estimator", {"input_delay_s": 0.0}, quiet=True),
             start_node("compensation_broadcaster", {"input_delay_s": 0.0}, quiet=True)]

    def counters(name):
        out = {}
        for array in diagnostics:
            for status in array.status:
                if name in status.name and status.name.endswith("delivery"):
                    out.update({v.key: v.value for v in status.values})
        return out

    try:
        assert spin_until(node, lambda: scales.get_subscription_count() >= 2, 30)
        sent = {"index": 0, "at": 0.0}

        def genuine(count_needed):
            if time.monotonic() - sent["at"] > 0.05:
                sent["at"] = time.monotonic()
                scales.publish(_batch(sent["index"] * 50, 10**9 + sent["index"] * 50_000_000,
                                      0.001))
                sent["index"] += 1
            return all(int(counters(n).get("scales.processed", 0)) >= count_needed
                       for n in ("yaw_estimator", "compensation_broadcaster"))
        assert spin_until(node, lambda: genuine(100), 60)
        last_index, last_stamp = sent["index"] * 50, 10**9 + sent["index"] * 50_000_000
        scales.publish(_batch(2**64 - 1, last_stamp, 0.001))
        scales.publish(_batch(last_index, last_stamp + 3600 * 10**9, 0.001))
        scales.publish(_batch(last_index - 50, last_stamp - 50_000_000, 0.001))  # went back
        assert spin_until(node, lambda: all(int(counters(n).get("scales.refused", 0)) >= 3
                                            for n in ("yaw_estimator",
                                                      "compensation_broadcaster")), 20), \
            (counters("yaw_estimator"), counters("compensation_broadcaster"))
        processed = int(counters("compensation_broadcaster")["scales.processed"])
        assert spin_until(node, lambda: genuine(processed + 200), 60)
        for name in ("yaw_estimator", "compensation_broadcaster"):
            values = counters(name)
            assert int(values["scales.lost"]) < 1000, values     # a few dropped batches at most
            assert int(values["scales.refused"]) == 3, values
        reasons = [s.message for array in diagnostics for s in array.status]
        assert any("not a running count" in r for r in reasons)
        assert any("beyond the 60 s horizon" in r for r in reasons)
        assert any("yaw_estimator" in s.name and "went back" in s.message
                   for array in diagnostics for s in array.status)
        assert all(n.popen.poll() is None for n in nodes)
    finally:
        for n in nodes:
            n.stop()
        node.destroy_node()


def test_an_input_that_stops_is_reported_and_its_last_value_held(rclpy_context):
    """Issue 29: when the temperature source (or the estimator) stops, the broadcaster says
    so - WARN after input_timeout_s of data, ERROR after three times that - holds the last
    value, keeps compensating, and says when the input is back."""
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray

    from mt_accuracy_msgs.msg import ScaleBatch, TemperatureArray, VolumetricCompensation
    from mt_accuracy_ros.io.fields import nanoseconds_to_stamp
    from mt_accuracy_ros.nodes._common import SENSOR_QOS
    from mt_accuracy_ros.nodes.compensation_broadcaster import COMPENSATION_QOS

    node = rclpy.create_node("cnc")
    diagnostics, compensation = [], []
    node.create_subscription(DiagnosticArray, "/diagnostics", diagnostics.append, 100)
    node.create_subscription(VolumetricCompensation, "compensation", compensation.append,
                             COMPENSATION_QOS)
    scales = node.create_publisher(ScaleBatch, "scales", SENSOR_QOS)
    temperatures = node.create_publisher(TemperatureArray, "temperatures", SENSOR_QOS)
    broadcaster = start_node("compensation_broadcaster", {"input_delay_s": 0.0,
                                                          "input_timeout_s": 1.0}, quiet=True)
    sent = {"index": 0, "at": 0.0}

    def run(with_temperatures):
        # One 50 ms batch per 20 ms of waiting: data time runs 2.5x wall time.
        if time.monotonic() - sent["at"] > 0.02:
            sent["at"] = time.monotonic()
            stamp = 10**9 + sent["index"] * 50_000_000
            if with_temperatures:
                message = TemperatureArray(sensor_names=["column"], temperatures=[20.0])
                message.header.stamp = nanoseconds_to_stamp(stamp - 1)
                temperatures.publish(message)
            scales.publish(_batch(sent["index"] * 50, stamp, 0.001))
            sent["index"] += 1

    def said(level, words):
        return any(s.level == level and words in s.message and "compensation_broadcaster"
                   in s.name for array in diagnostics for s in array.status)

    try:
        assert spin_until(node, lambda: scales.get_subscription_count() > 0
                          and temperatures.get_subscription_count() > 0, 30)
        assert spin_until(node, lambda: run(True) or len(compensation) > 20, 30)
        assert not said(b"\x01", "temperatures: nothing for")
        assert spin_until(node, lambda: run(False) or said(b"\x01", "temperatures: nothing for"),
                          30)
        assert spin_until(node, lambda: run(False) or said(b"\x02", "temperatures: nothing for"),
                          30)
        count = len(compensation)
        assert spin_until(node, lambda: run(False) or len(compensation) > count + 10, 30)
        assert spin_until(node, lambda: run(True) or said(b"\x00", "temperatures: receiving "
                                                                    "again"), 30)
        assert broadcaster.popen.poll() is None
    finally:
        broadcaster.stop()
        node.destroy_node()


def test_scale_readings_outside_the_stroke_are_said_and_left_out_of_the_profile(
        rclpy_context):
    """X scales that read 100.0 for 0.1 m (mm published as m) lie outside kidani_hmc's X
    stroke 0..0.39 m: the estimator keeps running, says on /diagnostics how many and that
    they look like mm, and its profile takes none of them; readings on the stroke that
    follow are taken."""
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray

    from mt_accuracy_msgs.msg import ScaleBatch
    from mt_accuracy_ros.io.fields import pack_float64
    from mt_accuracy_ros.nodes._common import SENSOR_QOS

    node = rclpy.create_node("millimetre_scales")
    diagnostics = []
    node.create_subscription(DiagnosticArray, "/diagnostics", diagnostics.append, 100)
    scales = node.create_publisher(ScaleBatch, "scales", SENSOR_QOS)
    estimator = start_node("yaw_estimator", {"input_delay_s": 0.0, "profile_period_s": 0.1},
                           quiet=True)

    def axis_x():
        values = {}
        for array in diagnostics:
            for status in array.status:
                if status.name.endswith(": axis X"):
                    values = {v.key: v.value for v in status.values}
        return values

    try:
        assert spin_until(node, lambda: scales.get_subscription_count() >= 1, 30)
        sent = {"index": 0, "at": 0.0}

        def send(reading_m, until):
            if time.monotonic() - sent["at"] > 0.05:
                sent["at"] = time.monotonic()
                batch = _batch(sent["index"] * 50, 10**9 + sent["index"] * 50_000_000, 0.001)
                batch.positions = pack_float64([reading_m] * 100)
                scales.publish(batch)
                sent["index"] += 1
            return until()

        assert spin_until(node, lambda: send(100.0, lambda: int(
            axis_x().get("outside_stroke", 0)) >= 200), 60), axis_x()
        assert axis_x()["samples"] == "0"
        said = [s.message for array in diagnostics for s in array.status
                if s.name.endswith(": input") and "outside the stroke" in s.message]
        assert said and "readings at 100..100 m lie outside the stroke 0..0.39 m" in said[0]
        assert "the scales read in mm, not m?" in said[0]
        assert spin_until(node, lambda: send(0.1, lambda: int(
            axis_x().get("samples", 0)) >= 100), 60), axis_x()
        assert estimator.popen.poll() is None
    finally:
        estimator.stop()
        node.destroy_node()
