"""What a report needs from a bag of this package's topics, read once."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..io.bag_reader import bag_info, decode, read_messages, topics
from ..io.fields import stamp_to_nanoseconds, unpack_float64

#: Yaw samples kept per axis for the scatter plot (every n-th sample).
YAW_POINTS = 20000


@dataclass
class AxisData:
    """One axis' dual-scale yaw and its kNN profiles."""

    axis: str
    yaw_time_ns: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    yaw_position_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    yaw_rad: np.ndarray = field(default_factory=lambda: np.zeros(0))
    profiles: list = field(default_factory=list)  # SystematicProfile messages, in order


@dataclass
class BagData:
    path: Path
    info: dict
    start_ns: int
    scales: object | None = None            # the first ScaleBatch
    batch_count: int = 0
    references: list = field(default_factory=list)        # (stamp, ReferenceMeasurement)
    temperatures: list = field(default_factory=list)      # (stamp, names, values)
    axes: dict[str, AxisData] = field(default_factory=dict)
    compensation: list = field(default_factory=list)      # (stamp, error xyz, version)
    tables: dict[str, object] = field(default_factory=dict)  # axis -> last CompensationTable
    models: list = field(default_factory=list)            # (stamp, model YAML, version, reason)

    def seconds(self, stamps_ns) -> np.ndarray:
        """Time since the start of the data [s] - the one time base of every report plot."""
        return (np.asarray(stamps_ns, dtype=np.float64) - self.start_ns) / 1e9


def read_bag(bag: str | Path, namespace: str = "") -> BagData:
    """Read the report's inputs from ``bag`` (topics under ``namespace``)."""
    bag = Path(bag)
    prefix = namespace.rstrip("/")
    available = topics(bag)
    wanted = [name for name in available if name.startswith(prefix + "/")] if prefix else \
        list(available)
    data = BagData(bag, bag_info(bag), 0)
    yaw_stride: dict[str, int] = {}
    from tqdm import tqdm

    total = sum(data.info["topics"].get(t, {}).get("count", 0) for t in wanted)
    for message in tqdm(read_messages(bag, wanted), desc="report: reading the bag", unit="msg",
                        total=total, disable=None, leave=False):
        name = message.topic[len(prefix):]
        if name == "/scales":
            data.batch_count += 1
            if data.scales is None:
                data.scales = decode(message)
            continue
        if name not in ("/reference/tcp_error", "/temperatures", "/compensation",
                        "/compensation_table", "/model") and \
                not name.startswith(("/yaw/", "/systematic/")):
            continue
        value = decode(message)
        stamp = message.log_time_ns if name == "/model" else \
            stamp_to_nanoseconds(value.header.stamp)
        if name == "/reference/tcp_error":
            data.references.append((stamp, value))
        elif name == "/temperatures":
            data.temperatures.append((stamp, list(value.sensor_names),
                                      unpack_float64(value.temperatures).copy()))
        elif name == "/compensation":
            data.compensation.append((stamp, (value.error.x, value.error.y, value.error.z),
                                      int(value.model_version)))
        elif name == "/compensation_table":
            data.tables[value.axis] = value
        elif name == "/model":
            if hasattr(value, "model_yaml"):  # ModelVersion
                data.models.append((stamp, value.model_yaml, int(value.version), value.reason))
            else:  # bags of earlier versions: the model's YAML as std_msgs/String
                data.models.append((stamp, value.data, None, ""))
        elif name.startswith("/yaw/"):
            axis = data.axes.setdefault(value.axis, AxisData(value.axis))
            # Keep about YAW_POINTS samples whatever the run's length.
            stride = yaw_stride.setdefault(value.axis, 1)
            yaw = unpack_float64(value.yaw)[::stride]
            positions = unpack_float64(value.positions)[::stride]
            times = stamp + (np.arange(yaw.size) * stride * value.sample_period * 1e9
                             ).astype(np.int64)
            axis.yaw_time_ns = np.concatenate([axis.yaw_time_ns, times])
            axis.yaw_position_m = np.concatenate([axis.yaw_position_m, positions])
            axis.yaw_rad = np.concatenate([axis.yaw_rad, yaw])
            if axis.yaw_rad.size > 2 * YAW_POINTS:
                axis.yaw_time_ns, axis.yaw_position_m, axis.yaw_rad = (
                    a[::2] for a in (axis.yaw_time_ns, axis.yaw_position_m, axis.yaw_rad))
                yaw_stride[value.axis] = stride * 2
        else:
            data.axes.setdefault(value.axis, AxisData(value.axis)).profiles.append(value)
    starts = [s for s in ([stamp_to_nanoseconds(data.scales.header.stamp)] if data.scales else [])
              + [r[0] for r in data.references[:1]] + [t[0] for t in data.temperatures[:1]]]
    data.start_ns = min(starts) if starts else int(data.info["start_ns"])
    return data
