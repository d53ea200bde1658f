"""The CNC bridge against a real OPC UA server that plays the CNC (issue 18).

The server (asyncua, in this process) holds the CNC's variables in the units a
controller uses - axis positions in mm, compensation inputs in um - and the
virtual machine tool drives them: command positions and column temperature
of the demo scenario at successive moments. The bridge node (its own
process) reads them, the compensation broadcaster (its own process) turns
them into corrections, and the bridge writes those back to the server. The
expected correction is the closed form of the model's only effect, a thermal
drift: -beta (T - T_first).
"""
from __future__ import annotations

import socket
import subprocess
import sys

import numpy as np
import pytest
import yaml

from graph_helpers import spin_until
from mt_accuracy_ros.commands.processes import start_node

BETA = np.array([2.0e-6, -4.0e-6, 6.0e-6])  # m/K


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.fixture()
def cnc_server():
    """An OPC UA server with a CNC's variables; yields (url, variables)."""
    from asyncua import ua
    from asyncua.sync import Server

    server = Server()
    url = f"opc.tcp://127.0.0.1:{_free_port()}/cnc/"
    server.set_endpoint(url)
    idx = server.register_namespace("urn:mt-accuracy:test-cnc")
    cnc = server.nodes.objects.add_object(idx, "CNC")
    variables = {}
    for name, value, kind in (("Axis.X", 0.0, ua.VariantType.Double),
                              ("Axis.Y", 0.0, ua.VariantType.Double),
                              ("Axis.Z", 0.0, ua.VariantType.Double),
                              ("Temp.Column", 20.0, ua.VariantType.Double),
                              ("Comp.X", 0.0, ua.VariantType.Double),
                              ("Comp.Y", 0.0, ua.VariantType.Double),
                              ("Comp.Z", 0.0, ua.VariantType.Double),
                              ("Comp.Version", 0, ua.VariantType.UInt32),
                              ("Comp.Stamp", 0, ua.VariantType.Int64)):
        node = cnc.add_variable(ua.NodeId(name, idx), name, ua.Variant(value, kind))
        node.set_writable()
        variables[name] = node
    server.start()
    try:
        yield url, idx, variables
    finally:
        server.stop()


def _node_map(tmp_path, idx: int) -> str:
    path = tmp_path / "cnc_nodes.yaml"
    path.write_text(yaml.safe_dump({
        "axes": {axis: {"node": f"ns={idx};s=Axis.{axis}", "unit": "mm"} for axis in "XYZ"},
        "temperatures": {"column": {"node": f"ns={idx};s=Temp.Column", "unit": "degC"}},
        "compensation": {**{c: {"node": f"ns={idx};s=Comp.{c.upper()}", "unit": "um"}
                            for c in "xyz"},
                         "version": f"ns={idx};s=Comp.Version",
                         "stamp": f"ns={idx};s=Comp.Stamp"}}))
    return str(path)


