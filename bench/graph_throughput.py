"""End-to-end throughput and latency of the live graph (issues 7 and 18).

Sustained 20 kHz x 6 scale heads for ``--seconds``: encoder publisher (the
virtual CNC) -> yaw estimator and compensation broadcaster -> back to the
CNC, each its own process, this process listening. Reports batches published /
received by the estimator (every first_sample_index accounted for),
compensation messages (expected: 100 Hz of data time), CPU per node, and two
latencies:

* **stamp -> applied**, measured by the CNC itself (``compensation_input:
  realtime`` with no fixed delay and a 1 ms controller cycle): from a
  sample's stamp to the controller cycle at which the correction computed
  for it is applied - the latency issue 18 bounds (p99 <= 20 ms);
* stamp -> arrival of the compensation at this listener.

``--batch-periods 0.05 0.02 0.01 0.005 0.002`` sweeps the scale batch period
in one run.

Baseline in the same run: the per-sample design - one ``sensor_msgs/JointState``
(6 positions) per sample - publishing as fast as it can from one process to a
subscriber in another, messages/s received.
"""
from __future__ import annotations

import argparse
import json
import struct
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np

SCENARIO = """machine: kidani_hmc
seed: 1
duration_s: {seconds}
sample_rate_hz: 20000
temperature_rate_hz: 1
program: {{type: back_and_forth, axes: [X, Y, Z], feed_m_per_min: 30}}
effects: {{scale_thermal_expansion: true, timing_skew: true}}
"""

#: Extra yaw-estimator parameters (``--reselect-every``).
ESTIMATOR: dict = {}
#: ``--monitor``: the model monitor searching continuously - a check after every
#: reference reading (one every ``--reference-period`` of data), on windows of up to
#: 600 readings: the next search starts as soon as one ends.
MONITOR = {"model": "demo", "window": 600, "check_every": 1, "min_readings": 30}
REFERENCE = {"period_s": 0.1}
#: ``--niceness``: what the compensation path's nodes (encoder/CNC, estimator,
#: broadcaster) are given.
PATH: dict = {}
#: ``--burners``: CPU-burning processes alongside (a loaded host).
BURNERS = {"count": 0}

