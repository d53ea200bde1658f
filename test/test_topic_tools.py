"""`mt-accuracy topic list | info | echo | hz` on bags (exact) and on the live graph."""
from __future__ import annotations

import io
from argparse import Namespace

import pytest

from conftest import DATA
from mt_accuracy_ros.cli import main
from mt_accuracy_ros.commands.topic_tools import rate_statistics

TALKER = DATA / "rosbag2_samples" / "talker"


def test_rate_statistics_closed_form():
    stats = rate_statistics([0, 100_000_000, 300_000_000, 400_000_000])
    assert stats.window == 4
    assert stats.average_rate_hz == pytest.approx(1 / (0.4 / 3))
    assert (stats.min_period_s, stats.max_period_s) == pytest.approx((0.1, 0.2))
    assert stats.std_dev_s == pytest.approx(0.04714045, rel=1e-6)
    assert rate_statistics([5]) is None


def test_on_a_rosbag2_bag_like_ros2_topic(capsys):
    assert main(["topic", "list", "-t", "--bag", str(TALKER)]) == 0
    assert capsys.readouterr().out.splitlines() == [
        "/parameter_events [rcl_interfaces/msg/ParameterEvent]",
        "/rosout [rcl_interfaces/msg/Log]", "/topic [std_msgs/msg/String]"]
    assert main(["topic", "info", "/topic", "--bag", str(TALKER)]) == 0
    assert capsys.readouterr().out == "Type: std_msgs/msg/String\nMessage count: 10\n"
    assert main(["topic", "echo", "/topic", "--bag", str(TALKER), "-n", "2"]) == 0
    assert capsys.readouterr().out == "data: Hello, world! 0\n---\ndata: Hello, world! 1\n---\n"
    assert main(["topic", "echo", "/nope", "--bag", str(TALKER)]) == 2
    error = capsys.readouterr().err
    assert error.startswith("mt-accuracy topic: topic /nope is not in") and error.count("\n") == 1


def test_hz_of_a_bag_is_exact(tmp_path, capsys):
    from rclpy.serialization import serialize_message
    from std_msgs.msg import String

    from mt_accuracy_ros.io.bag_writer import BagWriter

    with BagWriter(tmp_path / "bag") as bag:
        bag.add_topic("/chatter", "std_msgs/msg/String")
        for i in range(50):
            bag.write("/chatter", serialize_message(String(data=str(i))), 10**9 + i * 40_000_000)
    assert main(["topic", "hz", "/chatter", "--bag", str(tmp_path / "bag")]) == 0
    assert capsys.readouterr().out == ("average rate: 25.000\n\tmin: 0.040s max: 0.040s "
                                       "std dev: 0.00000s window: 50\n")


def test_on_the_live_graph(tmp_path):
    from mt_accuracy_ros.commands.processes import start_node
    from mt_accuracy_ros.commands.topic_tools import cmd_echo, cmd_hz, cmd_info, cmd_list

    scenario = tmp_path / "s.yaml"
    scenario.write_text("machine: kidani_hmc\nduration_s: 600\nsample_rate_hz: 100\n"
                        "temperature_rate_hz: 5\n"
                        "program: {type: back_and_forth, axes: [X], feed_m_per_min: 10}\n")
    publisher = start_node("temperature_publisher", {"scenario": str(scenario)}, quiet=True)
    try:
        out = io.StringIO()
        cmd_echo(Namespace(topic="/temperatures", bag=None, spin_time=30.0, once=True, count=0,
                           no_arr=False, truncate_length=2, duration=60.0), out)
        text = out.getvalue()
        assert text.startswith("header:") and "sensor_names:" in text and text.endswith("---\n")
        out = io.StringIO()
        cmd_info(Namespace(topic="/temperatures", bag=None, spin_time=30.0), out)
        assert out.getvalue().startswith("Type: mt_accuracy_msgs/msg/TemperatureArray\n"
                                         "Publisher count: 1\n")
        # `list` shows what discovery found in its spin time; a fresh participant may
        # need more than one look, so ask again (up to a minute) rather than trust luck.
        listed = ""
        for _ in range(20):
            out = io.StringIO()
            cmd_list(Namespace(bag=None, spin_time=3.0, show_types=True), out)
            listed = out.getvalue()
            if "/temperatures" in listed:
                break
        assert "/temperatures [mt_accuracy_msgs/msg/TemperatureArray]" in listed
        out = io.StringIO()
        cmd_hz(Namespace(topic="/temperatures", bag=None, spin_time=30.0, window=100, count=3,
                         duration=60.0), out)
        assert "average rate:" in out.getvalue() or "no new messages" in out.getvalue()
    finally:
        publisher.stop()


@pytest.mark.parametrize("argv, words", [
    (["hz", "/topic", "--bag", str(TALKER), "--duration", "2"],
     "--duration applies to the live graph, not to a bag"),
    (["list", "--bag", str(TALKER), "--spin-time", "3"],
     "--spin-time applies to the live graph, not to a bag"),
    (["hz", "/topic", "--bag", str(TALKER), "-n", "3"],
     "-n/--count applies to the live graph, not to a bag"),
    (["hz", "/topic", "--use-header-stamp"],
     "--use-header-stamp applies to a bag (--bag), not to the live graph"),
    (["echo", "/topic", "--bag", str(TALKER), "--truncate-length", "-1"],
     "--truncate-length must be an integer >= 0 [0: whole arrays], got -1"),
    (["hz", "/topic", "--bag", str(TALKER), "-w", "-2"],
     "-w/--window must be an integer >= 0 [messages; 0: all], got -2"),
    (["echo", "/topic", "--spin-time", "0"], "--spin-time must be > 0 [s], got 0"),
    (["list", "--bag", "/no/such/bag"], "no such bag"),
])
def test_options_out_of_range_or_out_of_place_are_refused_in_one_line(capsys, argv, words):
    assert main(["topic", *argv]) == 2
    error = capsys.readouterr().err
    assert words in error and error.count("\n") == 1
