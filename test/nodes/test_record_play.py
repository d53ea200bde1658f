"""Recorder and player as real processes: record a live graph, validate the bag with
rosbags, replay it through the estimator with use_sim_time and get the same outputs."""
from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from mcap.writer import Writer

from graph_helpers import call_service, spin_for, spin_until
from mt_accuracy_ros.core.errors import BagError
from mt_accuracy_ros.io.bag_reader import bag_info, decode, read_messages, recover
from mt_accuracy_ros.io.bag_writer import BagWriter, qos_dict
from mt_accuracy_ros.commands.processes import start_node


SCENARIO = """machine: kidani_hmc
seed: 12
duration_s: 4
sample_rate_hz: 2000
temperature_rate_hz: 4
program: {type: back_and_forth, axes: [X, Y], feed_m_per_min: 30}
effects: {scale_thermal_expansion: {time_constant_s: 2}}
"""


def _by_stamp(bag: Path, topic: str) -> dict[int, object]:
    out = {}
    for message in read_messages(bag, [topic]):
        decoded = decode(message)
        out[decoded.header.stamp.sec * 10**9 + decoded.header.stamp.nanosec] = decoded
    return out


def _graph(probe, out: Path, topics: list[str], sim_time: bool):
    """Recorder, estimator and compensator; returns the processes once they listen.

    Started only once the graph has none of their subscriptions left: those of a graph
    stopped just before leave the graph's view late on a loaded host, and counted as this
    graph's they let the test go on - and stop - a recorder still constructing."""
    watched = ("/yaw/y", "/compensation", "/scales")
    assert spin_until(probe, lambda: not any(probe.count_subscribers(t) for t in watched),
                      timeout_s=60), {t: probe.count_subscribers(t) for t in watched}
    extra = {"use_sim_time": True} if sim_time else {}
    processes = [start_node("recorder", {"output": str(out), "topics": topics,
                                         "discovery_period_s": 0.1, "chunk_size": 65536, **extra}),
                 start_node("yaw_estimator", {"baseline_after_s": 0.0, "profile_period_s": 0.5,
                                              **extra}),
                 # Profiles are applied 5 s of data behind the data they serve: a loaded
                 # host that delays one by less still computes what the replay computes
                 # (a later one would be a documented "late" input, used on arrival).
                 start_node("compensation_broadcaster", {"model": "demo", "input_delay_s": 5.0,
                                                         **extra})]
    ready = spin_until(probe, lambda: probe.count_subscribers("/yaw/y") >= 1 and
                       probe.count_subscribers("/compensation") >= 1 and
                       probe.count_subscribers("/scales") >= 2, timeout_s=60)
    if not ready:
        for process in processes:
            process.stop()
    assert ready
    return processes


