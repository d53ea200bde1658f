"""Write a :class:`~.machine_tool.SimulationResult` as a rosbag2-compatible MCAP bag and CSV.

Bag topics (namespace prefix optional; log time = sample time of the first
sample of the batch on the scenario's clock, ``start_time_s`` + t):

=====================  ===============================  ===================================
topic                  type                             content
=====================  ===============================  ===================================
``/scales``            ``mt_accuracy_msgs/ScaleBatch``   every head, ``batch_period_s`` each [m]
``/temperatures``      ``mt_accuracy_msgs/TemperatureArray``  every thermocouple [degC]
``/reference/tcp_error`` ``mt_accuracy_msgs/ReferenceMeasurement``  with ``reference_period_s``:
                       a probe's TCP error of the uncompensated machine every period [m]
=====================  ===============================  ===================================

The reference readings are what the live graph's encoder publisher sends with its
compensation off: the simulator's true TCP error at the sample, plus the probe's
noise (1 um at k = 2), zeroed at the scenario's ``work_offset`` when it has one.
A day of a machine in a fleet is such a bag (``mt-accuracy simulate --reference-period``).

CSV files: ``scales.csv`` (time_s, command_<axis>, <head> ...) and
``temperatures.csv`` (time_s, <sensor> ..., spindle_rpm) with a ``#`` header
line naming the scenario and the units.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .machine_tool import SimulationResult, direction_held


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


#: The reference probe's uncertainty (k = 2) [m], as the live graph's.
PROBE_UNCERTAINTY_M = 1e-6


def reference_messages(result: SimulationResult, period_s: float, start_ns: int, frame: str):
    """(stamp [ns], ReferenceMeasurement) of a probe every ``period_s`` of data time."""
    from mt_accuracy_msgs.msg import ReferenceMeasurement

    from ..io.fields import nanoseconds_to_stamp

    if not (np.isfinite(period_s) and period_s > 0):
        raise ValueError(f"reference_period_s must be finite and > 0, got {period_s}")
    machine = result.scenario.machine
    axes = list(machine.axis_order)
    rate = result.sample_rate_hz
    picks = np.unique(np.round(np.arange(0.0, result.time_s[-1] + 0.5 / rate, period_s)
                               * rate).astype(np.int64))
    picks = picks[picks < result.time_s.size]
    error = result.tcp_error(picks)
    # The probe's noise is the run's (noise_seed): the same machine reads anew each day.
    noise = result.scenario.seed if result.scenario.noise_seed is None \
        else result.scenario.noise_seed
    rng = np.random.default_rng(np.random.SeedSequence([noise, 0xEEF, 1]))
    error = error + rng.normal(0.0, PROBE_UNCERTAINTY_M / 2, error.shape)
    if result.scenario.work_offset:
        error = error - result.error_at(result.scenario.work_offset, 0)
    # What the CNC knows of each axis' direction: its last motion.
    directions = {a: direction_held(result.velocity[a]) for a in axes}
    for k, index in enumerate(picks):
        message = ReferenceMeasurement(instrument="reference_probe",
                                       command_axes=[a.lower() for a in axes])
        stamp_ns = start_ns + int(round(index * 1e9 / rate))
        message.header.stamp = nanoseconds_to_stamp(stamp_ns)
        message.header.frame_id = frame
        message.command_positions = [float(result.command[a][index]) for a in axes]
        message.command_velocities = [float(result.velocity[a][index]) for a in axes]
        message.command_directions = [int(directions[a][index]) for a in axes]
        message.error.x, message.error.y, message.error.z = (float(v) for v in error[k])
        message.measured = [True, True, True]
        message.uncertainty = PROBE_UNCERTAINTY_M
        message.sequence = k
        yield stamp_ns, message


def write_bag(result: SimulationResult, bag_dir: str | Path, *, batch_period_s: float = 0.05,
              namespace: str = "", progress: bool = False,
              reference_period_s: float | None = None, scales: bool = True) -> Path:
    """The result as a bag directory (see the module docstring).

    ``reference_period_s`` adds a probe's reading of the TCP error every so many
    seconds of data time; ``scales=False`` leaves the scale batches out (a bag of
    reference readings and temperatures, what ``mt-accuracy check`` reads)."""
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
    if scales:
        for first in range(0, result.time_s.size, per_batch):
            events.append((start_ns + int(round(first * 1e9 / rate)), 0, first))
    for k, t in enumerate(result.temperature_time_s):
        events.append((start_ns + int(round(t * 1e9)), 1, k))
    references = []
    if reference_period_s is not None:
        references = list(reference_messages(result, reference_period_s, start_ns,
                                             result.scenario.machine.name))
        events.extend((stamp, 2, k) for k, (stamp, _) in enumerate(references))
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
        if references:
            bag.add_topic(f"{prefix}/reference/tcp_error",
                          "mt_accuracy_msgs/msg/ReferenceMeasurement", qos_dict())
        for stamp_ns, kind, index in iterator:
            if kind == 2:
                bag.write(f"{prefix}/reference/tcp_error",
                          serialize_message(references[index][1]), stamp_ns, stamp_ns)
                continue
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