JOINT_STATE_PUBLISHER = textwrap.dedent("""
    import time, rclpy
    from sensor_msgs.msg import JointState
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    rclpy.init()
    node = rclpy.create_node('joint_state_source')
    pub = node.create_publisher(JointState, '/per_sample', QoSProfile(depth=1000,
                                reliability=ReliabilityPolicy.RELIABLE))
    while pub.get_subscription_count() < 1:
        rclpy.spin_once(node, timeout_sec=0.05)
    time.sleep(0.5)
    end = time.monotonic() + {seconds}
    i = 0
    while time.monotonic() < end:
        msg = JointState(name=['x1', 'x2', 'y1', 'y2', 'z1', 'z2'], position=[float(i)] * 6)
        msg.header.stamp = node.get_clock().now().to_msg()
        pub.publish(msg)
        i += 1
    print(i, flush=True)
    time.sleep(1.0)
    node.destroy_node()
    rclpy.try_shutdown()
    """)


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process so far [s]."""
    import os

    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def bench_graph(seconds: float, batch_period_s: float = 0.05, monitor: bool = False) -> dict:
    import rclpy

    from diagnostic_msgs.msg import DiagnosticArray
    from mt_accuracy_msgs.msg import ModelCheck, VolumetricCompensation, YawBatch
    from mt_accuracy_ros.nodes._common import RESULT_QOS, stamp_to_nanoseconds
    from mt_accuracy_ros.commands.processes import start_node

    workdir = Path(tempfile.mkdtemp(prefix="graph_bench_"))
    (workdir / "s.yaml").write_text(SCENARIO.format(seconds=seconds))
    rclpy.init()
    node = rclpy.create_node("bench_listener")
    yaw_indices: list[int] = []
    latencies: list[float] = []
    counts = {"compensation": 0}

    # Per stage (issue 27): each scale batch's publish time (its writer's source
    # timestamp) and each correction's publish and arrival times.
    batch_published: dict[int, int] = {}
    corrections: list[tuple[int, int, int]] = []   # (stamp, published, received) [ns]

    def on_scales(serialized: bytes, info) -> None:
        # Raw CDR (a batch is ~10 kB of samples; decoding them would load this listener):
        # 4 bytes of encapsulation, then header.stamp = int32 sec, uint32 nanosec.
        sec, nanosec = struct.unpack_from("<iI" if serialized[1] else ">iI", serialized, 4)
        batch_published[sec * 1_000_000_000 + nanosec] = int(info["source_timestamp"])

    def on_compensation(message: VolumetricCompensation, info) -> None:
        counts["compensation"] += 1
        stamp = stamp_to_nanoseconds(message.header.stamp)
        latencies.append((time.time_ns() - stamp) / 1e6)
        corrections.append((stamp, int(info["source_timestamp"]),
                            int(info["received_timestamp"])))

    # Deep enough that this listener (not on the path, normal priority) never drops
    # batches itself when a loaded host delays it: "lost" is then the path's loss.
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    node.create_subscription(YawBatch, "yaw/x", lambda m: yaw_indices.append(
        int(m.first_sample_index)), QoSProfile(depth=5000,
                                               reliability=ReliabilityPolicy.RELIABLE))
    node.create_subscription(VolumetricCompensation, "compensation", on_compensation, RESULT_QOS)
    from mt_accuracy_msgs.msg import ScaleBatch
    from mt_accuracy_ros.nodes._common import SENSOR_QOS

    node.create_subscription(ScaleBatch, "scales", on_scales, SENSOR_QOS, raw=True)
    controller: dict[str, str] = {}
    estimator_counts: dict[str, str] = {}

    def on_diagnostics(message: DiagnosticArray) -> None:
        for status in message.status:
            if status.name.endswith("yaw_estimator: delivery"):
                # The estimator's own count of scale samples lost between it and the CNC.
                estimator_counts.update({v.key: v.value for v in status.values})
            if status.name.endswith("encoder_publisher: compensation"):
                controller.update({v.key: v.value for v in status.values})

    node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, 50)
    checks: list[int] = []
    node.create_subscription(ModelCheck, "model_check", lambda m: checks.append(
        int(m.sample_count)), RESULT_QOS)
    monitor_process = start_node("model_monitor", MONITOR, quiet=True) if monitor else None
    estimator = start_node("yaw_estimator", {"thermal_correction": False, **ESTIMATOR, **PATH},
                           quiet=True)
    compensator = start_node("compensation_broadcaster", {"model": "demo", **PATH}, quiet=True)
    while node.count_subscribers("/scales") < 2 or node.count_publishers("/compensation") < 1 \
            or (monitor and node.count_subscribers("reference/tcp_error") < 1):
        rclpy.spin_once(node, timeout_sec=0.05)
    encoder = start_node("encoder_publisher", {"scenario": str(workdir / "s.yaml"),
                                               "min_subscribers": 2,
                                               "batch_period_s": batch_period_s,
                                               "compensation_input": "realtime",
                                               "compensation_delay_s": 0.0,
                                               "controller_cycle_s": 0.001,
                                               "max_compensation_age_s": 1.0,
                                               "reference_period_s":
                                               REFERENCE["period_s"], **PATH},
                         quiet=True)
    burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
               for _ in range(BURNERS["count"])]
    processes = {"encoder_publisher": encoder, "yaw_estimator": estimator,
                 "compensation_broadcaster": compensator}
    if monitor_process is not None:
        processes["model_monitor"] = monitor_process
    cpu_before = {name: cpu_seconds(p.popen.pid) for name, p in processes.items()}
    started = time.monotonic()
    cpu_after = dict(cpu_before)
    while encoder.popen.poll() is None and time.monotonic() - started < seconds + 60:
        rclpy.spin_once(node, timeout_sec=0.01)
        for name, process in processes.items():
            try:
                cpu_after[name] = cpu_seconds(process.popen.pid)
            except OSError:
                pass  # the encoder has finished
    end = time.monotonic() + 2.0
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.01)
    for burner in burners:
        burner.kill()
        burner.wait()
    for process in (estimator, compensator, monitor_process):
        if process is not None:
            process.stop()
    node.destroy_node()
    rclpy.try_shutdown()
    per_batch = int(round(20000 * batch_period_s))
    batches = int(seconds * 20000) // per_batch
    expected_indices = list(range(0, int(seconds * 20000), per_batch))
    elapsed = max(time.monotonic() - started, 1e-9)
    stages = stage_latencies(batch_published, corrections, batch_period_s)
    return {"samples_per_s": 20000, "channels": 6, "seconds": seconds,
            "stages_ms": stages,
            "batch_period_s": batch_period_s,
            "path_niceness": PATH.get("niceness", 0), "burners": len(burners),
            "cpu_percent": {name: round(100 * (cpu_after[name] - cpu_before[name]) / elapsed, 1)
                            for name in processes},
            "batches_expected": batches, "yaw_batches_received": len(yaw_indices),
            "lost_samples": (len(expected_indices) - len(set(yaw_indices))) * per_batch,
            "estimator_scales_lost": int(estimator_counts.get("scales.lost", -1)),
            "compensation_expected": int(seconds * 100),
            "compensation_received": counts["compensation"],
            "applied_latency_ms_p50": float(controller.get("latency_p50_ms", "nan")),
            "applied_latency_ms_p99": float(controller.get("latency_p99_ms", "nan")),
            "applied_latency_ms_max": float(controller.get("latency_max_ms", "nan")),
            "compensation_applied": int(controller.get("applied", 0)),
            "compensation_stale": int(controller.get("stale", 0)),
            "monitor_checks": len(checks) if monitor else None,
            "monitor_largest_window": max(checks, default=0) if monitor else None,
            "latency_ms_p50": float(np.percentile(latencies, 50)) if latencies else None,
            "latency_ms_p99": float(np.percentile(latencies, 99)) if latencies else None,
            "latency_ms_max": float(np.max(latencies)) if latencies else None}


#: Histogram bins of the per-stage latencies [ms].
STAGE_BINS_MS = (0, 1, 2, 5, 10, 20, 50, 100, 1e9)


def _summary(values_ms: list[float]) -> dict:
    if not values_ms:
        return {}
    values = np.asarray(values_ms)
    counts, _ = np.histogram(values, bins=STAGE_BINS_MS)
    labels = [f"{a:g}-{b:g}" if b < 1e9 else f">{a:g}" for a, b in
              zip(STAGE_BINS_MS[:-1], STAGE_BINS_MS[1:])]
    return {"p50": round(float(np.percentile(values, 50)), 2),
            "p99": round(float(np.percentile(values, 99)), 2),
            "max": round(float(values.max()), 2),
            "histogram": dict(zip(labels, (int(c) for c in counts)))}


def stage_latencies(batch_published: dict[int, int], corrections: list[tuple[int, int, int]],
                    batch_period_s: float) -> dict:
    """Where a correction's time goes, per stage [ms]:

    * ``batching``: from the sample's stamp to its scale batch's publication (the encoder
      collects a batch period of samples, then its timer must run);
    * ``broadcaster``: batch published -> correction published (DDS delivery to the
      broadcaster, its queue, and its computation);
    * ``delivery``: correction published -> received by a subscriber (this listener,
      a process like the CNC's);
    * the CNC's own ``stamp -> applied`` is ``applied_latency_ms_*``: the three above,
      its queue and the 1 ms controller cycle.
    """
    starts = np.array(sorted(batch_published))
    batching, broadcaster, delivery = [], [], []
    period_ns = int(round(batch_period_s * 1e9))
    for stamp, published, received in corrections:
        i = int(np.searchsorted(starts, stamp, side="right")) - 1
        if i < 0 or stamp - starts[i] >= period_ns:
            continue   # its batch was not heard here (best effort)
        batch_time = batch_published[int(starts[i])]
        batching.append((batch_time - stamp) / 1e6)
        broadcaster.append((published - batch_time) / 1e6)
        delivery.append((received - published) / 1e6)
    return {"batching": _summary(batching), "broadcaster": _summary(broadcaster),
            "delivery": _summary(delivery), "matched": len(batching)}


def bench_joint_state(seconds: float) -> dict:
    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    rclpy.init()
    node = rclpy.create_node("per_sample_sink")
    received = {"n": 0}
    node.create_subscription(JointState, "/per_sample", lambda m: received.__setitem__(
        "n", received["n"] + 1), QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    source = subprocess.Popen([sys.executable, "-c", JOINT_STATE_PUBLISHER.format(
        seconds=seconds)], stdout=subprocess.PIPE, text=True)
    first = None
    while source.poll() is None:
        rclpy.spin_once(node, timeout_sec=0.01)
        if first is None and received["n"]:
            first = (time.monotonic(), received["n"])
    published = int(source.stdout.read().strip() or 0)
    node.destroy_node()
    rclpy.try_shutdown()
    return {"published": published, "received": received["n"],
            "received_per_s": received["n"] / seconds,
            "samples_per_s_needed": 20000}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--batch-periods", type=float, nargs="+", default=[0.05],
                        help="sweep: batch periods [s], e.g. 0.05 0.02 0.01 0.005 0.002")
    parser.add_argument("--monitor", action="store_true",
                        help="run the model monitor searching continuously alongside")
    parser.add_argument("--reference-period", type=float, default=None, metavar="S",
                        help="reference reading period of the virtual instrument [s] "
                             "(default 0.1 with --monitor, else 0.5)")
    parser.add_argument("--niceness", type=int, default=0, metavar="N",
                        help="niceness of the path's nodes (e.g. -15; 0: as started)")
    parser.add_argument("--burners", type=int, default=0, metavar="K",
                        help="CPU-burning processes alongside during the run")
    parser.add_argument("--reselect-every", type=int, default=0, metavar="N",
                        help="the estimator's reselect_every [samples] (0: its default)")
    args = parser.parse_args()
    REFERENCE["period_s"] = args.reference_period if args.reference_period is not None else \
        (0.1 if args.monitor else 0.5)
    if args.reselect_every:
        ESTIMATOR["reselect_every"] = args.reselect_every
    if args.niceness:
        PATH["niceness"] = args.niceness
    BURNERS["count"] = args.burners
    if len(args.batch_periods) > 1:
        sweep = [bench_graph(args.seconds, period, args.monitor) for period in args.batch_periods]
        print(json.dumps({"sweep": sweep}, indent=2))
        return 0
    graph = bench_graph(args.seconds, args.batch_periods[0], args.monitor)
    per_sample = bench_joint_state(min(args.seconds, 10.0))
    out = {"batched_graph": graph, "per_sample_joint_state": per_sample,
           "ratio_samples_per_s": 20000 / max(per_sample["received_per_s"], 1e-9)}
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
