"""Lockstep (issue 39): the virtual machine streams in data time, each batch once every
participant has caught up. Real processes: the encoder publisher and the temperature
publisher; this process is the participant the machine waits for."""
from __future__ import annotations

from graph_helpers import spin_for, spin_until
from mt_accuracy_ros.commands.processes import start_node


def test_the_machine_waits_for_its_participant_and_leaves_a_silent_one_out(rclpy_context):
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from mt_accuracy_msgs.msg import ScaleBatch, TemperatureArray

    from mt_accuracy_ros.nodes._common import SENSOR_QOS, stamp_to_nanoseconds
    from mt_accuracy_ros.nodes._lockstep import ProgressReporter, batch_end_ns

    node = rclpy.create_node("lockstep_tester")
    batches, temperatures, warnings = [], [], []
    node.create_subscription(ScaleBatch, "scales", batches.append, SENSOR_QOS)
    node.create_subscription(TemperatureArray, "temperatures", temperatures.append, SENSOR_QOS)
    node.create_subscription(DiagnosticArray, "/diagnostics", lambda m: warnings.extend(
        s.message for s in m.status if "lockstep" in s.message), 50)
    machine = {"scenario": "demo", "start_stamp_ns": 0, "lockstep": True}
    thermometers = start_node("temperature_publisher", {**machine, "min_subscribers": 1},
                              quiet=True)
    # Two participants: this tester (scales, 20 ms lead) and one that never comes (left
    # out after 10 s of wall time, with a WARN: a dead node must not hang the machine).
    encoder = start_node("encoder_publisher", {
        **machine, "min_subscribers": 1, "batch_period_s": 0.01, "lockstep_lead_s": 0.02,
        "lockstep_timeout_s": 10.0, "reference_period_s": 0.0,
        "lockstep_nodes": ["lockstep_tester:scales", "temperature_publisher:temperatures"]},
        quiet=True)
    reporter = ProgressReporter(node, "lockstep_tester")
    try:
        # Silent, the tester holds the stream at the lead: batches [0, 10), [10, 20) and
        # [20, 30) ms may go out unhandled, the next one may not - however long we wait.
        # A deadline only against a hung machine: it ends at the third batch; beside two
        # CPU burners the machine took more than 60 s to start and match its subscribers.
        assert spin_until(node, lambda: len(batches) >= 3, 240.0), len(batches)
        spin_for(node, 3.0)
        n = round(0.01 / batches[0].sample_period)   # samples per 10 ms batch
        assert [b.first_sample_index for b in batches] == [0, n, 2 * n]
        start = stamp_to_nanoseconds(batches[0].header.stamp)
        # The temperatures followed the machine's data time, not the wall clock: only
        # those stamped up to the stream's position are out (the first, at its start).
        assert temperatures and all(stamp_to_nanoseconds(t.header.stamp) <= start + 30_000_000
                                    for t in temperatures)
        # Handled up to the third batch's end: exactly the batches the lead allows follow.
        reporter.report(handled_ns=batch_end_ns(batches[2]))
        assert spin_until(node, lambda: len(batches) >= 6, 30.0)
        spin_for(node, 2.0)
        assert [b.first_sample_index for b in batches] == [k * n for k in range(6)]
        # The stamps are data time: 10 ms apart, whatever the wall clock did meanwhile.
        stamps = [stamp_to_nanoseconds(b.header.stamp) for b in batches]
        assert [s - start for s in stamps] == [k * 10_000_000 for k in range(6)]
        assert warnings == []
        # Silent again: after the timeout the tester is left out, said on /diagnostics,
        # and the stream goes on.
        assert spin_until(node, lambda: len(batches) > 50, 60.0), len(batches)
        assert any("lockstep: lockstep_tester held the stream" in w and "without it" in w
                   for w in warnings), warnings
    finally:
        encoder.stop()
        thermometers.stop()
        node.destroy_node()
