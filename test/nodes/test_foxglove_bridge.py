"""The Foxglove bridge, tested by a WebSocket client speaking the Foxglove protocol."""
from __future__ import annotations

import json
import re
import socket
import struct
import time

from conftest import REPO_ROOT
from mt_accuracy_ros.commands.processes import start_node

#: What the foxglove-sdk server speaks (the protocol's current name; v1 is the legacy one).
SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_bridge_relays_topics_a_foxglove_client_decodes(tmp_path):
    from rclpy.serialization import deserialize_message
    from websockets.exceptions import InvalidHandshake
    from websockets.sync.client import connect

    from mt_accuracy_msgs.msg import TemperatureArray

    scenario = tmp_path / "s.yaml"
    scenario.write_text("machine: kidani_hmc\nduration_s: 600\nsample_rate_hz: 100\n"
                        "temperature_rate_hz: 5\n"
                        "program: {type: back_and_forth, axes: [X], feed_m_per_min: 10}\n")
    port = _free_port()
    bridge = start_node("foxglove_bridge", {"port": port, "discovery_period_s": 0.2}, quiet=True)
    publisher = start_node("temperature_publisher", {"scenario": str(scenario)}, quiet=True)
    try:
        deadline = time.monotonic() + 60
        connection = None
        while connection is None and time.monotonic() < deadline:
            try:
                connection = connect(f"ws://127.0.0.1:{port}", subprotocols=SUBPROTOCOLS,
                                     open_timeout=5, max_size=None)
            except (OSError, InvalidHandshake):
                time.sleep(0.2)
        assert connection is not None, \
            f"the bridge's server did not come up (bridge exit code {bridge.popen.poll()})"
        deadline = time.monotonic() + 60  # a fresh minute for discovery and data
        with connection:
            channels, decoded = {}, None
            # Each advertisement of /temperatures gets its own subscription (a channel
            # advertised again has a new id); what the server said is kept for the message.
            subscriptions, said, binary = set(), [], []
            while decoded is None and time.monotonic() < deadline:
                try:
                    frame = connection.recv(timeout=max(0.1, deadline - time.monotonic()))
                except TimeoutError:
                    break
                if isinstance(frame, str):
                    message = json.loads(frame)
                    said.append(message["op"] if message["op"] == "advertise" else message)
                    advertised = message["channels"] if message["op"] == "advertise" else []
                    # The server once answered a subscription to the channel it had just
                    # advertised with "Unknown channel ID" (an idle run, foxglove-sdk
                    # 0.30.3): a client asks again, as the Foxglove app does.
                    temperatures = channels.get("/temperatures")
                    if message["op"] == "status" and temperatures and \
                            message.get("message") == f"Unknown channel ID: {temperatures['id']}":
                        time.sleep(0.2)
                        advertised = [temperatures]
                    for channel in advertised:
                        channels[channel["topic"]] = channel
                        if channel["topic"] == "/temperatures":
                            subscriptions.add(7 + len(subscriptions))
                            connection.send(json.dumps({"op": "subscribe", "subscriptions": [
                                {"id": max(subscriptions), "channelId": channel["id"]}]}))
                    continue
                opcode, subscription, _log_time = struct.unpack_from("<BIQ", frame)
                binary.append((opcode, subscription))
                if opcode == 1 and subscription in subscriptions:
                    decoded = deserialize_message(frame[13:], TemperatureArray)
        assert "/temperatures" in channels, f"advertised only {sorted(channels)}; bridge " \
            f"exit code {bridge.popen.poll()}, publisher {publisher.popen.poll()}"
        temperatures = channels["/temperatures"]
        assert temperatures["encoding"] == "cdr"
        assert temperatures["schemaName"] == "mt_accuracy_msgs/msg/TemperatureArray"
        assert temperatures["schemaEncoding"] == "ros2msg"
        assert "float64[] temperatures" in temperatures["schema"]
        assert "/error_map" in channels  # the 3-D error map (foxglove.SceneUpdate)
        assert decoded is not None, f"no /temperatures data: server said {said[-10:]}, binary " \
            f"frames {binary[-10:]}, publisher exit code {publisher.popen.poll()}"
        assert len(decoded.sensor_names) == len(decoded.temperatures) > 0
    finally:
        publisher.stop()
        bridge.stop()


def test_the_shipped_layout_names_topics_the_graph_publishes():
    layout = json.loads((REPO_ROOT / "foxglove" / "mt_accuracy_layout.json").read_text())
    published = {"/yaw/x", "/yaw/y", "/yaw/z", "/systematic/x", "/systematic/y", "/systematic/z",
                 "/compensation", "/model_check", "/temperatures", "/diagnostics", "/error_map",
                 "/scales", "/reference/tcp_error"}
    text = json.dumps(layout["configById"])
    named = set(re.findall(r'"(/[a-z_]+(?:/[a-z_]+)?)', text))
    assert named and named <= published, named - published
    # Every panel in the mosaic is configured.
    mosaic = json.dumps(layout["layout"])
    assert set(re.findall(r'"(\w+![a-z]+)"', mosaic)) == set(layout["configById"])
    assert {"/error_map", "/compensation", "/temperatures", "/model_check"} <= named


def test_error_map_colours_points_by_the_size_of_the_error(rclpy_context):
    from rclpy.parameter import Parameter

    from mt_accuracy_msgs.msg import VolumetricCompensation
    from mt_accuracy_ros.nodes.foxglove_bridge import FoxgloveBridge

    bridge = FoxgloveBridge(parameter_overrides=[Parameter("port", value=0),
                                                 Parameter("error_map_points", value=3)])
    try:
        for k, size in enumerate([0.0, 5e-6, 10e-6, 20e-6]):
            message = VolumetricCompensation()
            message.command_position.x = 0.1 * k
            message.error.z = size
            bridge._on_compensation(message)
        points = bridge.error_map()
        assert len(points) == 3  # the latest error_map_points
        assert [round(p[0], 6) for p, _ in points] == [0.1, 0.2, 0.3]
        # Full scale = the largest error: red for it, half red for half of it.
        colours = [c for _, c in points]
        assert colours[-1][:3] == (1.0, 0.2, 0.0)
        assert colours[1][0] == 0.5 and colours[0][0] == 0.25
        assert bridge.scene_update() is not None  # builds the foxglove.SceneUpdate
    finally:
        bridge.destroy_node()
