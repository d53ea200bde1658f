"""The model monitor validates in on_set and acts afterwards, on a real node process.

A parameter set that is invalid is refused with its reason and changes nothing; a valid
one is answered at once and its change (the fit, the gate, a new version) is made after
the answer, one change at a time in the order set; ``change_model`` answers with
accepted, reason and version. The monitor runs its real fit, held by this test until it
releases it: the order of events shows the fit is not made inside the set. Readings are
written in closed form (e_x = -S y, a squareness S of 25 urad on EC0Y, 0.3 um noise).
"""
from __future__ import annotations

import sys
import textwrap

import numpy as np
import yaml

from graph_helpers import call_service, set_parameter_again_until_answered, spin_until
from mt_accuracy_ros.commands.processes import NodeProcess, ros_arguments

TRUE_ANGLE_RAD = 25e-6
NOISE_M = 0.3e-6
READINGS = 40

#: The monitor's own main(), its fit (``add_effect``) held until the file ``release``
#: exists; ``started`` is written when the fit is reached. Bounded: a test that died
#: leaves no process waiting for ever.
HELD_MONITOR = textwrap.dedent("""
    import os, sys, time
    from mt_accuracy_ros.nodes import model_monitor

    started, release = sys.argv[1], sys.argv[2]
    fit = model_monitor.add_effect

    def held_fit(*args, **kwargs):
        open(started, "w").close()
        deadline = time.monotonic() + 120.0
        while not os.path.exists(release) and time.monotonic() < deadline:
            time.sleep(0.02)
        return fit(*args, **kwargs)

    model_monitor.add_effect = held_fit
    if __name__ == "__main__":
        sys.exit(model_monitor.main(sys.argv))
""")


def _start_held_monitor(tmp_path, parameters: dict) -> NodeProcess:
    import subprocess

    script = tmp_path / "held_monitor.py"
    script.write_text(HELD_MONITOR)
    command = [sys.executable, str(script), str(tmp_path / "started"), str(tmp_path / "release"),
               *ros_arguments(parameters)]
    return NodeProcess(name="model_monitor", popen=subprocess.Popen(
        command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL), command=command)


def _reading(sequence: int, rng):
    from mt_accuracy_msgs.msg import ReferenceMeasurement
    from mt_accuracy_ros.nodes._common import nanoseconds_to_stamp

    x, y, z = rng.uniform(0.0, 0.39), rng.uniform(-0.44, 0.0), rng.uniform(0.0, 0.495)
    message = ReferenceMeasurement()
    message.header.stamp = nanoseconds_to_stamp(1_000_000_000 + sequence * 400_000_000)
    message.header.frame_id = "bed"
    message.sequence = sequence
    message.instrument = "reference_probe"
    message.command_axes = ["z", "x", "y"]
    message.command_positions = [z, x, y]
    message.command_velocities = [0.0, 0.0, 0.0]
    error = np.array([-TRUE_ANGLE_RAD * y, 0.0, 0.0]) + rng.normal(0.0, NOISE_M, 3)
    message.error.x, message.error.y, message.error.z = (float(v) for v in error)
    message.measured = [True, True, True]
    message.uncertainty = 2 * NOISE_M
    message.compensation_model_version = 1
    return message


def _set_once(node, client, name: str, value) -> tuple[bool, str]:
    """Set one parameter through a client whose service already answered it once (matched):
    for a setting whose repetition would change something."""
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter

    future = client.call_async(SetParameters.Request(
        parameters=[Parameter(name, value=value).to_parameter_msg()]))
    assert spin_until(node, future.done, 60), f"{name} unanswered"
    result = future.result().results[0]
    return bool(result.successful), str(result.reason)


