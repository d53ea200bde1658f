"""The live graph (issue 7): discovery, the compensation against the core model, refused
parameters, two namespaced machines, latched tables for late joiners, and all nodes
composed in one executor."""
from __future__ import annotations

import time

import numpy as np
import yaml

from graph_helpers import call_service, spin_for, spin_until
from mt_accuracy_ros.commands.processes import start_node

SCENARIO = """machine: kidani_hmc
seed: {seed}
duration_s: {duration}
sample_rate_hz: 1000
temperature_rate_hz: 2
program: {{type: back_and_forth, axes: [X, Y], feed_m_per_min: 20}}
effects: {{structural_thermal_drift: {{time_constant_s: 5}}}}
"""


def _scenario(tmp_path, seed=1, duration=4.0, name="s.yaml"):
    path = tmp_path / name
    path.write_text(SCENARIO.format(seed=seed, duration=duration))
    return str(path)


def _set(node, target, name, value):
    from mt_accuracy_ros.commands.model_tools import set_remote_parameter

    return set_remote_parameter(node, target, name, value)


def test_graph_topics_types_and_refused_parameters(rclpy_context, tmp_path):
    import rclpy

    probe = rclpy.create_node("probe")
    # Long enough that the machine still streams however slowly a loaded host brings
    # the five processes up; the processes are stopped at the end anyway.
    scenario = _scenario(tmp_path, duration=600.0)
    machine = {"scenario": scenario, "rate_factor": 1.0}
    processes = [start_node("temperature_publisher", machine),
                 start_node("encoder_publisher", {**machine, "batch_period_s": 0.05}),
                 start_node("yaw_estimator"), start_node("compensation_broadcaster"),
                 start_node("model_monitor")]
    expected = {
        "/scales": "mt_accuracy_msgs/msg/ScaleBatch",
        "/temperatures": "mt_accuracy_msgs/msg/TemperatureArray",
        "/reference/tcp_error": "mt_accuracy_msgs/msg/ReferenceMeasurement",
        "/yaw/x": "mt_accuracy_msgs/msg/YawBatch", "/yaw/y": "mt_accuracy_msgs/msg/YawBatch",
        "/systematic/y": "mt_accuracy_msgs/msg/SystematicProfile",
        "/compensation": "mt_accuracy_msgs/msg/VolumetricCompensation",
        "/compensation_table": "mt_accuracy_msgs/msg/CompensationTable",
        "/model_check": "mt_accuracy_msgs/msg/ModelCheck",
        "/model": "mt_accuracy_msgs/msg/ModelVersion",
        "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"}
    try:
        def discovered():
            # What `ros2 topic list -t` prints, through the same graph API.
            return {name: types[0] for name, types in probe.get_topic_names_and_types()}
        assert spin_until(probe, lambda: expected.items() <= discovered().items(), timeout_s=60)
        assert spin_until(probe, lambda: {"encoder_publisher", "temperature_publisher",
                                          "yaw_estimator", "compensation_broadcaster",
                                          "model_monitor"} <= set(probe.get_node_names()))
        # Endpoint counts settle after the names are known (slower on a loaded host).
        assert spin_until(probe, lambda: probe.count_publishers("/scales") == 1 and
                          probe.count_publishers("/temperatures") == 1, timeout_s=30)
        refused = [
            ("/compensation_broadcaster", "model", "no_such_model", "model refused"),
            ("/compensation_broadcaster", "publish_rate_hz", 0.5, ""),
            ("/model_monitor", "add_effects", ["warp_drive"], "unknown effect"),
            ("/model_monitor", "add_effects", ["squareness"], "cannot fit squareness"),
            ("/temperature_publisher", "dead_sensors", ["no_such_sensor"], "unknown sensor"),
            ("/yaw_estimator", "k_lim", 5, "read-only"),
        ]
        from diagnostic_msgs.msg import DiagnosticArray

        reports: list[str] = []
        probe.create_subscription(DiagnosticArray, "/diagnostics", lambda m: reports.extend(
            f"{s.name}: {s.message}" for s in m.status), 10)
        for target, name, value, reason in refused:
            ok, text = _set(probe, target, name, value)
            assert not ok, (target, name)
            assert reason.lower() in text.lower(), text
        # Refusals by the descriptor (rclpy's own range and read-only checks) are counted
        # and said on /diagnostics too (issue 29).
        for node, text in (("yaw_estimator", "parameters: refused: k_lim is read-only"),
                           ("compensation_broadcaster",
                            "parameters: refused: publish_rate_hz: 0.5 outside")):
            assert spin_until(probe, lambda: any(node in r and text in r for r in reports),
                              timeout_s=20), (node, [r for r in reports if "refused" in r])
        ok, _ = _set(probe, "/temperature_publisher", "dead_sensors", ["column"])
        assert ok
        # A dead thermocouple: the nodes keep running and say so on /diagnostics.
        for node in ("compensation_broadcaster", "yaw_estimator"):
            assert spin_until(probe, lambda: any(
                node in r and "no valid reading from column" in r for r in reports),
                timeout_s=20), node
    finally:
        for process in processes:
            process.stop()
        probe.destroy_node()


