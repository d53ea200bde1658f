"""Which ScaleBatch sizes arrive on the ``scales`` topic, best effort and reliable.

A subscriber in another process counts what arrives; the publisher sends each size
``--repeats`` times, 0.3 s apart (no queueing), with 6 scale heads per sample. The
virtual CNC's start-up limit (``MAX_SCALE_BATCH_BYTES`` in
``mt_accuracy_ros/nodes/encoder_publisher.py``) comes from this measurement.

Usage: ``python -m bench.scale_batch_delivery [--repeats 3]``
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

SIZES = [1000, 5000, 10000, 20000, 30000, 40000, 50000, 65000, 100000]
CHANNELS = 6

_SUBSCRIBER = r'''
import json, sys
import rclpy
from mt_accuracy_msgs.msg import ScaleBatch
from mt_accuracy_ros.nodes._common import RESULT_QOS, SENSOR_QOS
rclpy.init()
node = rclpy.create_node("batch_counter")
qos = SENSOR_QOS if sys.argv[1] == "best_effort" else RESULT_QOS
node.create_subscription(ScaleBatch, "batch_delivery", lambda m: print(
    json.dumps(int(m.first_sample_index)), flush=True), qos)
try:
    rclpy.spin(node)
except BaseException:
    pass
'''


def measure(mode: str, repeats: int) -> dict[int, int]:
    import rclpy

    from mt_accuracy_msgs.msg import ScaleBatch
    from mt_accuracy_ros.io.fields import pack_float64
    from mt_accuracy_ros.nodes._common import RESULT_QOS, SENSOR_QOS

    rclpy.init()
    node = rclpy.create_node("batch_sender")
    publisher = node.create_publisher(ScaleBatch, "batch_delivery",
                                      SENSOR_QOS if mode == "best_effort" else RESULT_QOS)
    child = subprocess.Popen([sys.executable, "-c", _SUBSCRIBER, mode], stdout=subprocess.PIPE,
                             stderr=subprocess.DEVNULL, text=True)
    try:
        deadline = time.time() + 30
        while publisher.get_subscription_count() == 0 and time.time() < deadline:
            rclpy.spin_once(node, timeout_sec=0.1)
        time.sleep(1.0)
        for i, size in enumerate(SIZES):
            for repeat in range(repeats):
                message = ScaleBatch(first_sample_index=i * 100 + repeat, sample_period=1e-3,
                                     channel_names=[f"{a}{k}" for a in "xyz" for k in "12"])
                message.positions = pack_float64([0.1] * (CHANNELS * size))
                publisher.publish(message)
                time.sleep(0.3)
        time.sleep(2.0)
    finally:
        child.terminate()
        try:
            out = child.communicate(timeout=10)[0]
        except subprocess.TimeoutExpired:
            child.kill()         # its lines are flushed as they come: nothing is lost
            out = child.communicate()[0]
        node.destroy_node()
        rclpy.try_shutdown()
    arrived = {size: 0 for size in SIZES}
    for line in out.splitlines():
        if line.strip():
            arrived[SIZES[json.loads(line) // 100]] += 1
    return arrived


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    for mode in ("best_effort", "reliable"):
        arrived = measure(mode, args.repeats)
        print(json.dumps({"qos": mode, "arrived": {
            f"{size} samples ({size * CHANNELS * 8 / 1e6:.2f} MB)": f"{n}/{args.repeats}"
            for size, n in arrived.items()}}), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
