"""Bag writer, reader and recorder-node throughput at the demo's data rates (issue 8).

The demo's heaviest stream: 6 scale heads sampled at 20 kHz, published as 100
ScaleBatch messages per second (200 samples x 6 channels, ~9.7 kB each).

* writer: BagWriter messages/s and MB/s (zstd and uncompressed);
* reader: read_messages + decode, as a multiple of real time (the bag's duration
  divided by the read time); baseline in the same run: the rosbags library
  reading and deserialising the same file;
* recorder node: a publisher here, the recorder in its own process, 10 s at the
  demo's rate; published vs recorded count (drops).
"""
from __future__ import annotations

import argparse
import json
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

SAMPLE_RATE_HZ = 20_000
BATCH_HZ = 100
CHANNELS = ["x1", "x2", "y1", "y2", "z1", "z2"]


def _batch(index: int, rng):
    from mt_accuracy_msgs.msg import ScaleBatch

    from mt_accuracy_ros.io.fields import nanoseconds_to_stamp, pack_float64

    per_batch = SAMPLE_RATE_HZ // BATCH_HZ
    message = ScaleBatch()
    message.header.stamp = nanoseconds_to_stamp(10**18 + index * 10**9 // BATCH_HZ)
    message.first_sample_index = index * per_batch
    message.sample_period = 1.0 / SAMPLE_RATE_HZ
    message.channel_names = CHANNELS
    message.positions = pack_float64(rng.normal(0.1, 0.05, per_batch * len(CHANNELS)))
    message.command_axes = ["x", "y", "z"]
    message.command_positions = pack_float64(rng.normal(0.1, 0.05, per_batch * 3))
    return message


def bench_files(seconds: float, workdir: Path) -> dict:
    from rclpy.serialization import serialize_message
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg

    from mt_accuracy_ros.io.bag_reader import decode, read_messages
    from mt_accuracy_ros.io.bag_writer import BagWriter, qos_dict

    rng = np.random.default_rng(0)
    count = int(seconds * BATCH_HZ)
    payloads = [serialize_message(_batch(i, rng)) for i in range(count)]
    megabytes = sum(len(p) for p in payloads) / 1e6
    results = {"messages": count, "payload_MB": megabytes, "bag_duration_s": seconds}
    for compression in ("zstd", None):
        path = workdir / f"bag_{compression}"
        start = time.perf_counter()
        with BagWriter(path, compression=compression) as bag:
            bag.add_topic("/scales", "mt_accuracy_msgs/msg/ScaleBatch",
                          qos_dict(reliability="best_effort", depth=5))
            for i, payload in enumerate(payloads):
                t = 10**18 + i * 10**9 // BATCH_HZ
                bag.write("/scales", payload, t, t)
        elapsed = time.perf_counter() - start
        label = compression or "none"
        results[f"write_{label}"] = {"messages_per_s": count / elapsed,
                                     "MB_per_s": megabytes / elapsed,
                                     "file_MB": (path / f"{path.name}_0.mcap").stat().st_size / 1e6}
        start = time.perf_counter()
        decoded = sum(1 for m in read_messages(path) if decode(m) is not None)
        elapsed = time.perf_counter() - start
        assert decoded == count
        results[f"read_decode_{label}"] = {"messages_per_s": count / elapsed,
                                           "times_real_time": seconds / elapsed}
        store = get_typestore(Stores.ROS2_JAZZY)
        start = time.perf_counter()
        with Reader(path) as reader:
            for connection in reader.connections:
                store.register(get_types_from_msg(connection.msgdef.data, connection.msgtype))
            n = sum(1 for c, _, raw in reader.messages()
                    if store.deserialize_cdr(raw, c.msgtype) is not None)
        elapsed = time.perf_counter() - start
        assert n == count
        results[f"rosbags_read_decode_{label}"] = {"messages_per_s": count / elapsed,
                                                   "times_real_time": seconds / elapsed}
    return results


def bench_recorder(seconds: float, workdir: Path) -> dict:
    import rclpy

    from mt_accuracy_msgs.msg import ScaleBatch
    from mt_accuracy_ros.io.bag_reader import bag_info
    from mt_accuracy_ros.nodes._common import SENSOR_QOS
    from mt_accuracy_ros.commands.processes import start_node

    rclpy.init()
    node = rclpy.create_node("bench_publisher")
    publisher = node.create_publisher(ScaleBatch, "/scales", SENSOR_QOS)
    recorder = start_node("recorder", {"output": str(workdir / "recorded"),
                                       "topics": ["/scales"], "discovery_period_s": 0.1},
                          quiet=True)
    deadline = time.monotonic() + 30
    while publisher.get_subscription_count() < 1 and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)
    rng = np.random.default_rng(1)
    messages = [_batch(i, rng) for i in range(int(seconds * BATCH_HZ))]
    start = time.monotonic()
    for i, message in enumerate(messages):
        due = start + i / BATCH_HZ
        while time.monotonic() < due:
            time.sleep(max(0.0, min(0.001, due - time.monotonic())))
        publisher.publish(message)
    time.sleep(1.0)
    recorder.stop()
    node.destroy_node()
    rclpy.try_shutdown()
    recorded = bag_info(workdir / "recorded")["topics"]["/scales"]["count"]
    return {"published": len(messages), "recorded": recorded,
            "dropped": len(messages) - recorded,
            "MB_per_s": len(messages) * len(bytes(_serialized(messages[0]))) / 1e6 / seconds}


def _serialized(message) -> bytes:
    from rclpy.serialization import serialize_message

    return serialize_message(message)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=60.0, help="simulated bag length")
    parser.add_argument("--recorder-seconds", type=float, default=10.0)
    args = parser.parse_args()
    workdir = Path(tempfile.mkdtemp(prefix="bag_bench_"))
    try:
        out = {"files": bench_files(args.seconds, workdir),
               "recorder_node": bench_recorder(args.recorder_seconds, workdir)}
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
