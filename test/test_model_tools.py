"""``mt-accuracy model``: the live model changed from a terminal, against a real monitor.

The command asks the monitor's ``change_model`` service, answered once the change is
made: a fit the monitor cannot make is the command's refusal, with the reason, and a
change made is printed with the version it made. Readings are written in closed form
(e_x = -S y, a squareness S of 25 urad on EC0Y, 0.3 um noise, no temperatures).
"""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import yaml

from mt_accuracy_ros.commands.processes import start_node

TRUE_ANGLE_RAD = 25e-6
NOISE_M = 0.3e-6
READINGS = 40


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mt_accuracy_ros.cli", "model", *args],
                          capture_output=True, text=True, timeout=120)


def test_model_remove_show_and_refusals_on_a_running_monitor(tmp_path):
    model = tmp_path / "model.yaml"
    model.write_text("machine: kidani_hmc\neffects:\n  geometric: {}\n"
                     "  squareness: {errors_rad: {EC0Y: 1.0e-5}}\n")
    monitor = start_node("model_monitor", {"model": str(model)}, quiet=True)
    try:
        shown = _cli("show", "--timeout", "30")
        assert shown.returncode == 0, shown.stderr
        assert shown.stdout.startswith("version 1: start")
        removed = _cli("remove", "squareness")
        assert removed.returncode == 0 and "accepted" in removed.stdout, removed.stderr
        shown = _cli("show", "--timeout", "30")
        assert "version 2: removed squareness (user)" in shown.stdout
        assert "effects: geometric\n" in shown.stdout
        # Removing what the model does not hold: one line, exit 2, the model unchanged.
        again = _cli("remove", "squareness")
        assert again.returncode == 2
        assert "not in the model (it holds geometric)" in again.stderr
        assert len(again.stderr.strip().splitlines()) == 1
        # Adding needs reference readings to fit to; an unknown effect is named.
        early = _cli("add", "structural_thermal_drift")
        assert early.returncode == 2 and "reference readings" in early.stderr, early.stderr
        unknown = _cli("add", "flux_capacitor")
        assert unknown.returncode == 2 and "unknown effect 'flux_capacitor'" in unknown.stderr
        # Refitting (no names: every fitted effect) needs readings too: one line, exit 2.
        refit = _cli("refit")
        assert refit.returncode == 2, refit.stderr
        assert "refit all refused: cannot refit: only 0 reference readings" in refit.stderr
        assert monitor.popen.poll() is None
    finally:
        monitor.stop()


def test_model_commands_without_a_monitor_say_so(tmp_path):
    result = _cli("remove", "squareness", "--monitor", "/nobody_here", "--timeout", "2")
    assert result.returncode == 2 and "not available" in result.stderr, result.stderr


def _reading(sequence: int, rng):
    """A reference reading of the closed-form squareness, stamped 0.4 s apart."""
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


def _feed_monitor(readings: int) -> None:
    """Publish ``readings`` closed-form readings to the monitor, ten at a time, each ten
    processed (its delivery counters on /diagnostics) before the next."""
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray

    from nodes.graph_helpers import spin_until
    from mt_accuracy_msgs.msg import ReferenceMeasurement
    from mt_accuracy_ros.nodes._common import RESULT_QOS

    rclpy.init()
    node = rclpy.create_node("reference_probe")
    processed = [0]

    def hear(message) -> None:
        for status in message.status:
            values = {v.key: v.value for v in status.values}
            if "model_monitor: delivery" in status.name and \
                    values.get("reference/tcp_error.processed"):
                processed[0] = max(processed[0], int(values["reference/tcp_error.processed"]))

    node.create_subscription(DiagnosticArray, "/diagnostics", hear, 100)
    publisher = node.create_publisher(ReferenceMeasurement, "reference/tcp_error", RESULT_QOS)
    rng = np.random.default_rng(7)
    try:
        assert spin_until(node, lambda: publisher.get_subscription_count() >= 1, 60)
        for start in range(0, readings, 10):
            for sequence in range(start, start + 10):
                publisher.publish(_reading(sequence, rng))
            assert spin_until(node, lambda: processed[0] >= start + 10, 60), processed[0]
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def test_model_add_reports_the_outcome_of_the_fit_not_only_its_validation(tmp_path):
    model = tmp_path / "model.yaml"
    model.write_text("machine: kidani_hmc\neffects:\n  geometric: {}\n")
    monitor = start_node("model_monitor", {"model": str(model), "check_every": 100000},
                         quiet=True)
    try:
        _feed_monitor(READINGS)
        # Validated (known, enough readings held) but not made: these readings carry no
        # temperature, so a thermal drift has nothing to be fitted to. Said as the
        # command's refusal - one line, exit 2 - with the monitor's reason; the version
        # stays.
        drift = _cli("add", "structural_thermal_drift")
        assert drift.returncode == 2, (drift.stdout, drift.stderr)
        assert "add structural_thermal_drift refused: cannot fit structural_thermal_drift" in \
            drift.stderr, drift.stderr
        assert len(drift.stderr.strip().splitlines()) == 1 and drift.stdout == ""
        assert _cli("show", "--timeout", "30").stdout.startswith("version 1: start")
        # Made: the version it made and its reason, printed once it is live.
        added = _cli("add", "squareness:EC0Y")
        assert added.returncode == 0, added.stderr
        assert added.stdout == ("add squareness:EC0Y: accepted by /model_monitor - version 2 "
                                "live (added squareness:EC0Y (user))\n")
        shown = _cli("show", "--timeout", "30")
        assert shown.stdout.startswith("version 2: added squareness:EC0Y (user)")
        entry = yaml.safe_load(shown.stdout.split("\n\n", 1)[1])["effects"]["squareness:EC0Y"]
        angle, u = entry["coefficients"]["angle_rad"], entry["uncertainties"]["angle_rad"]
        assert abs(angle - TRUE_ANGLE_RAD) < 3 * u and u < 2e-6, (angle, u)
        # Asked again: held already, nothing to change - accepted, the version as it was.
        again = _cli("add", "squareness:EC0Y")
        assert again.returncode == 0 and "version 2 live (nothing to change)" in again.stdout
        assert monitor.popen.poll() is None
    finally:
        monitor.stop()