def test_live_recording_validates_independently_and_replays_identically(rclpy_context, tmp_path):
    import time as wall

    import rclpy
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg

    (tmp_path / "s.yaml").write_text(SCENARIO)
    probe = rclpy.create_node("probe")
    live = tmp_path / "live"
    topics = ["/scales", "/temperatures", "/yaw/y", "/compensation"]
    processes = _graph(probe, live, topics, sim_time=False)
    try:
        # Far enough ahead that the encoder has matched its subscribers before sample 0
        # is due: no catch-up burst, which best-effort transport may thin out on replay.
        start = wall.time_ns() + 5_000_000_000
        machine = {"scenario": str(tmp_path / "s.yaml"), "start_stamp_ns": start}
        temperatures = start_node("temperature_publisher", {**machine, "min_subscribers": 3})
        encoder = start_node("encoder_publisher", {**machine, "min_subscribers": 3,
                                                     "batch_period_s": 0.05})
        assert encoder.popen.wait(timeout=60) == 0
        temperatures.stop()
        spin_for(probe, 1.0)
    finally:
        for process in processes:
            assert process.stop() == 0
    info = bag_info(live)
    assert info["topics"]["/scales"]["count"] == 80  # 4 s at 20 batches/s, none lost
    assert info["topics"]["/yaw/y"]["count"] == 80
    assert info["topics"]["/compensation"]["count"] == 400  # 100 Hz of data time
    assert info["topics"]["/temperatures"]["count"] >= 10  # 4 Hz; its stop is not synchronised

    # The independent reader sees the same topics, types, counts, times, QoS, contents.
    store = get_typestore(Stores.ROS2_JAZZY)
    ours = list(read_messages(live))
    with Reader(live) as reader:
        assert {c.topic: c.msgtype for c in reader.connections} == {
            "/scales": "mt_accuracy_msgs/msg/ScaleBatch",
            "/temperatures": "mt_accuracy_msgs/msg/TemperatureArray",
            "/yaw/y": "mt_accuracy_msgs/msg/YawBatch",
            "/compensation": "mt_accuracy_msgs/msg/VolumetricCompensation"}
        qos = {c.topic: c.ext.offered_qos_profiles[0] for c in reader.connections}
        assert qos["/scales"].reliability.name.lower() == "best_effort"
        assert qos["/yaw/y"].reliability.name.lower() == "reliable"
        for connection in reader.connections:
            store.register(get_types_from_msg(connection.msgdef.data, connection.msgtype))
        theirs = [(c.topic, t, store.deserialize_cdr(raw, c.msgtype))
                  for c, t, raw in reader.messages()]
    assert [(m.topic, m.log_time_ns) for m in ours] == [(t, ts) for t, ts, _ in theirs]
    for mine, (topic, _, other) in zip(ours, theirs):
        if topic == "/scales":
            decoded = decode(mine)
            assert decoded.first_sample_index == other.first_sample_index
            np.testing.assert_array_equal(np.asarray(decoded.positions), other.positions)

    # Replay /scales and /temperatures through a fresh estimator and compensator on sim time.
    replay = tmp_path / "replay"
    processes = _graph(probe, replay, ["/yaw/y", "/compensation"], sim_time=True)
    try:
        player = start_node("bag_player", {"bag": str(live), "topics": ["/scales", "/temperatures"],
                                           "wait_for_subscribers_s": 20.0,
                                           "min_subscribers": 2})
        assert player.popen.wait(timeout=60) == 0
        spin_for(probe, 1.5)
    finally:
        for process in processes:
            assert process.stop() == 0
        probe.destroy_node()
    for topic, field in (("/yaw/y", "yaw"), ("/compensation", "error")):
        live_out, replayed = _by_stamp(live, topic), _by_stamp(replay, topic)
        assert sorted(replayed) == sorted(live_out)
        for stamp, message in live_out.items():
            if field == "yaw":
                np.testing.assert_array_equal(np.asarray(replayed[stamp].yaw),
                                              np.asarray(message.yaw))  # bit-identical
                np.testing.assert_array_equal(np.asarray(replayed[stamp].thermal_correction),
                                              np.asarray(message.thermal_correction))
            else:
                assert replayed[stamp].error == message.error  # bit-identical
                assert replayed[stamp].model_version == message.model_version
    # The replay recorder logged on the played /clock: recorded time, not today's.
    scale_times = [m.log_time_ns for m in read_messages(live, ["/scales"])]
    replay_times = [m.log_time_ns for m in read_messages(replay)]
    assert scale_times[0] - 10**8 <= min(replay_times)
    assert max(replay_times) <= scale_times[-1] + 10**9


def _chatter_bag(path: Path, n: int = 11, with_unknown_type: bool = True) -> None:
    """/chatter at 10 Hz for 1 s, plus a topic of a type nobody has installed."""
    from rclpy.serialization import serialize_message
    from std_msgs.msg import String

    with BagWriter(path) as bag:
        bag.add_topic("/chatter", "std_msgs/msg/String")
        for i in range(n):
            bag.write("/chatter", serialize_message(String(data=f"m{i}")), 10**18 + i * 10**8)
    if with_unknown_type:
        with open(path / "extra.mcap", "wb") as stream:
            writer = Writer(stream)
            writer.start(profile="ros2", library="test")
            schema = writer.register_schema("fake_msgs/msg/Nothing", "ros2msg", b"int32 a")
            channel = writer.register_channel("/fake", "cdr", schema)
            writer.add_message(channel, log_time=10**18, publish_time=10**18,
                               data=b"\0\1\0\0\0\0\0\0")
            writer.finish()


