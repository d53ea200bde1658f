"""Soak the full live graph: ``python -m bench.soak [--minutes 30]``.

Every node in its own process - encoder and temperature publishers (the
virtual machine, real time), yaw estimator, compensation broadcaster, model
monitor, recorder - for ``--minutes``. The resident memory (VmRSS) of each
process is sampled every ``--sample-s``; after a warm-up (the first fifth of
the run: the estimator's kNN memory, the monitor's window and the recorder's
first chunks fill up) the RSS must stay flat: the last sample within 5 % of
the first post-warm-up one. The delivery diagnostics of the model nodes are
read at the end (losses and refusals over the whole run).

Prints one JSON document; exit status 1 if any node died or grew > 5 %.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

from tqdm import tqdm

SCENARIO = """machine: kidani_hmc
seed: 3
duration_s: {seconds}
sample_rate_hz: 1000
temperature_rate_hz: 1
program: {{type: back_and_forth, axes: [X, Y], feed_m_per_min: 20}}
effects: {{structural_thermal_drift: {{time_constant_s: 600}}}}
"""


def rss_kib(pid: int) -> int:
    """Resident set size of a process [KiB] (0 once it has gone)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


def main(argv: list[str] | None = None) -> int:
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray

    from mt_accuracy_ros.commands.processes import start_node

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--minutes", type=float, default=30.0)
    parser.add_argument("--sample-s", type=float, default=10.0)
    parser.add_argument("--domain", type=int, default=101,
                        help="ROS_DOMAIN_ID of the soak's graph (kept apart from other runs)")
    args = parser.parse_args(argv)
    # Set before rclpy starts; the node processes inherit it.
    os.environ["ROS_DOMAIN_ID"] = str(args.domain)
    seconds = args.minutes * 60
    folder = Path(tempfile.mkdtemp(prefix="mt_soak_"))
    scenario = folder / "soak.yaml"
    scenario.write_text(SCENARIO.format(seconds=seconds + 120))
    machine = {"scenario": str(scenario), "rate_factor": 1.0,
               "start_stamp_ns": time.time_ns() + 5_000_000_000}
    processes = {
        "recorder": start_node("recorder", {"output": str(folder / "bag")}, quiet=True),
        "yaw_estimator": start_node("yaw_estimator", quiet=True),
        "compensation_broadcaster": start_node("compensation_broadcaster", quiet=True),
        "model_monitor": start_node("model_monitor", quiet=True),
        "temperature_publisher": start_node("temperature_publisher",
                                            {**machine, "min_subscribers": 4}, quiet=True),
        "encoder_publisher": start_node("encoder_publisher", {**machine, "min_subscribers": 3,
                                                             "batch_period_s": 0.05},
                                        quiet=True),
    }
    rclpy.init()
    listener = rclpy.create_node("soak_listener")
    delivery: dict[str, dict[str, str]] = {}

    def on_diagnostics(message) -> None:
        for status in message.status:
            if status.name.endswith(": delivery"):
                delivery[status.name.split(":")[0]] = {v.key: v.value for v in status.values}

    listener.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, 50)
    samples: dict[str, list[tuple[float, int]]] = {name: [] for name in processes}
    started = time.monotonic()
    next_sample = started
    try:
        with tqdm(total=int(seconds), desc="soak", unit="s", file=sys.stderr) as progress:
            while (elapsed := time.monotonic() - started) < seconds:
                rclpy.spin_once(listener, timeout_sec=0.1)
                if time.monotonic() >= next_sample:
                    for name, process in processes.items():
                        samples[name].append((round(elapsed, 1), rss_kib(process.popen.pid)))
                    next_sample += args.sample_s
                    progress.n = int(elapsed)
                    progress.refresh()
        died = [name for name, p in processes.items() if p.popen.poll() is not None]
    finally:
        for process in processes.values():
            process.stop()
        listener.destroy_node()
        rclpy.try_shutdown()
    result = {"minutes": args.minutes, "sample_s": args.sample_s, "died": died, "nodes": {}}
    failed = bool(died)
    for name, series in samples.items():
        after_warmup = [rss for t, rss in series if t >= seconds / 5 and rss]
        if not after_warmup:
            continue
        growth = (after_warmup[-1] - after_warmup[0]) / after_warmup[0]
        result["nodes"][name] = {
            "rss_start_mib": round(series[0][1] / 1024, 1),
            "rss_after_warmup_mib": round(after_warmup[0] / 1024, 1),
            "rss_end_mib": round(after_warmup[-1] / 1024, 1),
            "rss_max_mib": round(max(after_warmup) / 1024, 1),
            "growth_after_warmup_percent": round(100 * growth, 2)}
        failed |= growth > 0.05
    result["delivery"] = delivery
    result["flat_within_5_percent"] = not failed
    (folder / "soak.json").write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