def test_broadcast_compensation_equals_the_core_model(rclpy_context, tmp_path):
    """Known commands and temperatures in; every published error = ErrorModel to 1e-12."""
    import rclpy

    from mt_accuracy_msgs.msg import ScaleBatch, TemperatureArray, VolumetricCompensation
    from mt_accuracy_ros.core.compensation.error_model import model_from_dict
    from mt_accuracy_ros.nodes._common import (RESULT_QOS, SENSOR_QOS, nanoseconds_to_stamp,
                                               pack_float64, stamp_to_nanoseconds)

    model_data = {"machine": "kidani_hmc", "reference_temperatures_c": {"column": 20.0},
                  "effects": {"squareness": {"errors_rad": {"EC0Y": 30e-6, "EB0Z": -20e-6}},
                              "structural_thermal_drift": {"beta_m_per_k": [1e-6, 4e-6, 2e-6],
                                                           "sensor": "column"},
                              "abbe_offset": {"offset_m": [0.1, 0.0, 0.05]},
                              "servo_lag": {"lag_s": 1e-3, "axes": ["X", "Y", "Z"]}}}
    (tmp_path / "model.yaml").write_text(yaml.safe_dump(model_data))
    probe = rclpy.create_node("probe")
    received: list[VolumetricCompensation] = []
    probe.create_subscription(VolumetricCompensation, "compensation", received.append, RESULT_QOS)
    scales = probe.create_publisher(ScaleBatch, "scales", SENSOR_QOS)
    temperatures = probe.create_publisher(TemperatureArray, "temperatures", SENSOR_QOS)
    broadcaster = start_node("compensation_broadcaster", {"model": str(tmp_path / "model.yaml"),
                                                          "follow_model_topic": False,
                                                          "publish_rate_hz": 250.0})
    rng = np.random.default_rng(4)
    base = 1_700_000_000 * 10**9
    sent = []
    def batch_message(index, commands):
        message = ScaleBatch()
        message.header.stamp = nanoseconds_to_stamp(base + index * 40 * 10**6)
        message.first_sample_index = index * 40
        message.sample_period = 1e-3
        message.channel_names = ["x1", "x2"]
        message.positions = pack_float64(np.zeros(80))
        message.command_axes = ["z", "x", "y"]
        message.command_positions = pack_float64(commands[:, [2, 0, 1]].ravel())
        return message

    try:
        assert spin_until(probe, lambda: scales.get_subscription_count() >= 1 and
                          temperatures.get_subscription_count() >= 1)
        # Best-effort streams: the broadcaster may match this probe a little after the
        # probe matched it (more on a loaded host). Warm up - temperature and batches of
        # the same stream - until a correction comes back, instead of a fixed wait.
        temperature = TemperatureArray(sensor_names=["column"])
        temperature.temperatures = pack_float64([22.5])
        warm = 0
        while not received:
            assert warm < 200, "the broadcaster never answered"
            temperature.header.stamp = nanoseconds_to_stamp(base - 10**9 + warm * 10**6)
            temperatures.publish(temperature)
            scales.publish(batch_message(warm, np.full((40, 3), 0.1)))
            warm += 1
            spin_for(probe, 0.1)
        first = warm
        for batch in range(10):
            commands = np.column_stack([np.linspace(0.05, 0.3, 40) + 0.01 * batch,
                                        rng.uniform(-0.4, -0.05, 1).repeat(40),
                                        np.linspace(0.1, 0.2, 40)])
            message = batch_message(first + batch, commands)
            scales.publish(message)
            sent.append(commands)
            spin_for(probe, 0.05)
        start = base + first * 40 * 10**6

        def ours():
            return [m for m in received if stamp_to_nanoseconds(m.header.stamp) >= start]

        # A deadline only against a hung broadcaster: it ends at the 100th correction, and
        # a heavily loaded host took more than 20 s to send them.
        assert spin_until(probe, lambda: len(ours()) >= 100, timeout_s=120)
        received = ours()
    finally:
        broadcaster.stop()
    probe.destroy_node()
    model = model_from_dict(model_data)
    commands = np.concatenate(sent)
    velocity = np.concatenate([np.gradient(c, 1e-3, axis=0) for c in sent])
    rows = np.arange(3, commands.shape[0], 4)  # 250 Hz of 1 kHz data: each interval's newest
    error, _ = model.tcp_error({"X": commands[rows, 0], "Y": commands[rows, 1],
                                "Z": commands[rows, 2]}, {"column": 22.5},
                               {"X": velocity[rows, 0], "Y": velocity[rows, 1],
                                "Z": velocity[rows, 2]})
    got = np.array([[m.error.x, m.error.y, m.error.z] for m in received])
    assert got.shape == error.shape
    np.testing.assert_allclose(got, error, rtol=0, atol=1e-12)
    np.testing.assert_allclose([[m.correction.x, m.correction.y, m.correction.z]
                                for m in received], -error, rtol=0, atol=1e-12)
    assert np.abs(error).max() > 5e-6  # the comparison is not of zeros


