"""Each custom message makes a real trip: publisher in one process, subscriber in this one."""
from __future__ import annotations

import subprocess
import sys
import textwrap
import time

import pytest

from conftest import REPO_ROOT

MESSAGE_TYPES = ["ScaleBatch", "TemperatureArray", "YawBatch", "SystematicProfile",
                 "VolumetricCompensation", "CompensationTable", "EffectScore", "ModelCheck",
                 "ReferenceMeasurement"]

PUBLISHER = textwrap.dedent("""
    import sys, time
    sys.path.insert(0, {test_dir!r})
    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy
    import mt_accuracy_msgs.msg as m
    from msg_fill import filled
    rclpy.init()
    node = rclpy.create_node('roundtrip_publisher')
    qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
    pubs = [(node.create_publisher(getattr(m, t), 'roundtrip/' + t, qos), getattr(m, t))
            for t in {types!r}]
    for pub, cls in pubs:
        pub.publish(filled(cls(), 5))
    end = time.monotonic() + 30
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.1)
    """)


@pytest.fixture(scope="module")
def received():
    """Every message type as the other process published it. The subscriber has a context
    and an executor of its own (never the process-wide ones other test files share) and
    is torn down in rclpy's order: the executor, the node, the context - and only then is
    the publisher's process ended (a loaded run once crashed inside destroy_node)."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    import mt_accuracy_msgs.msg as messages

    code = PUBLISHER.format(test_dir=str(REPO_ROOT / "test"), types=MESSAGE_TYPES)
    publisher = subprocess.Popen([sys.executable, "-c", code])
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("roundtrip_subscriber", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
    got: dict[str, object] = {}
    for type_name in MESSAGE_TYPES:
        node.create_subscription(getattr(messages, type_name), "roundtrip/" + type_name,
                                 lambda msg, t=type_name: got.setdefault(t, msg), qos)
    try:
        # A timeout against a hung graph, not a speed requirement.
        deadline = time.monotonic() + 25
        while len(got) < len(MESSAGE_TYPES) and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.1)
    finally:
        executor.remove_node(node)
        executor.shutdown()
        node.destroy_node()
        context.try_shutdown()
        publisher.kill()
        publisher.wait()
    return got


@pytest.mark.parametrize("type_name", MESSAGE_TYPES)
def test_message_round_trips_between_processes(received, type_name):
    import mt_accuracy_msgs.msg as messages
    from msg_fill import filled

    assert type_name in received, f"{type_name} never arrived from the other process"
    expected = filled(getattr(messages, type_name)(), 5)
    assert received[type_name] == expected
    # The fill really populated something: an empty message must differ.
    assert received[type_name] != getattr(messages, type_name)()


@pytest.mark.parametrize("type_name", MESSAGE_TYPES)
def test_every_field_is_documented_with_a_unit_or_meaning(type_name):
    text = (REPO_ROOT / "msg_defs" / "msg" / f"{type_name}.msg").read_text()
    for line in text.splitlines():
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        assert "#" in stripped or stripped.startswith(("std_msgs/Header", "EffectScore[]")), \
            f"{type_name}: field without a comment: {stripped!r}"