def test_bridge_reads_the_cnc_and_writes_the_compensation_back(rclpy_context, tmp_path,
                                                               cnc_server):
    import rclpy

    from mt_accuracy_msgs.msg import ScaleBatch
    from mt_accuracy_ros.nodes._common import SENSOR_QOS
    from mt_accuracy_ros.nodes._scenario import resolve_scenario
    from mt_accuracy_ros.sim.machine_tool import simulate

    url, idx, variables = cnc_server
    # The virtual machine behind the server: the demo's commands and column temperature.
    scenario = resolve_scenario("demo")
    run = simulate(scenario, start_index=0, stop_index=1)
    moments_s = [0.0, 20.0, 45.0, 80.0]
    column = run.temperature_names.index("column")
    states = []
    for moment in moments_s:
        sample = simulate(scenario, start_index=int(moment * scenario.sample_rate_hz),
                          stop_index=int(moment * scenario.sample_rate_hz) + 1)
        step = int(round(moment * scenario.temperature_rate_hz))
        states.append(({a: float(sample.command[a][0]) for a in "XYZ"},
                       float(run.temperatures_c[step, column])))
    assert states[-1][1] - states[0][1] > 1.0  # the machine warmed: a drift to compensate

    model = tmp_path / "model.yaml"
    # The reference temperature is given: otherwise it is the first reading the
    # broadcaster happens to get, which on a loaded host may already be a later state.
    model.write_text(yaml.safe_dump({"machine": "kidani_hmc", "effects": {
        "structural_thermal_drift": {"beta_m_per_k": BETA.tolist(), "sensor": "column"}},
        "reference_temperatures_c": {"column": states[0][1]}}))
    node = rclpy.create_node("cnc_operator")
    batches: list = []
    node.create_subscription(ScaleBatch, "scales", batches.append, SENSOR_QOS)

    def serve(state) -> None:
        positions, temperature = state
        for axis, value in positions.items():
            variables[f"Axis.{axis}"].write_value(value * 1e3)  # the CNC speaks mm
        variables["Temp.Column"].write_value(temperature)

    serve(states[0])
    broadcaster = start_node("compensation_broadcaster", {"model": str(model),
                                                          "follow_model_topic": False,
                                                          "input_delay_s": 0.0}, quiet=True)
    bridge = start_node("cnc_bridge", {"url": url, "node_map": _node_map(tmp_path, idx),
                                       "poll_period_s": 0.02, "temperature_period_s": 0.1},
                        quiet=True)
    try:
        assert spin_until(node, lambda: bool(batches), 60), "no data from the bridge"
        for state in states:
            serve(state)
            expected_um = -BETA * (state[1] - states[0][1]) * 1e6

            def arrived(expected_um=expected_um):
                written = np.array([variables[f"Comp.{c}"].read_value() for c in "XYZ"])
                return np.allclose(written, expected_um, atol=1e-6)

            assert spin_until(node, arrived, 30), (
                [variables[f"Comp.{c}"].read_value() for c in "XYZ"], expected_um)
            received = batches[-1]
            assert received.command_axes == ["x", "y", "z"]
            np.testing.assert_allclose(received.command_positions,
                                       [state[0][a] for a in "XYZ"], atol=1e-12)
        assert variables["Comp.Version"].read_value() == 1
        # The stamp written is that of the CNC read the correction was computed for.
        from mt_accuracy_ros.nodes._common import stamp_to_nanoseconds

        stamp = variables["Comp.Stamp"].read_value()
        # The batch of that read may still be on its way to this node on a loaded host:
        # wait for it (the bridge publishes every read it computes a correction for).
        assert spin_until(node, lambda: stamp in {stamp_to_nanoseconds(b.header.stamp)
                                                  for b in batches}, 30), stamp
        assert bridge.popen.poll() is None and broadcaster.popen.poll() is None
    finally:
        bridge.stop()
        broadcaster.stop()
        node.destroy_node()


def _bridge_exit(args: list[str]) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mt_accuracy_ros.nodes.cnc_bridge",
                           "--ros-args", *args], capture_output=True, text=True, timeout=60)


def test_bridge_refuses_a_bad_node_map_and_a_missing_server_in_one_line(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({"axes": {"X": {"node": "ns=2;s=Axis.X", "unit": "inch"}},
                                   "compensation": {c: f"ns=2;s=Comp.{c}" for c in "xyz"}}))
    result = _bridge_exit(["-p", f"node_map:={bad}"])
    assert result.returncode == 2 and "unknown unit 'inch'" in result.stderr, result.stderr
    assert "Traceback" not in result.stderr
    good = tmp_path / "good.yaml"
    good.write_text(yaml.safe_dump({"axes": {"X": "ns=2;s=Axis.X"},
                                    "compensation": {c: f"ns=2;s=Comp.{c}" for c in "xyz"}}))
    result = _bridge_exit(["-p", f"node_map:={good}",
                           "-p", f"url:=opc.tcp://127.0.0.1:{_free_port()}/none"])
    assert result.returncode == 2 and "no OPC UA server" in result.stderr, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