def test_the_monitor_validates_in_the_set_and_applies_afterwards(rclpy_context, tmp_path):
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rcl_interfaces.srv import GetParameters, SetParameters

    from mt_accuracy_msgs.msg import ModelVersion, ReferenceMeasurement
    from mt_accuracy_msgs.srv import ChangeModel
    from mt_accuracy_ros.nodes._common import LATCHED_QOS, RESULT_QOS

    start = tmp_path / "start.yaml"
    start.write_text("machine: kidani_hmc\neffects:\n  geometric: {}\n")
    other = tmp_path / "other.yaml"   # a model file in model_dir, set by name
    other.write_text("machine: kidani_hmc\neffects:\n  geometric: {}\n")
    node = rclpy.create_node("user")
    versions, statuses = [], []
    node.create_subscription(ModelVersion, "model", versions.append, LATCHED_QOS)
    node.create_subscription(DiagnosticArray, "/diagnostics", lambda m: statuses.extend(
        (s.name, s.level, s.message, {v.key: v.value for v in s.values}) for s in m.status), 100)
    readings = node.create_publisher(ReferenceMeasurement, "reference/tcp_error", RESULT_QOS)
    setter = node.create_client(SetParameters, "/model_monitor/set_parameters")
    getter = node.create_client(GetParameters, "/model_monitor/get_parameters")
    change = node.create_client(ChangeModel, "/model_monitor/change_model")
    monitor = _start_held_monitor(tmp_path, {"model": str(start), "model_dir": str(tmp_path),
                                             "check_every": 100000})
    rng = np.random.default_rng(7)

    def processed() -> int:
        counts = [v.get("reference/tcp_error.processed") for name, _, _, v in statuses
                  if "model_monitor: delivery" in name]
        return max([int(c) for c in counts if c] or [0])

    def parameter(name: str) -> list[str]:
        response = call_service(node, getter, GetParameters.Request(names=[name]))
        return list(response.values[0].string_array_value)

    def version(number: int):
        return next((v for v in versions if v.version == number), None)

    try:
        assert spin_until(node, lambda: versions and readings.get_subscription_count() >= 1, 60)
        for start_at in range(0, READINGS, 10):   # ten at a time, each ten processed
            for sequence in range(start_at, start_at + 10):
                readings.publish(_reading(sequence, rng))
            assert spin_until(node, lambda: processed() >= start_at + 10, 60), processed()

        # 1. Invalid sets: refused with the reason; nothing changes (the parameter keeps
        # its value; no version comes of them: the versions are checked in full below).
        # (Refused settings, asked again while unanswered: through the client that later
        # sends the valid set once, so that its first request cannot be lost in discovery.)
        result = call_service(node, setter, SetParameters.Request(parameters=[
            _parameter_msg("remove_effects", ["squareness"])])).results[0]
        assert not result.successful and result.reason == "cannot remove squareness: not " \
            "in the model (it holds geometric)", result.reason
        assert parameter("remove_effects") == [""]
        ok, reason = set_parameter_again_until_answered(node, "/model_monitor", "add_effects",
                                                        ["warp"])
        assert not ok and "unknown effect 'warp'" in reason, reason
        ok, reason = set_parameter_again_until_answered(node, "/model_monitor", "model",
                                                        "machine: kidani_hmc\nversion: two\n")
        assert not ok and reason.startswith("model refused"), reason
        assert parameter("add_effects") == [""]
        assert call_service(node, getter, GetParameters.Request(
            names=["model"])).values[0].string_value == str(start)

        # 2. A valid set is accepted at once: its fit is held (nothing released yet),
        # so the answer came before the fit could end - it is not made inside the set.
        ok, reason = _set_once(node, setter, "add_effects", ["squareness:EC0Y"])
        assert ok, reason
        assert version(2) is None
        # The fit starts after the answer, on the monitor's executor (which it holds
        # meanwhile: parameter requests wait for it); still no version.
        assert spin_until(node, (tmp_path / "started").exists, 60)
        assert version(2) is None
        # A second set meanwhile waits its turn: it is answered and made after the first.
        later = setter.call_async(SetParameters.Request(parameters=[
            _parameter_msg("model", other.name)]))
        (tmp_path / "release").touch()
        assert spin_until(node, lambda: later.done() and version(3) is not None, 120), \
            [(v.version, v.reason) for v in versions]
        assert later.result().results[0].successful
        assert parameter("add_effects") == ["squareness:EC0Y"]
        added = version(2)
        assert added.reason == "added squareness:EC0Y (user)"
        entry = yaml.safe_load(added.model_yaml)["effects"]["squareness:EC0Y"]
        angle, u = entry["coefficients"]["angle_rad"], entry["uncertainties"]["angle_rad"]
        assert abs(angle - TRUE_ANGLE_RAD) < 3 * u and u < 2e-6, (angle, u)
        assert version(3).reason == "model parameter set"
        assert version(3).effects == ["geometric"]

        # 3. The service: a bad request refused with its reason and the live version...
        response = call_service(node, change, ChangeModel.Request(add_effects=["warp"]))
        assert not response.accepted and "unknown effect 'warp'" in response.reason
        assert response.version == 3
        # ...a good one answered once made, with the version it made...
        response = call_service(node, change, ChangeModel.Request(
            add_effects=["squareness:EC0Y"]), attempt_s=60.0)
        assert response.accepted, response.reason
        assert response.reason == "added squareness:EC0Y (user)" and response.version == 4
        assert spin_until(node, lambda: version(4) is not None, 30)
        # ...and one validated but not made (these readings carry no temperature: a
        # thermal drift has nothing to be fitted to): refused, said, the version stays.
        response = call_service(node, change, ChangeModel.Request(
            add_effects=["structural_thermal_drift"]), attempt_s=60.0)
        assert not response.accepted and response.version == 4
        assert response.reason.startswith("cannot fit structural_thermal_drift"), response.reason
        assert spin_until(node, lambda: any(
            name.endswith("model_monitor: model") and level == b"\x02" and
            "add_effects ['structural_thermal_drift'] not applied: cannot fit" in text
            for name, level, text, _ in statuses), 30)
        # Nothing to change: accepted, the version as it was.
        response = call_service(node, change, ChangeModel.Request())
        assert response.accepted and response.version == 4
        assert monitor.popen.poll() is None
    finally:
        monitor.stop()
        node.destroy_node()
    # Every version, in order: none came of a refused set or request.
    assert [(v.version, v.reason) for v in versions] == [
        (1, "start"), (2, "added squareness:EC0Y (user)"), (3, "model parameter set"),
        (4, "added squareness:EC0Y (user)")]


def _parameter_msg(name: str, value):
    from rclpy.parameter import Parameter

    return Parameter(name, value=value).to_parameter_msg()