def _player(bag: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "mt_accuracy_ros.cli", "play", str(bag),
                             "--wait-for-subscribers", "20", *extra],
                            stderr=subprocess.PIPE, text=True)


@pytest.mark.parametrize("rate, offset, expected_count", [(2.0, 0.0, 11), (1.0, 0.5, 6)])
def test_player_timing_offset_remap_clock_and_unknown_type(rclpy_context, tmp_path, rate, offset,
                                                           expected_count):
    import rclpy
    from rosgraph_msgs.msg import Clock
    from std_msgs.msg import String

    from mt_accuracy_ros.nodes.player import CLOCK_QOS

    _chatter_bag(tmp_path / "bag")
    node = rclpy.create_node("listener")
    received: list[str] = []
    clocks: list[int] = []
    node.create_subscription(String, "/talk", lambda m: received.append(m.data), 10)
    node.create_subscription(Clock, "/clock", lambda m: clocks.append(
        m.clock.sec * 10**9 + m.clock.nanosec), CLOCK_QOS)
    process = _player(tmp_path / "bag", "--rate", str(rate), "--start-offset", str(offset),
                      "--remap", "/chatter:=/talk")
    try:
        assert spin_until(node, lambda: process.poll() is not None, timeout_s=60)
        spin_for(node, 0.3)
    finally:
        process.kill()
        stderr = process.communicate()[1]
        node.destroy_node()
    assert process.returncode == 0, stderr
    assert stderr.count("fake_msgs/msg/Nothing is not installed") == 1
    assert received == [f"m{i}" for i in range(11 - expected_count, 11)]
    # The rate's arithmetic is tested exactly, without wall time, in io/test_playback.py.
    assert clocks == sorted(clocks)
    assert clocks[-1] == 10**18 + 10 * 10**8  # /clock reaches the last message's bag time
    assert clocks[0] >= 10**18 + int(offset * 1e9)


def test_player_pause_resume_and_loop(rclpy_context, tmp_path):
    import rclpy
    from std_msgs.msg import String
    from std_srvs.srv import Trigger

    _chatter_bag(tmp_path / "bag", with_unknown_type=False)
    node = rclpy.create_node("listener")
    received: list[str] = []
    node.create_subscription(String, "/chatter", lambda m: received.append(m.data), 10)
    resume = node.create_client(Trigger, "/bag_player/resume")
    process = _player(tmp_path / "bag", "--start-paused", "--loop", "--rate", "4")
    try:
        assert resume.wait_for_service(timeout_sec=30)
        spin_for(node, 1.0)
        assert received == []  # paused: nothing plays
        assert call_service(node, resume, Trigger.Request()).success
        assert spin_until(node, lambda: len(received) >= 25, timeout_s=30)
    finally:
        process.send_signal(signal.SIGINT)
        process.communicate(timeout=20)
        node.destroy_node()
    assert received[:22] == [f"m{i}" for i in range(11)] * 2  # looped, in order


