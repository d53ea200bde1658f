"""Simulator output: bag (read back by rosbags), CSV, the simulate CLI, the ball bar."""
from __future__ import annotations

import json

import numpy as np
import pytest

from mt_accuracy_ros.sim.instruments import ball_bar
from mt_accuracy_ros.sim.machine_tool import simulate
from mt_accuracy_ros.sim.scenario import scenario_from_yaml

SCENARIO = """machine: kidani_hmc
seed: 2
duration_s: 3
sample_rate_hz: 2000
temperature_rate_hz: 2
program: {type: back_and_forth, axes: [X, Y], feed_m_per_min: 20}
effects: {timing_skew: true}
"""


def test_simulate_cli_writes_a_bag_rosbags_reads_and_csv(tmp_path):
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg

    from mt_accuracy_ros.cli import main

    (tmp_path / "s.yaml").write_text(SCENARIO)
    assert main(["simulate", str(tmp_path / "s.yaml"), "--out", str(tmp_path / "out"), "-q"]) == 0
    result = simulate(scenario_from_yaml(SCENARIO))
    store = get_typestore(Stores.ROS2_JAZZY)
    with Reader(tmp_path / "out" / "bag") as reader:
        for connection in reader.connections:
            store.register(get_types_from_msg(connection.msgdef.data, connection.msgtype))
        scales, temperatures = [], []
        for connection, _, raw in reader.messages():
            message = store.deserialize_cdr(raw, connection.msgtype)
            (scales if connection.topic == "/scales" else temperatures).append(message)
    assert len(scales) == 60 and len(temperatures) == result.temperature_time_s.size
    positions = np.concatenate([m.positions for m in scales]).reshape(-1, 6)
    np.testing.assert_array_equal(positions, result.scale_readings)
    assert list(scales[0].channel_names) == result.scale_channels
    assert [m.first_sample_index for m in scales] == list(range(0, 6000, 100))
    np.testing.assert_array_equal(temperatures[-1].temperatures, result.temperatures_c[-1])
    table = np.loadtxt(tmp_path / "out" / "scales.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(table[:, 4:], result.scale_readings, rtol=1e-9, atol=1e-15)
    summary = json.loads((tmp_path / "out" / "simulation.json").read_text())
    assert summary["samples"] == 6000 and "timing_skew" in summary["effects_on"]


def test_simulate_cli_reports_bad_scenarios_with_exit_code_2(tmp_path, capsys):
    from mt_accuracy_ros.cli import main

    (tmp_path / "bad.yaml").write_text("machine: kidani_hmc\neffects:\n  flux: true\n")
    assert main(["simulate", str(tmp_path / "bad.yaml"), "--out", str(tmp_path / "o")]) == 2
    assert "bad.yaml, line 3: unknown effect 'flux'" in capsys.readouterr().err


def test_ball_bar_sees_squareness_as_the_textbook_signature():
    text = ("machine: kidani_hmc\nseed: 1\nduration_s: 20\nsample_rate_hz: 200\n"
            "program: {type: circle, axes: [X, Y], radius_m: 0.1, feed_m_per_min: 2}\n"
            "noise: {scale_m: 0}\neffects: {geometric: false%s}\n")
    on = simulate(scenario_from_yaml(text % ", squareness: {errors_rad: {EC0Y: 40e-6}}"))
    off = simulate(scenario_from_yaml(text % ""))
    a = ball_bar(on, stride=10, noise_m=0.0, resolution_m=0.0)
    b = ball_bar(off, stride=10, noise_m=0.0, resolution_m=0.0)
    assert np.abs(b.radial_deviation_m).max() < 1e-12
    program = on.program
    y = program.center_m[1] + program.radius_m * np.sin(a.angle_rad)
    # e_x = -S (y + c), c the Y frame's lever to the TCP: radial part -S (y + c) cos(phi),
    # the diagonal ellipse of ISO 230-4 plus a centre offset.
    basis = np.column_stack([y * np.cos(a.angle_rad), np.cos(a.angle_rad), np.sin(a.angle_rad)])
    coefficients, *_ = np.linalg.lstsq(basis, a.radial_deviation_m, rcond=None)
    assert coefficients[0] == pytest.approx(-40e-6, rel=1e-3)
    assert np.abs(basis @ coefficients - a.radial_deviation_m).max() < 1e-10


def test_circle_leaving_the_stroke_is_refused():
    from mt_accuracy_ros.core.errors import ScenarioError

    with pytest.raises(ScenarioError, match="outside the X stroke"):
        scenario_from_yaml("machine: kidani_hmc\nprogram: {type: circle, radius_m: 0.3}\n")


def test_reference_readings_are_the_machines_tcp_error_within_the_probe_noise(tmp_path, capsys):
    """``simulate --reference-period``: a probe's reading of the uncompensated TCP error
    every period, read back by the MCAP ROS 2 decoder Foxglove uses; within the probe's
    noise of the simulator's truth and with the CNC's last direction of each axis."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    from mt_accuracy_ros.cli import main
    from mt_accuracy_ros.sim.export import PROBE_UNCERTAINTY_M

    text = SCENARIO.replace("duration_s: 3", "duration_s: 30")
    (tmp_path / "s.yaml").write_text(text)
    assert main(["simulate", str(tmp_path / "s.yaml"), "--out", str(tmp_path / "out"), "-q",
                 "--no-csv", "--reference-period", "0.25"]) == 0
    result = simulate(scenario_from_yaml(text))
    readings = []
    for path in sorted((tmp_path / "out" / "bag").glob("*.mcap")):
        with open(path, "rb") as stream:
            reader = make_reader(stream, decoder_factories=[DecoderFactory()])
            for _, _, record, m in reader.iter_decoded_messages(topics=["/reference/tcp_error"]):
                readings.append((record.log_time, m))
    assert len(readings) == 120
    start_ns = int(round(result.scenario.start_time_s * 1e9))
    picks = np.array([(stamp - start_ns) * 2000 // 10**9 for stamp, _ in readings])
    np.testing.assert_array_equal(picks, np.arange(0, 60000, 500))
    truth = result.tcp_error(picks)
    seen = np.array([[m.error.x, m.error.y, m.error.z] for _, m in readings])
    noise = seen - truth
    assert np.abs(noise).max() < 5 * PROBE_UNCERTAINTY_M / 2      # 5 sigma of the probe
    assert 0.3e-6 < noise.std() < 0.7e-6                             # its sigma, 0.5 um
    assert np.abs(truth).max() > 5 * PROBE_UNCERTAINTY_M             # the machine's error shows
    first = readings[7][1]
    axes = list(result.scenario.machine.axis_order)
    assert list(first.command_axes) == [a.lower() for a in axes]
    assert list(first.command_positions) == [result.command[a][picks[7]] for a in axes]
    velocity = np.array([result.velocity["X"][p] for p in picks])
    directions = np.array([m.command_directions[axes.index("X")] for _, m in readings])
    moving = np.abs(velocity) > 1e-9
    np.testing.assert_array_equal(directions[moving], np.sign(velocity[moving]))
    assert all(m.uncertainty == PROBE_UNCERTAINTY_M and list(m.measured) == [True] * 3
               for _, m in readings)
    assert main(["simulate", str(tmp_path / "s.yaml"), "--out", str(tmp_path / "o2"),
                 "--reference-period", "0"]) == 2
    assert "--reference-period must be" in capsys.readouterr().err
