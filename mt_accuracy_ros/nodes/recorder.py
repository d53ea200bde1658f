"""Recorder: write topics of the graph to a rosbag2-compatible MCAP bag.

Subscribes with ``raw=True`` (serialized CDR, never decoded) to the listed
topics, or to every topic of the graph whose type is installed, discovered
again every ``discovery_period_s`` so late publishers are recorded too. Each
message is written with log time = receive time on the node's clock (so
``use_sim_time`` records sim time) and publish time = the publisher's source
timestamp. The subscription QoS follows the publishers (reliable only if all
are, transient local only if all are - so latched tables are caught).

SIGINT/SIGTERM close the bag completely (summary, statistics,
``metadata.yaml``); after a SIGKILL every closed chunk is still readable and
:func:`mt_accuracy_ros.io.bag_reader.recover` salvages it. Status on
``/diagnostics`` once a second.
"""
from __future__ import annotations

import sys

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.clock import Clock, ClockType
from rclpy.node import Node

from ..core.errors import BagError
from ..io.bag_writer import BagWriter, default_bag_name
from ._common import (float_descriptor, int_descriptor, plain_descriptor, run_node,
                      signals_held)
from ._raw_topics import RawTopicFollower


class Recorder(Node):
    """Record raw messages of selected (or all) topics into one bag directory."""

    def __init__(self, **kwargs) -> None:
        super().__init__("recorder", **kwargs)
        self.declare_parameter("output", "", plain_descriptor(
            "Bag directory to create (empty: rosbag2_<date>_<time>)", read_only=True))
        self.declare_parameter("topics", [""], plain_descriptor(
            "Topics to record (empty: every topic whose type is installed)", read_only=True))
        self.declare_parameter("exclude_topics", [""], plain_descriptor(
            "Topics never to record (e.g. a lockstep run's '/lockstep' pacing reports)",
            read_only=True))
        self.declare_parameter("compression", "zstd", plain_descriptor(
            "Chunk compression: 'zstd' or 'none'", read_only=True))
        self.declare_parameter("chunk_size", 1024 * 1024, int_descriptor(
            "Bytes per MCAP chunk [B]", 1024, 1 << 30, read_only=True))
        self.declare_parameter("chunk_interval_s", 1.0, float_descriptor(
            "Close a chunk after this long even if not full: a kill loses at most this much "
            "(0: by size only) [s]", 0.0, 3600.0, read_only=True))
        self.declare_parameter("max_bag_size", 0, int_descriptor(
            "Split to a new file after this many bytes (0: never) [B]", 0, 1 << 40,
            read_only=True))
        self.declare_parameter("max_bag_duration", 0.0, float_descriptor(
            "Split to a new file after this much time (0: never) [s]", 0.0, 1e7,
            read_only=True))
        self.declare_parameter("discovery_period_s", 0.5, float_descriptor(
            "How often to look for new topics [s]", 0.05, 60.0))
        self.add_on_set_parameters_callback(self._validate)

        output = str(self.get_parameter("output").value) or default_bag_name()
        compression = str(self.get_parameter("compression").value)
        if compression not in ("zstd", "none"):
            raise BagError(f"compression must be 'zstd' or 'none', got {compression!r}")
        self.bag = BagWriter(output, compression=None if compression == "none" else "zstd",
                             chunk_size=int(self.get_parameter("chunk_size").value),
                             max_file_size=int(self.get_parameter("max_bag_size").value),
                             max_file_duration_s=float(
                                 self.get_parameter("max_bag_duration").value),
                             chunk_interval_s=float(
                                 self.get_parameter("chunk_interval_s").value))
        self._pending: list[tuple[str, bytes, int]] = []
        self._diagnostics = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self._follower = RawTopicFollower(
            self, {t for t in self.get_parameter("topics").value if t},
            float(self.get_parameter("discovery_period_s").value), self._new_topic, "recording")
        # Status and chunk closing run on wall time too (also under use_sim_time).
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.create_timer(1.0, self._report, clock=steady)
        interval = float(self.get_parameter("chunk_interval_s").value)
        if interval > 0:
            self.create_timer(min(interval, 1.0) / 4, self._flush_due, clock=steady)
        self.get_logger().info(f"recording to {self.bag.path}")

    def _validate(self, parameters):
        return self._follower.validate(parameters)

    def _new_topic(self, name: str, type_name: str, offered: list[dict]):
        if name in {t for t in self.get_parameter("exclude_topics").value if t}:
            return None
        self.bag.add_topic(name, type_name, offered)
        return self._writer_for(name)

    def _writer_for(self, topic: str):
        clock = self.get_clock()

        def write(data: bytes, info) -> None:
            # info: rmw message info; source_timestamp is the publisher's stamp [ns].
            received = clock.now().nanoseconds
            source = int(info.get("source_timestamp", received))
            if received == 0:
                # use_sim_time and no /clock heard yet: hold the message rather
                # than log it at time zero; it gets the first valid time.
                self._pending.append((topic, data, source))
                return
            # A stop signal waits until the message is in the bag (signals_held).
            with signals_held():
                while self._pending:
                    held_topic, held_data, held_source = self._pending.pop(0)
                    self.bag.write(held_topic, held_data, received, held_source)
                self.bag.write(topic, data, received, source)
        return write

    def _flush_due(self) -> None:
        with signals_held():
            self.bag.flush_due()

    def _report(self) -> None:
        status = DiagnosticStatus(level=DiagnosticStatus.OK, name=f"{self.get_name()}: bag",
                                  message=f"recording {len(self._follower.subscriptions)} topics",
                                  hardware_id=str(self.bag.path))
        status.values = [KeyValue(key="messages", value=str(self.bag.message_count)),
                         KeyValue(key="files", value=",".join(self.bag.file_names))]
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics.publish(array)

    def close(self) -> None:
        with signals_held():   # a second Ctrl-C must not cut the summary short
            # Messages still waiting for a first /clock are kept, at their source time.
            for topic, data, source in self._pending:
                self.bag.write(topic, data, source, source)
            self._pending.clear()
            self.bag.close()


def main(args: list[str] | None = None) -> int:
    """Entry point; whatever stops the spin, the bag is finished (summary, metadata)."""
    return run_node(Recorder, args, on_exit=lambda node: node.close())


if __name__ == "__main__":
    sys.exit(main())