def test_two_namespaced_machines_run_side_by_side(rclpy_context, tmp_path):
    import rclpy

    from mt_accuracy_msgs.msg import YawBatch
    from mt_accuracy_ros.nodes._common import RESULT_QOS, unpack_float64

    probe = rclpy.create_node("probe")
    yaws = {"/mt1": [], "/mt2": []}
    for ns in yaws:
        probe.create_subscription(YawBatch, f"{ns}/yaw/y", yaws[ns].append, RESULT_QOS)
    processes = []
    for ns, seed in (("/mt1", 1), ("/mt2", 2)):
        processes.append(start_node("yaw_estimator", {"thermal_correction": False}, namespace=ns))
    try:
        assert spin_until(probe, lambda: probe.count_subscribers("/mt1/scales") >= 1 and
                          probe.count_subscribers("/mt2/scales") >= 1)
        encoders = [start_node("encoder_publisher", {"batch_period_s": 0.05,
            "scenario": _scenario(tmp_path, seed=seed, duration=3.0, name=f"{seed}.yaml"),
            "rate_factor": 2.0, "min_subscribers": 1}, namespace=ns)
            for ns, seed in (("/mt1", 1), ("/mt2", 2))]
        # Until both machines have streamed their 3 s and ended: a loaded host took more
        # than 60 s to start two encoders and match their subscribers.
        assert spin_until(probe, lambda: all(e.popen.poll() is not None for e in encoders),
                          timeout_s=240)
        spin_for(probe, 0.5)
        topics = dict(probe.get_topic_names_and_types())
        assert "/mt1/compensation" not in topics and "/yaw/y" not in topics  # nothing leaked
    finally:
        for process in processes:
            process.stop()
        probe.destroy_node()
    assert [b.first_sample_index for b in yaws["/mt1"]] == list(range(0, 3000, 50))
    assert [b.first_sample_index for b in yaws["/mt2"]] == list(range(0, 3000, 50))
    one = np.concatenate([unpack_float64(b.yaw) for b in yaws["/mt1"]])
    two = np.concatenate([unpack_float64(b.yaw) for b in yaws["/mt2"]])
    assert not np.allclose(one, two)  # two machines (seeds), two different yaw profiles


