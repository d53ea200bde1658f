"""Write a :class:`~.machine_tool.SimulationResult` as a rosbag2-compatible MCAP bag and CSV.

Bag topics (namespace prefix optional; log time = sample time of the first
sample of the batch on the scenario's clock, ``start_time_s`` + t):

=====================  ===============================  ===================================
topic                  type                             content
=====================  ===============================  ===================================
``/scales``            ``mt_accuracy_msgs/ScaleBatch``   every head, ``batch_period_s`` each [m]
``/temperatures``      ``mt_accuracy_msgs/TemperatureArray``  every thermocouple [degC]
=====================  ===============================  ===================================

CSV files: ``scales.csv`` (time_s, command_<axis>, <head> ...) and
``temperatures.csv`` (time_s, <sensor> ..., spindle_rpm) with a ``#`` header
line naming the scenario and the units.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .machine_tool import SimulationResult


def write_csv(result: SimulationResult, out_dir: str | Path, *, stride: int = 1) -> list[Path]:
    """``scales.csv`` (every ``stride``-th sample) and ``temperatures.csv`` in ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    axes = list(result.scenario.machine.axis_order)
    index = np.arange(0, result.time_s.size, stride)
    columns = [result.time_s[index]] + [result.command[a][index] for a in axes] + \
        [result.scale_readings[index, k] for k in range(len(result.scale_channels))]
    header = ",".join(["time_s"] + [f"command_{a.lower()}" for a in axes] + result.scale_channels)
    scales = out / "scales.csv"
    np.savetxt(scales, np.column_stack(columns), delimiter=",", header=header, comments="",
               fmt="%.10g")
    temperatures = out / "temperatures.csv"
    np.savetxt(temperatures, np.column_stack([result.temperature_time_s, result.temperatures_c,
                                              result.spindle_speed_rpm]),
               delimiter=",", fmt="%.6g", comments="",
               header=",".join(["time_s"] + result.temperature_names + ["spindle_rpm"]))
    return [scales, temperatures]


def write_bag(result: SimulationResult, bag_dir: str | Path, *, batch_period_s: float = 0.05,
              namespace: str = "", progress: bool = False) -> Path:
    """The result as a bag directory (see the module docstring)."""
    from rclpy.serialization import serialize_message

    from mt_accuracy_msgs.msg import ScaleBatch, TemperatureArray

    from ..io.bag_writer import BagWriter, qos_dict
    from ..io.fields import nanoseconds_to_stamp, pack_float64

    prefix = namespace.rstrip("/")
    scales_topic, temperatures_topic = f"{prefix}/scales", f"{prefix}/temperatures"
    start_ns = int(round(result.scenario.start_time_s * 1e9))
    rate = result.sample_rate_hz
    per_batch = max(1, int(round(batch_period_s * rate)))
    axes = [a for a in result.scenario.machine.axis_order]
    command = np.column_stack([result.command[a] for a in axes])
    events = []
    for first in range(0, result.time_s.size, per_batch):
        events.append((start_ns + int(round(first * 1e9 / rate)), 0, first))
    for k, t in enumerate(result.temperature_time_s):
        events.append((start_ns + int(round(t * 1e9)), 1, k))
    events.sort()
    iterator = events
    if progress:
        from tqdm import tqdm

        iterator = tqdm(events, desc="writing bag", unit="msg")
    with BagWriter(Path(bag_dir)) as bag:
        bag.add_topic(scales_topic, "mt_accuracy_msgs/msg/ScaleBatch",
                      qos_dict(reliability="best_effort", depth=100))
        bag.add_topic(temperatures_topic, "mt_accuracy_msgs/msg/TemperatureArray",
                      qos_dict(reliability="best_effort", depth=100))
        for stamp_ns, kind, index in iterator:
            if kind == 0:
                rows = slice(index, min(index + per_batch, result.time_s.size))
                message = ScaleBatch()
                message.header.stamp = nanoseconds_to_stamp(stamp_ns)
                message.header.frame_id = result.scenario.machine.name
                message.first_sample_index = index
                message.sample_period = 1.0 / rate
                message.channel_names = list(result.scale_channels)
                message.positions = pack_float64(result.scale_readings[rows].ravel())
                message.command_axes = [a.lower() for a in axes]
                message.command_positions = pack_float64(command[rows].ravel())
                message.encoder_names = [a.lower() for a in result.encoder_axes]
                message.encoder_angles = pack_float64(result.encoder_readings[rows].ravel())
                bag.write(scales_topic, serialize_message(message), stamp_ns, stamp_ns)
            else:
                message = TemperatureArray()
                message.sequence = index
                message.header.stamp = nanoseconds_to_stamp(stamp_ns)
                message.header.frame_id = result.scenario.machine.name
                message.sensor_names = list(result.temperature_names)
                message.temperatures = pack_float64(result.temperatures_c[index])
                message.variances = pack_float64(np.full(
                    len(result.temperature_names),
                    float(result.scenario.noise["thermocouple_k"]) ** 2))
                bag.write(temperatures_topic, serialize_message(message), stamp_ns, stamp_ns)
    return Path(bag_dir)
