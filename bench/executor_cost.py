"""CPU a node spends per message received, in rclpy's two executors.

A subscriber process spins one node (one subscription, the parameter services) in
a single-threaded executor or in the events executor; a publisher sends it
``--messages`` messages (a lockstep ``DataProgress`` or a ``YawBatch`` of 200
samples, 500 a second). The subscriber's process CPU per message
received is printed as JSON: the cost of a wake-up, which the nodes that take a
message per scale batch pay 9000 times per main job (``nodes/_common.node_executor``)::

    ROS_DOMAIN_ID=95 .venv/bin/python -m bench.executor_cost
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time


def _message(kind: str):
    from mt_accuracy_msgs.msg import DataProgress, YawBatch

    from mt_accuracy_ros.io.fields import pack_float64

    if kind == "progress":
        return DataProgress(node="encoder_publisher")
    message = YawBatch()
    message.positions = message.yaw = message.thermal_correction = pack_float64([0.0] * 200)
    return message


def _qos(kind: str):
    from mt_accuracy_ros.nodes._common import RESULT_QOS
    from mt_accuracy_ros.nodes._lockstep import lockstep_qos

    return lockstep_qos() if kind == "progress" else RESULT_QOS


def subscriber(kind: str, events: bool, expected: int, timeout_s: float) -> dict:
    """Spin until ``expected`` messages came (or ``timeout_s``): CPU per message [us]."""
    import rclpy

    from mt_accuracy_ros.nodes._common import node_executor

    rclpy.init()
    node = rclpy.create_node("executor_cost_sub")
    count = [0]
    node.create_subscription(type(_message(kind)), f"executor_cost_{kind}",
                             lambda _: count.__setitem__(0, count[0] + 1), _qos(kind))
    executor = node_executor(node, events=events)
    end = time.monotonic() + timeout_s
    first = last = None   # (process CPU [s], count) at the first and the latest message
    quiet_since = time.monotonic()
    while time.monotonic() < end and count[0] < expected:
        seen = count[0]
        executor.spin_once(timeout_sec=0.05)
        if count[0] != seen:
            last, quiet_since = (time.process_time(), count[0]), time.monotonic()
            first = first or last
        elif first is not None and time.monotonic() - quiet_since > 3.0:
            break   # the publisher is done: the idle spinning after it is not counted
    cpu = last[0] - first[0] if first else 0.0
    received = last[1] - first[1] if first else 0
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown()
    return {"received": count[0], "cpu_per_message_us": round(cpu / max(received, 1) * 1e6, 1)}


def publisher(kind: str, messages: int) -> None:
    import rclpy

    rclpy.init()
    node = rclpy.create_node("executor_cost_pub")
    publisher = node.create_publisher(type(_message(kind)), f"executor_cost_{kind}", _qos(kind))
    while publisher.get_subscription_count() < 1:
        rclpy.spin_once(node, timeout_sec=0.1)
    time.sleep(1.0)   # the subscriber's reader matched too
    message = _message(kind)
    for _ in range(messages):
        publisher.publish(message)
        time.sleep(0.002)   # 500 a second: both executors keep up, nothing is dropped
    time.sleep(1.0)
    node.destroy_node()
    rclpy.try_shutdown()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--messages", type=int, default=3000)
    parser.add_argument("--role", choices=["sub", "pub"], default=None)
    parser.add_argument("--kind", default="progress")
    parser.add_argument("--events", action="store_true")
    args = parser.parse_args()
    if args.role == "sub":
        print(json.dumps(subscriber(args.kind, args.events, args.messages, 60.0)))
        return 0
    if args.role == "pub":
        publisher(args.kind, args.messages)
        return 0
    results = []
    for kind in ("progress", "yaw"):
        for events in (False, True):
            command = [sys.executable, "-m", "bench.executor_cost", "--kind", kind,
                       "--messages", str(args.messages), "--role"]
            sub = subprocess.Popen(command + ["sub"] + (["--events"] if events else []),
                                   stdout=subprocess.PIPE, text=True)
            subprocess.run(command + ["pub"], check=True)
            out, _ = sub.communicate(timeout=120)
            results.append({"message": kind, "executor": "events" if events else
                            "single-threaded", **json.loads(out)})
    print(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