def test_player_refuses_non_cdr_bags_clearly(data_dir):
    result = subprocess.run([sys.executable, "-m", "mt_accuracy_ros.cli", "play",
                             str(data_dir / "rosbag2_samples" / "wrong_rmw_test")],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert "only 'cdr'" in result.stderr


@pytest.mark.parametrize("sample, topic", [("multiple_files", "/chatter"), ("talker", "/topic")])
def test_player_plays_rosbag2_written_bags(rclpy_context, data_dir, sample, topic):
    """A bag split over files without metadata.yaml, and one with zstd chunks."""
    import rclpy
    from std_msgs.msg import String

    bag = data_dir / "rosbag2_samples" / sample
    expected = [decode(m).data for m in read_messages(bag, [topic])]
    node = rclpy.create_node("listener")
    received: list[str] = []
    node.create_subscription(String, topic, lambda m: received.append(m.data), 5000)
    process = _player(bag, "--rate", "1000", "--topics", topic)
    try:
        assert spin_until(node, lambda: process.poll() is not None, timeout_s=60)
        # The player left once every message was acknowledged: the listener's queue holds
        # them all, however far behind a loaded host keeps its callbacks.
        spin_until(node, lambda: len(received) >= len(expected), timeout_s=30)
        spin_for(node, 0.2)
    finally:
        process.kill()
        process.communicate()
        node.destroy_node()
    assert process.returncode == 0
    assert received == expected


def _recoverable(path: Path) -> int:
    """Messages a reader could save from ``path`` right now (0 while there is nothing)."""
    try:
        return len(recover(path))
    except BagError:
        return 0


@pytest.mark.parametrize("stop_signal", [signal.SIGINT, signal.SIGTERM])
def test_recorder_stopped_by_signal_leaves_a_complete_bag(rclpy_context, tmp_path, stop_signal):
    import rclpy
    from std_msgs.msg import String

    node = rclpy.create_node("talker")
    publisher = node.create_publisher(String, "/chatter", 10)
    recorder = start_node("recorder", {"output": str(tmp_path / "bag"), "discovery_period_s": 0.1})
    assert spin_until(node, lambda: publisher.get_subscription_count() >= 1)
    from diagnostic_msgs.msg import DiagnosticArray

    counts: list[int] = []
    node.create_subscription(DiagnosticArray, "/diagnostics", lambda m: counts.extend(
        int(v.value) for s in m.status if s.name.endswith(": bag") for v in s.values
        if v.key == "messages"), 10)
    for i in range(50):
        publisher.publish(String(data=f"m{i}"))
        spin_for(node, 0.01)
    # Stop once the recorder says it holds all 50 (its 1 Hz status), however loaded the host.
    assert spin_until(node, lambda: counts and counts[-1] >= 50, timeout_s=60)
    recorder.popen.send_signal(stop_signal)
    assert recorder.popen.wait(timeout=20) == 0
    node.destroy_node()
    info = bag_info(tmp_path / "bag")  # summary + statistics present: a complete file
    assert info["topics"]["/chatter"]["count"] == 50
    assert (tmp_path / "bag" / "metadata.yaml").is_file()
    read = [decode(m).data for m in read_messages(tmp_path / "bag", ["/chatter"])]
    assert read == [f"m{i}" for i in range(50)], _bag_layout(tmp_path / "bag")


@pytest.mark.parametrize("held", [True, False])
def test_a_stop_signal_waits_until_the_write_in_progress_is_done(held):
    """The recorder writes inside ``signals_held()``: a SIGINT that arrives mid-write
    becomes a KeyboardInterrupt only once the write is complete (without it, Python
    raises at the next bytecode, inside the MCAP writer)."""
    code = (
        "import os, signal\n"
        "from contextlib import nullcontext\n"
        "from mt_accuracy_ros.nodes._common import signals_held\n"
        "done = []\n"
        "try:\n"
        f"    with {'signals_held()' if held else 'nullcontext()'}:\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "        for _ in range(200000):\n"
        "            pass\n"
        "        done.append('written')\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted after', done)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60, check=True).stdout
    assert out.strip() == ("interrupted after ['written']" if held else "interrupted after []")


@pytest.mark.parametrize("round_", range(3))
def test_a_stop_signal_in_the_middle_of_writing_leaves_every_counted_message_readable(
        rclpy_context, tmp_path, round_):
    """SIGINT while the recorder writes as fast as it can (small chunks, closed every
    10 ms). A loaded run once left, after a SIGINT, a bag whose summary counted 50
    messages and indexed a last chunk that neither this package's reader nor the mcap
    library's linear scan could read (36 read); a KeyboardInterrupt inside the MCAP
    writer is the way we see to do that, and the writes are now held against it. The
    race is too narrow to force here (this test passed 9 of 9 on the old code too): it
    checks that whatever the moment, every message the statistics count is read back,
    by both readers, in order."""
    import time

    from mcap.reader import NonSeekingReader
    from std_msgs.msg import String

    import rclpy

    node = rclpy.create_node("talker")
    publisher = node.create_publisher(String, "/chatter", 1000)
    recorder = start_node("recorder", {"output": str(tmp_path / "bag"), "topics": ["/chatter"],
                                       "chunk_size": 1024, "chunk_interval_s": 0.01,
                                       "discovery_period_s": 0.1})
    assert spin_until(node, lambda: publisher.get_subscription_count() >= 1)
    # The signal's moment is counted from the first chunk on disk (an event), not from the
    # match: a loaded host once let the whole 0.3 s pass before the recorder wrote anything.
    bag_file = tmp_path / "bag" / "bag_0.mcap"
    sent, writing_since, signalled_at = 0, None, None
    deadline = time.monotonic() + 60
    while signalled_at is None or time.monotonic() - signalled_at < 0.5:
        assert time.monotonic() < deadline, "the recorder wrote no chunk in 60 s"
        publisher.publish(String(data=f"m{sent}"))
        sent += 1
        if sent % 20 == 0:
            spin_for(node, 0.001)
            if writing_since is None and _recoverable(bag_file) > 0:
                writing_since = time.monotonic()
        if (signalled_at is None and writing_since is not None
                and time.monotonic() - writing_since >= 0.1 * round_):
            recorder.popen.send_signal(signal.SIGINT)
            signalled_at = time.monotonic()
    assert recorder.popen.wait(timeout=30) == 0
    node.destroy_node()
    counted = bag_info(tmp_path / "bag")["topics"]["/chatter"]["count"]
    assert counted > 0
    read = [decode(m).data for m in read_messages(tmp_path / "bag", ["/chatter"])]
    assert read == [f"m{i}" for i in range(counted)], _bag_layout(tmp_path / "bag")
    (path,) = sorted((tmp_path / "bag").glob("*.mcap"))
    with open(path, "rb") as stream:
        scanned = [m.data for _, c, m in NonSeekingReader(stream).iter_messages()
                   if c.topic == "/chatter"]
    assert len(scanned) == counted


def _bag_layout(bag: Path) -> str:
    """Chunk indexes and a linear scan of a bag's file: what to look at if a read falls short
    (seen once in CI, not reproduced in 12 loaded runs)."""
    from mcap.reader import NonSeekingReader, make_reader

    lines = []
    for path in sorted(bag.glob("*.mcap")):
        with open(path, "rb") as stream:
            summary = make_reader(stream).get_summary()
            for index in summary.chunk_indexes:
                lines.append(f"chunk @{index.chunk_start_offset} {index.message_start_time}-"
                             f"{index.message_end_time} channels "
                             f"{sorted(index.message_index_offsets)}")
            lines.append(f"channels {[(k, c.topic) for k, c in summary.channels.items()]}")
        with open(path, "rb") as stream:
            scan = [(c.topic, m.log_time) for _, c, m in NonSeekingReader(stream).iter_messages()]
            lines.append(f"linear scan: {scan}")
    return "\n".join(lines)


def test_recorder_killed_keeps_closed_chunks(rclpy_context, tmp_path):
    import rclpy
    from std_msgs.msg import String

    node = rclpy.create_node("talker")
    publisher = node.create_publisher(String, "/chatter", 100)
    recorder = start_node("recorder", {"output": str(tmp_path / "bag"), "topics": ["/chatter"],
                                       "chunk_size": 2048, "discovery_period_s": 0.1,
                                       "compression": "none"})
    assert spin_until(node, lambda: publisher.get_subscription_count() >= 1)
    for i in range(400):
        publisher.publish(String(data=f"message number {i:05d}"))
        spin_for(node, 0.002)
    # Kill once the closed chunks are on disk (a condition on the file, not a sleep).
    bag_file = tmp_path / "bag" / "bag_0.mcap"
    assert spin_until(node, lambda: _recoverable(bag_file) >= 300, timeout_s=60)
    recorder.popen.kill()
    recorder.popen.wait()
    node.destroy_node()
    salvaged = [decode(m).data for m in recover(tmp_path / "bag" / "bag_0.mcap")]
    assert len(salvaged) >= 300  # all but the open chunk (< 2 kB of ~25-byte messages)
    assert salvaged == [f"message number {i:05d}" for i in range(len(salvaged))]


def test_split_bag_reads_as_one(tmp_path):
    from rclpy.serialization import serialize_message
    from rosbags.rosbag2 import Reader
    from std_msgs.msg import String

    with BagWriter(tmp_path / "bag", chunk_size=4096, max_file_size=20_000,
                   compression=None) as bag:
        bag.add_topic("/chatter", "std_msgs/msg/String", qos_dict())
        for i in range(2000):
            bag.write("/chatter", serialize_message(String(data=f"m{i:06d}")), 10**9 + i)
    files = sorted(p.name for p in (tmp_path / "bag").glob("*.mcap"))
    assert len(files) >= 3 and files[0] == "bag_0.mcap"
    assert bag_info(tmp_path / "bag")["message_count"] == 2000
    assert [decode(m).data for m in read_messages(tmp_path / "bag")] == \
        [f"m{i:06d}" for i in range(2000)]
    with Reader(tmp_path / "bag") as reader:
        assert reader.message_count == 2000
        assert [t for _, t, _ in reader.messages()] == [10**9 + i for i in range(2000)]


def test_recorder_killed_early_loses_at_most_the_last_second(rclpy_context, tmp_path, capsys):
    """Default 1 MiB chunks: before, a kill in the first ~20 s left nothing readable."""
    import rclpy
    from std_msgs.msg import String

    from mt_accuracy_ros.cli import main

    node = rclpy.create_node("talker")
    publisher = node.create_publisher(String, "/chatter", 100)
    recorder = start_node("recorder", {"output": str(tmp_path / "bag"), "topics": ["/chatter"],
                                       "discovery_period_s": 0.1})
    assert spin_until(node, lambda: publisher.get_subscription_count() >= 1)
    for i in range(100):
        publisher.publish(String(data=f"m{i:03d}"))
        spin_for(node, 0.01)
    # With 1 MiB chunks only chunk_interval_s (1 s) closes them: all 100 reach the disk
    # while the recorder runs (polled, with room for a loaded host), then the kill.
    bag_file = tmp_path / "bag" / "bag_0.mcap"
    assert spin_until(node, lambda: _recoverable(bag_file) >= 100, timeout_s=60)
    recorder.popen.kill()
    recorder.popen.wait()
    node.destroy_node()
    salvaged = [decode(m).data for m in recover(tmp_path / "bag" / "bag_0.mcap")]
    assert salvaged == [f"m{i:03d}" for i in range(100)]
    # info says the bag was cut short (a killed recorder) and how to recover it - one line,
    # exit 2.
    assert main(["info", str(tmp_path / "bag")]) == 2
    error = capsys.readouterr().err.strip()
    assert "is a truncated MCAP file" in error and "mt-accuracy recover" in error
    assert len(error.splitlines()) == 1
    assert main(["recover", str(tmp_path / "bag"), str(tmp_path / "saved")]) == 0
    info = bag_info(tmp_path / "saved")
    assert info["topics"]["/chatter"]["count"] == 100
    assert [decode(m).data for m in read_messages(tmp_path / "saved")] == salvaged
