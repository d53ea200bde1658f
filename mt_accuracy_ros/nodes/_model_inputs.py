"""Inputs every model-running node keeps: latest temperatures, measured profiles, the model."""
from __future__ import annotations

import numpy as np
import yaml
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

from mt_accuracy_msgs.msg import SystematicProfile, TemperatureArray

from ..core.error_model import ErrorModel, model_to_dict, resolve_model
from ..core.errors import MtAccuracyError
from ._common import LATCHED_QOS, RESULT_QOS, SENSOR_QOS, unpack_float64

#: Compensation tables, one message per axis: a late joiner must get all of them.
TABLE_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL, history=HistoryPolicy.KEEP_LAST)


class ModelInputs:
    """Subscribes temperatures and systematic/<axis>; holds the current ErrorModel.

    ``follow_topic``: also take whole models published (YAML) on ``model``.
    """

    def __init__(self, node, model_text: str, *, follow_topic: bool, on_change) -> None:
        self.node = node
        self.model: ErrorModel = resolve_model(model_text)
        self.temperatures: dict[str, float] = {}
        self.dead: set[str] = set()
        self.on_change = on_change
        node.create_subscription(TemperatureArray, "temperatures", self._on_temperatures,
                                 SENSOR_QOS)
        for axis in ("x", "y", "z"):
            node.create_subscription(SystematicProfile, f"systematic/{axis}", self._on_profile,
                                     RESULT_QOS)
        if follow_topic:
            node.create_subscription(String, "model", self._on_model, LATCHED_QOS)

    def set_model(self, model: ErrorModel) -> None:
        # Profiles and temperature references live on across model versions.
        model.profiles.update({k: v for k, v in self.model.profiles.items()
                               if k not in model.profiles})
        for sensor, value in self.model.reference_temperatures_c.items():
            model.reference_temperatures_c.setdefault(sensor, value)
        for name, value in self.model.profile_offsets.items():
            model.profile_offsets.setdefault(name, value)
        model.version = max(model.version, self.model.version + 1)
        self.model = model
        self.on_change()

    def _on_model(self, message: String) -> None:
        try:
            model = resolve_model(message.data)
        except MtAccuracyError as exc:
            self.node.get_logger().error(f"model on topic refused: {exc}")
            return
        if model_to_dict(model)["effects"] != model_to_dict(self.model)["effects"] or \
                model.reference_temperatures_c != self.model.reference_temperatures_c:
            self.set_model(model)

    def _on_temperatures(self, message: TemperatureArray) -> None:
        values = unpack_float64(message.temperatures)
        self.dead = set()
        for name, value in zip(message.sensor_names, values):
            if np.isfinite(value):
                self.temperatures[name] = float(value)
            else:
                self.dead.add(name)

    def _on_profile(self, message: SystematicProfile) -> None:
        if message.unit != "rad" or not message.error_name:
            return
        try:
            self.model.set_profile(message.error_name, unpack_float64(message.positions).copy(),
                                   unpack_float64(message.systematic).copy())
        except MtAccuracyError as exc:
            self.node.get_logger().warning(f"profile {message.error_name} ignored: {exc}")

    def model_yaml(self) -> str:
        return yaml.safe_dump(model_to_dict(self.model), sort_keys=False)