def test_late_joiner_receives_the_latched_tables(rclpy_context):
    import rclpy

    from mt_accuracy_msgs.msg import CompensationTable
    from mt_accuracy_ros.nodes._common import TABLE_QOS

    broadcaster = start_node("compensation_broadcaster")
    probe = rclpy.create_node("probe")
    try:
        assert spin_until(probe, lambda: probe.count_publishers("/compensation_table") >= 1)
        spin_for(probe, 1.0)  # the tables went out long before anyone listened
        late = rclpy.create_node("late_joiner")
        tables: list[CompensationTable] = []
        late.create_subscription(CompensationTable, "/compensation_table", tables.append,
                                 TABLE_QOS)
        assert spin_until(late, lambda: len(tables) >= 3, timeout_s=20)
        late.destroy_node()
    finally:
        broadcaster.stop()
        probe.destroy_node()
    assert sorted(t.axis for t in tables) == ["x", "y", "z"]
    table = tables[0]
    values = np.asarray(table.values).reshape(-1, len(table.columns))
    assert table.columns[0].endswith("_m") and values.shape[1] == 7


def test_all_nodes_composed_in_one_executor(rclpy_context, tmp_path):
    """The same node classes, one process, one executor (a composed deployment)."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter

    from mt_accuracy_msgs.msg import ModelCheck, VolumetricCompensation
    from mt_accuracy_ros.nodes._common import RESULT_QOS
    from mt_accuracy_ros.nodes.compensation_broadcaster import (COMPENSATION_QOS,
                                                                CompensationBroadcaster)
    from mt_accuracy_ros.nodes.encoder_publisher import EncoderPublisher
    from mt_accuracy_ros.nodes.model_monitor import ModelMonitor
    from mt_accuracy_ros.nodes.temperature_publisher import TemperaturePublisher
    from mt_accuracy_ros.nodes.yaw_estimator import YawEstimator

    scenario = _scenario(tmp_path, duration=20.0)
    start = time.time_ns() + 500_000_000
    machine = [Parameter("scenario", value=scenario), Parameter("rate_factor", value=4.0),
               Parameter("start_stamp_ns", value=start)]
    nodes = [YawEstimator(), CompensationBroadcaster(), ModelMonitor(
                 parameter_overrides=[Parameter("min_readings", value=20)]),
             TemperaturePublisher(parameter_overrides=machine),
             EncoderPublisher(parameter_overrides=machine + [
                 Parameter("batch_period_s", value=0.05)])]
    listener = rclpy.create_node("listener")
    checks, compensation = [], []
    listener.create_subscription(ModelCheck, "model_check", checks.append, RESULT_QOS)
    # A subscriber that one executor serves late: its history must hold the whole
    # backlog (the broadcaster's own history is as deep) - nothing is lost silently.
    listener.create_subscription(VolumetricCompensation, "compensation", compensation.append,
                                 COMPENSATION_QOS)
    executor = SingleThreadedExecutor()
    for node in nodes + [listener]:
        executor.add_node(node)
    try:
        deadline = time.monotonic() + 40
        while not nodes[-1].finished and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        # Drain: until every sample is accounted for by the broadcaster and every
        # compensation it sent has reached the listener (a condition, not a sleep).
        # The monitor's search runs in its worker process: its first check may come after
        # the machine stopped.
        def drained() -> bool:
            counts = nodes[1].health.counts["scales"]
            return counts["first_seen"] + counts["processed"] + counts["lost"] >= 20000 and \
                len(compensation) >= nodes[1]._compensation_sequence and bool(checks)
        deadline = time.monotonic() + 60
        while not drained() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        for _ in range(10):  # anything beyond would show as an extra message below
            executor.spin_once(timeout_sec=0.02)
    finally:
        for node in nodes + [listener]:
            executor.remove_node(node)
            node.destroy_node()
    assert nodes[-1].finished
    # On a loaded machine one executor may serve the best-effort scales late and the
    # broadcaster's history drops batches; what matters is that every sample is
    # accounted for: before the first batch it saw, processed, or counted lost (20 s at 1 kHz).
    scales = nodes[1].health.counts["scales"]
    assert scales["first_seen"] + scales["processed"] + scales["lost"] == 20000
    # One compensation per 10 processed samples (100 Hz of 1 kHz data), all published...
    assert nodes[1]._compensation_sequence == scales["processed"] // 10
    # ...and every one the broadcaster sent arrived, in order: no gap in sequence.
    assert [m.sequence for m in compensation] == list(range(nodes[1]._compensation_sequence))
    assert scales["processed"] > 0
    assert checks and "structural_thermal_drift" in {s.effect for s in checks[-1].ranking}
    # Where the residual lives travels with every check: variable, component, share.
    last = checks[-1]
    assert len(last.localisation_variables) == len(last.localisation_components) == \
        len(last.localisation_shares) > 0
    assert all(share <= 1.0 for share in last.localisation_shares)
    assert set(last.localisation_components) <= {"x", "y", "z"}
    for score in list(last.named) + list(last.ranking):
        assert len(score.parameter_names) == len(score.parameters) == \
            len(score.parameter_uncertainties)


def test_parameters_load_from_the_config_yaml(rclpy_context):
    """config/demo.yaml (ros2 --params-file format) reaches the node."""
    import rclpy
    from rcl_interfaces.srv import GetParameters

    from conftest import REPO_ROOT

    estimator = start_node("yaw_estimator", params_file=str(REPO_ROOT / "config" / "demo.yaml"))
    probe = rclpy.create_node("probe")
    try:
        client = probe.create_client(GetParameters, "/yaw_estimator/get_parameters")
        response = call_service(probe, client, GetParameters.Request(
            names=["tolerance_rad", "baseline_after_s", "niceness"]))
        values = [v.double_value for v in response.values[:2]]
        niceness = response.values[2].integer_value
    finally:
        estimator.stop()
        probe.destroy_node()
    expected = yaml.safe_load((REPO_ROOT / "config" / "demo.yaml").read_text())
    parameters = expected["/**/yaw_estimator"]["ros__parameters"]
    assert values == [parameters["tolerance_rad"], parameters["baseline_after_s"]]
    assert niceness == parameters["niceness"] == -15


def test_the_high_rate_config_reaches_the_estimator(rclpy_context):
    """config/high_rate.yaml (the 20 kHz settings of docs/benchmarks.md) loads as is."""
    import rclpy
    from rcl_interfaces.srv import GetParameters

    from conftest import REPO_ROOT

    path = REPO_ROOT / "config" / "high_rate.yaml"
    estimator = start_node("yaw_estimator", params_file=str(path))
    probe = rclpy.create_node("probe")
    try:
        client = probe.create_client(GetParameters, "/yaw_estimator/get_parameters")
        response = call_service(probe, client, GetParameters.Request(names=["reselect_every"]))
        value = response.values[0].integer_value
    finally:
        estimator.stop()
        probe.destroy_node()
    assert value == yaml.safe_load(path.read_text())["yaw_estimator"]["ros__parameters"][
        "reselect_every"] == 40000
