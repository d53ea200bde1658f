"""rosbag2-compatible MCAP writing and reading, checked with an independent reader (rosbags)."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import yaml

from mt_accuracy_ros.core.errors import BagError
from mt_accuracy_ros.io.bag_reader import bag_info, decode, read_messages, recover
from mt_accuracy_ros.io.bag_writer import BagWriter, qos_dict
from mt_accuracy_ros.io.msg_definitions import SEPARATOR, schema_text


def _scale_batch(i: int):
    from mt_accuracy_msgs.msg import ScaleBatch
    from mt_accuracy_ros.io.fields import nanoseconds_to_stamp, pack_float64

    m = ScaleBatch()
    m.header.stamp = nanoseconds_to_stamp(1_700_000_000_000_000_000 + i * 50_000_000)
    m.header.frame_id = "machine"
    m.first_sample_index = i * 50
    m.sample_period = 1e-3
    m.channel_names = ["x1", "x2"]
    m.positions = pack_float64(np.arange(100) * 1e-6 + i)
    m.command_axes = ["x"]
    m.command_positions = pack_float64(np.arange(50) * 1e-6)
    return m


def _write_bag(path: Path, n: int = 30, compression="zstd") -> list:
    from rclpy.serialization import serialize_message
    from std_msgs.msg import String

    written = []
    with BagWriter(path, compression=compression, chunk_size=4096) as bag:
        bag.add_topic("/mt1/scales", "mt_accuracy_msgs/msg/ScaleBatch",
                      qos_dict(reliability="best_effort", depth=5))
        bag.add_topic("/note", "std_msgs/msg/String")
        for i in range(n):
            msg = _scale_batch(i)
            t = 1_700_000_000_000_000_000 + i * 50_000_000
            bag.write("/mt1/scales", serialize_message(msg), t + 1000, t)
            written.append(("/mt1/scales", t + 1000, t, msg))
            if i % 10 == 0:
                note = String(data=f"note {i}")
                bag.write("/note", serialize_message(note), t + 2000, t + 2000)
                written.append(("/note", t + 2000, t + 2000, note))
    return written


def test_schema_text_follows_rosbag2_layout():
    text = schema_text("mt_accuracy_msgs/msg/ScaleBatch")
    assert text.startswith("# A batch of synchronous")
    blocks = text.split(SEPARATOR + "\n")
    assert [b.splitlines()[0] for b in blocks[1:]] == ["MSG: std_msgs/Header",
                                                      "MSG: builtin_interfaces/Time"]


def test_independent_reader_sees_the_same_bag(tmp_path):
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg

    written = _write_bag(tmp_path / "bag")
    assert sorted(os.listdir(tmp_path / "bag")) == ["bag_0.mcap", "metadata.yaml"]
    store = get_typestore(Stores.ROS2_JAZZY)
    with Reader(tmp_path / "bag") as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        assert types == {"/mt1/scales": "mt_accuracy_msgs/msg/ScaleBatch",
                         "/note": "std_msgs/msg/String"}
        for connection in reader.connections:
            if connection.topic == "/mt1/scales":
                store.register(get_types_from_msg(connection.msgdef.data, connection.msgtype))
                qos = connection.ext.offered_qos_profiles
                assert qos and qos[0].reliability.name.lower() == "best_effort"
                assert qos[0].depth == 5
        got = [(c.topic, t, store.deserialize_cdr(raw, c.msgtype))
               for c, t, raw in reader.messages()]
        assert reader.message_count == len(written)
    scales = [w for w in written if w[0] == "/mt1/scales"]
    ours = [g for g in got if g[0] == "/mt1/scales"]
    assert [g[1] for g in ours] == [w[1] for w in scales]  # log times
    for (_, _, _, sent), (_, _, decoded) in zip(scales, ours):
        np.testing.assert_array_equal(decoded.positions, np.asarray(sent.positions))
        assert decoded.header.stamp.sec == sent.header.stamp.sec
        assert list(decoded.channel_names) == ["x1", "x2"]
    notes = [g[2].data for g in got if g[0] == "/note"]
    assert notes == ["note 0", "note 10", "note 20"]


def test_own_reader_decodes_and_reports_info(tmp_path):
    written = _write_bag(tmp_path / "bag", compression=None)
    messages = list(read_messages(tmp_path / "bag"))
    assert [m.log_time_ns for m in messages] == sorted(w[1] for w in written)
    assert decode(messages[0]) == written[0][3]
    info = bag_info(tmp_path / "bag")
    assert info["message_count"] == len(written)
    assert info["topics"]["/mt1/scales"] == {"type": "mt_accuracy_msgs/msg/ScaleBatch",
                                            "count": 30, "encoding": "cdr"}
    meta = yaml.safe_load((tmp_path / "bag" / "metadata.yaml").read_text())
    assert meta["rosbag2_bagfile_information"]["ros_distro"] == "jazzy"
    assert meta["rosbag2_bagfile_information"]["version"] == 9


def test_rosbag2_written_samples_are_read(data_dir):
    talker = list(read_messages(data_dir / "rosbag2_samples" / "talker"))
    assert sum(m.topic == "/topic" for m in talker) == 10
    assert decode(next(m for m in talker if m.topic == "/topic")).data.startswith("Hello")
    split = list(read_messages(data_dir / "rosbag2_samples" / "multiple_files"))
    assert len(split) > 0 and all(m.topic == "/chatter" for m in split)
    assert [m.log_time_ns for m in split] == sorted(m.log_time_ns for m in split)


def test_non_cdr_bag_is_refused_clearly(data_dir):
    with pytest.raises(BagError, match="only 'cdr'"):
        list(read_messages(data_dir / "rosbag2_samples" / "wrong_rmw_test"))


def test_foreign_and_missing_files_raise_bag_error(tmp_path):
    (tmp_path / "junk.mcap").write_bytes(b"this is not mcap at all" * 10)
    with pytest.raises(BagError):
        list(read_messages(tmp_path / "junk.mcap"))
    with pytest.raises(BagError, match="no such bag"):
        list(read_messages(tmp_path / "missing"))
    with pytest.raises(BagError, match="already exists"):
        BagWriter(tmp_path)


def test_killed_writer_leaves_closed_chunks_recoverable(tmp_path):
    script = textwrap.dedent(f"""
        import sys, time
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from test_bag_files import _scale_batch
        from rclpy.serialization import serialize_message
        from mt_accuracy_ros.io.bag_writer import BagWriter
        bag = BagWriter({str(tmp_path / 'killed')!r}, chunk_size=2048)
        bag.add_topic('/scales', 'mt_accuracy_msgs/msg/ScaleBatch')
        i = 0
        while True:
            bag.write('/scales', serialize_message(_scale_batch(i)), 1000 + i, 1000 + i)
            i += 1
            if i == 200:
                print('ready', flush=True)
            time.sleep(0.0005)
        """)
    process = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True,
                               cwd=Path(__file__).resolve().parents[2])
    assert process.stdout.readline().strip() == "ready"
    process.kill()
    process.wait()
    mcap_file = tmp_path / "killed" / "killed_0.mcap"
    with pytest.raises(BagError):
        bag_info(tmp_path / "killed")
    salvaged = recover(mcap_file)
    assert len(salvaged) >= 150  # every closed chunk; the open one is lost
    assert [m.log_time_ns for m in salvaged] == list(range(1000, 1000 + len(salvaged)))
    assert decode(salvaged[-1]).first_sample_index == (len(salvaged) - 1) * 50


def test_info_command_prints_like_ros2_bag_info(data_dir, capsys):
    from mt_accuracy_ros.cli import main

    assert main(["info", str(data_dir / "rosbag2_samples" / "talker")]) == 0
    out = capsys.readouterr().out
    assert "Messages:       20" in out
    assert ("Topic: /topic | Type: std_msgs/msg/String | Count: 10 | "
            "Serialization Format: cdr") in out
    assert main(["info", str(data_dir / "no_such_bag")]) == 2


def test_schema_skips_constants_and_resolves_same_package_types():
    text = schema_text("diagnostic_msgs/msg/DiagnosticArray")
    headers = [line for line in text.splitlines() if line.startswith("MSG: ")]
    # DiagnosticStatus declares byte constants (OK=0 ...): none may become a dependency.
    assert headers == ["MSG: std_msgs/Header", "MSG: builtin_interfaces/Time",
                       "MSG: diagnostic_msgs/DiagnosticStatus", "MSG: diagnostic_msgs/KeyValue"]


def test_a_bag_recorded_with_an_older_type_version_still_decodes(tmp_path):
    """The installed type changed since recording (a field added): decode with the
    definition the bag carries, not with the installed one."""
    from mcap.writer import Writer
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg

    old = "std_msgs/Header header\nstring instrument\nfloat64[] command_positions\n"
    schema = old + "=" * 80 \
        + "\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n" \
        + "=" * 80 + "\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(get_types_from_msg(old, "mt_accuracy_msgs/msg/ReferenceMeasurement"))
    Message = store.types["mt_accuracy_msgs/msg/ReferenceMeasurement"]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    raw = store.serialize_cdr(Message(Header(Time(5, 6), "m"), "laser", np.array([0.1, -0.2])),
                              "mt_accuracy_msgs/msg/ReferenceMeasurement")
    with open(tmp_path / "old.mcap", "wb") as stream:
        writer = Writer(stream)
        writer.start(profile="ros2", library="test")
        schema_id = writer.register_schema("mt_accuracy_msgs/msg/ReferenceMeasurement", "ros2msg",
                                           schema.encode())
        channel = writer.register_channel("/reference/tcp_error", "cdr", schema_id,
                                          {"topic_type_hash": "RIHS01_" + "0" * 64})
        writer.add_message(channel, log_time=1, publish_time=1, data=bytes(raw))
        writer.finish()
    message = next(read_messages(tmp_path / "old.mcap"))
    decoded = decode(message)
    assert decoded.instrument == "laser"
    assert list(decoded.command_positions) == [0.1, -0.2]
    assert decoded.header.stamp.sec == 5
    assert not hasattr(decoded, "command_directions")  # the field the old version lacked


def test_header_schemas_and_channels_are_on_disk_before_the_first_chunk(tmp_path):
    """A writer killed before its first chunk closed: the topics are still readable."""
    from mt_accuracy_ros.io.bag_reader import recover, topics
    from mt_accuracy_ros.io.bag_writer import BagWriter

    writer = BagWriter(tmp_path / "bag")  # never closed: as if killed
    writer.add_topic("/scales", "mt_accuracy_msgs/msg/ScaleBatch")
    writer.add_topic("/chatter", "std_msgs/msg/String")
    found = topics(tmp_path / "bag" / "bag_0.mcap")
    assert {n: i.type for n, i in found.items()} == {
        "/scales": "mt_accuracy_msgs/msg/ScaleBatch", "/chatter": "std_msgs/msg/String"}
    assert recover(tmp_path / "bag" / "bag_0.mcap") == []
    writer.close()
    # Closed normally, the repeated records do not disturb an independent reader.
    from rosbags.highlevel import AnyReader

    with AnyReader([tmp_path / "bag"]) as reader:
        assert sorted(c.topic for c in reader.connections) == ["/chatter", "/scales"]


def _foreign_mcap(path: Path, profile: str = "", encoding: str = "json") -> Path:
    from mcap.writer import Writer

    with open(path, "wb") as stream:
        writer = Writer(stream)
        writer.start(profile=profile, library="another tool")
        schema = writer.register_schema(name="Pose", encoding="jsonschema", data=b"{}")
        channel = writer.register_channel(topic="/pose", message_encoding=encoding,
                                          schema_id=schema)
        writer.add_message(channel_id=channel, log_time=1, publish_time=1, data=b"{}")
        writer.finish()
    return path


@pytest.mark.parametrize("content, words", [
    (b"", "is empty (0 bytes), not an MCAP bag"),
    (b"\x89PNG\r\n\x1a\n" + bytes(64), "is a PNG image, not an MCAP bag or a CSV"),
    (b"SQLite format 3\x00" + bytes(64), "is a rosbag2 SQLite (.db3) bag (this package "
     "reads MCAP bags: `ros2 bag convert` it to MCAP)"),
    (bytes(range(256)) * 4, "is not an MCAP file (no MCAP magic) nor text"),
    (b"time_s,t1_C\n0,20\n", "is a text file (a CSV?), not an MCAP bag; `mt-accuracy check"),
])
def test_a_file_that_is_no_mcap_is_named_for_what_it_is(tmp_path, content, words):
    path = tmp_path / "data.mcap"
    path.write_bytes(content)
    for read in (lambda: list(read_messages(path)), lambda: bag_info(path), lambda: recover(path)):
        with pytest.raises(BagError) as error:
            read()
        assert words in str(error.value)


def test_a_truncated_mcap_is_refused_by_readers_and_scanned_by_recover_and_topics(data_dir,
                                                                                   tmp_path):
    from mt_accuracy_ros.io.bag_reader import topics

    whole = (data_dir / "rosbag2_samples" / "talker" / "talker.mcap").read_bytes()
    path = tmp_path / "killed.mcap"
    path.write_bytes(whole[:len(whole) * 2 // 3])
    for read in (lambda: list(read_messages(path)), lambda: bag_info(path)):
        with pytest.raises(BagError, match="is a truncated MCAP file .* `mt-accuracy recover"):
            read()
    assert "/topic" in topics(path)           # a killed recorder's topics: still listed
    assert len(recover(path)) > 0


def test_an_mcap_of_another_kind_is_refused_naming_its_profile_and_encoding(tmp_path):
    path = _foreign_mcap(tmp_path / "foreign.mcap")
    with pytest.raises(BagError, match=r"is an MCAP file of another kind \(profile '', json "
                                       r"messages\), not a ROS 2 bag"):
        list(read_messages(path))


def test_a_bag_directory_of_sqlite_files_says_so(tmp_path):
    (tmp_path / "bag").mkdir()
    (tmp_path / "bag" / "bag_0.db3").write_bytes(b"SQLite format 3\x00")
    with pytest.raises(BagError, match="bag_0.db3 is a rosbag2 SQLite bag: `ros2 bag convert`"):
        bag_info(tmp_path / "bag")


def test_rosbag2_samples_pass_identification(data_dir):
    from mt_accuracy_ros.io.bag_reader import identify_bag_file, mcap_files

    for sample in ("talker", "multiple_files", "wrong_rmw_test"):
        for path in mcap_files(data_dir / "rosbag2_samples" / sample):
            identify_bag_file(path)     # complete, profile ros2 (wrong_rmw: refused later)


def test_a_bag_damaged_before_its_first_topic_lists_none_and_says_so(data_dir, tmp_path):
    from mt_accuracy_ros.io.bag_reader import topics

    data = bytearray((data_dir / "rosbag2_samples" / "talker" / "talker.mcap").read_bytes())
    data[3000:3400] = b"\xab" * 400         # inside the first chunk; magic and footer intact
    path = tmp_path / "damaged.mcap"
    path.write_bytes(bytes(data))
    with pytest.raises(BagError, match="damaged MCAP file, no topic readable before the damage"):
        topics(path)
