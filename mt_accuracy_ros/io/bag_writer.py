"""Write rosbag2-compatible MCAP bags from serialized (CDR) messages.

Layout as rosbag2's MCAP storage writes it, so ``ros2 bag info/play``,
Foxglove and independent readers open the result:

* a bag directory ``<name>/`` with ``<name>_0.mcap`` and ``metadata.yaml``
  (bag version 9, ``ros_distro: jazzy``);
* MCAP profile ``ros2``; one schema per type (encoding ``ros2msg``, see
  :mod:`.msg_definitions`); channels with message encoding ``cdr`` and
  metadata ``offered_qos_profiles`` (a YAML list) and ``topic_type_hash``;
* ``log_time`` = receive time, ``publish_time`` = source time [ns];
* a metadata record ``rosbag2`` with key ``serialized_metadata``;
* statistics and summary sections (rosbag2's reader needs the Statistics record).

Optionally split over ``<name>_0.mcap``, ``<name>_1.mcap`` ... by size or
duration (each file complete on its own, every topic declared in each).

Chunks (optionally zstd-compressed) are flushed to disk as they close, so a
process killed mid-write leaves every closed chunk readable
(see :func:`mt_accuracy_ros.io.bag_reader.recover`). A chunk closes when it
reaches ``chunk_size`` bytes *or* has been open ``chunk_interval_s`` seconds
(wall time; :meth:`BagWriter.flush_due` lets a timer close it even when no
message arrives), so a kill loses at most about one second of messages. The
file header reaches the disk when the bag opens, and every schema and channel
the moment its topic is declared (written between chunks as well as inside
them), so a bag killed before any chunk closed still lists its topics.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import yaml
from mcap.writer import CompressionType, Writer

from ..core.errors import BagError
from .msg_definitions import schema_text, type_hash

#: rosbag2's "unset" duration for deadline / lifespan / liveliness lease.
INFINITE_DURATION = {"sec": 2147483647, "nsec": 4294967295}


def default_bag_name() -> str:
    """The bag directory a recording without a name gets: ``rosbag2_<date>-<time>``, as
    ``ros2 bag record`` names it, in the working directory."""
    from datetime import datetime

    return datetime.now().strftime("rosbag2_%Y_%m_%d-%H_%M_%S")


def qos_dict(*, reliability: str = "reliable", durability: str = "volatile",
             history: str = "keep_last", depth: int = 10) -> dict:
    """One offered QoS profile in the form rosbag2 (bag version 9) writes."""
    return {"history": history, "depth": int(depth), "reliability": reliability,
            "durability": durability, "deadline": dict(INFINITE_DURATION),
            "lifespan": dict(INFINITE_DURATION), "liveliness": "automatic",
            "liveliness_lease_duration": dict(INFINITE_DURATION),
            "avoid_ros_namespace_conventions": False}


def qos_from_rclpy(profile) -> dict:
    """:func:`qos_dict` of an ``rclpy.qos.QoSProfile``."""
    names = {"RELIABLE": "reliable", "BEST_EFFORT": "best_effort", "VOLATILE": "volatile",
             "TRANSIENT_LOCAL": "transient_local", "KEEP_LAST": "keep_last",
             "KEEP_ALL": "keep_all", "SYSTEM_DEFAULT": "system_default"}
    return qos_dict(reliability=names.get(profile.reliability.name, "reliable"),
                    durability=names.get(profile.durability.name, "volatile"),
                    history=names.get(profile.history.name, "keep_last"), depth=profile.depth)


@dataclass
class _Topic:
    name: str
    type: str
    qos: list[dict]
    type_hash: str
    count: int = 0


@dataclass
class _File:
    """Bookkeeping of one ``<name>_<i>.mcap`` of a (possibly split) bag."""

    name: str
    first_ns: int | None = None
    last_ns: int = 0
    count: int = 0

    def info(self) -> dict:
        start = self.first_ns or 0
        return {"path": self.name, "starting_time": {"nanoseconds_since_epoch": start},
                "duration": {"nanoseconds": max(0, self.last_ns - start)},
                "message_count": self.count}


@dataclass
class BagWriter:
    """Write one rosbag2-compatible bag directory.

    Parameters
    ----------
    path : str or Path
        Bag directory to create; must not exist yet.
    compression : ``"zstd"`` or ``None``
        Chunk compression.
    chunk_size : int
        Bytes per chunk before it is closed and flushed [B].
    max_file_size : int
        Split to a new ``<name>_<i>.mcap`` once the current file holds this many
        bytes (0: never), like ``ros2 bag record --max-bag-size``.
    max_file_duration_s : float
        Split once a file spans this much log time [s] (0: never), like
        ``--max-bag-duration``.
    chunk_interval_s : float
        Close a chunk that has been open this long [s] (0: by size only).
    """

    path: Path
    compression: str | None = "zstd"
    chunk_size: int = 1024 * 1024
    max_file_size: int = 0
    max_file_duration_s: float = 0.0
    chunk_interval_s: float = 1.0
    _topics: dict[str, _Topic] = field(default_factory=dict, init=False)
    _files: list[_File] = field(default_factory=list, init=False)
    _closed: bool = field(default=False, init=False)

    def __post_init__(self) -> None:
        self.path = Path(self.path)
        if self.path.exists():
            raise BagError(f"{self.path} already exists; refusing to overwrite a bag")
        if self.compression not in (None, "zstd"):
            raise BagError(f"compression must be 'zstd' or None, got {self.compression!r}")
        if self.max_file_size < 0 or self.max_file_duration_s < 0:
            raise BagError("max_file_size and max_file_duration_s must be >= 0 (0 = no split)")
        if not self.chunk_interval_s >= 0:
            raise BagError("chunk_interval_s must be >= 0 (0 = close chunks by size only)")
        self.path.mkdir(parents=True)
        self._open_file()

    # -- files -------------------------------------------------------------------------
    def _open_file(self) -> None:
        current = _File(f"{self.path.name}_{len(self._files)}.mcap")
        self._files.append(current)
        self._stream = open(self.path / current.name, "wb")
        self._writer = Writer(
            self._stream, chunk_size=self.chunk_size,
            compression=CompressionType.ZSTD if self.compression else CompressionType.NONE)
        self._writer.start(profile="ros2", library="mt_accuracy_ros")
        self._stream.flush()  # the header is on disk from the start
        self._flushed_bytes = self._stream.tell()
        self._chunk_opened = time.monotonic()
        self._unflushed = 0
        self._schema_ids: dict[str, int] = {}
        self._channel_ids: dict[str, int] = {}
        # rosbag2 repeats every known topic in each split file.
        for topic in self._topics.values():
            self._register(topic)

    def _finish_file(self) -> None:
        info = yaml.safe_dump(self.bag_info(), sort_keys=False)
        self._writer.add_metadata("rosbag2", {"serialized_metadata": info})
        self._writer.finish()
        self._stream.close()

    def _register(self, topic: _Topic) -> None:
        from mcap.data_stream import RecordBuilder
        from mcap.records import Channel, Schema

        # The MCAP writer keeps schema and channel records inside the open chunk, so a
        # killed process would leave none of them. Each is also written to the file at
        # once, between chunks (the MCAP spec allows identical repeats): a bag killed
        # before its first chunk closed still says what it was recording.
        records = RecordBuilder()
        if topic.type not in self._schema_ids:
            data = schema_text(topic.type).encode()
            self._schema_ids[topic.type] = self._writer.register_schema(
                name=topic.type, encoding="ros2msg", data=data)
            Schema(id=self._schema_ids[topic.type], name=topic.type, encoding="ros2msg",
                   data=data).write(records)
        metadata = {"offered_qos_profiles": yaml.safe_dump(topic.qos, sort_keys=False),
                    "topic_type_hash": topic.type_hash}
        self._channel_ids[topic.name] = self._writer.register_channel(
            topic=topic.name, message_encoding="cdr", schema_id=self._schema_ids[topic.type],
            metadata=metadata)
        Channel(id=self._channel_ids[topic.name], topic=topic.name, message_encoding="cdr",
                schema_id=self._schema_ids[topic.type], metadata=metadata).write(records)
        self._stream.write(records.end())
        self._stream.flush()
        self._flushed_bytes = self._stream.tell()

    def _split_due(self, log_time_ns: int) -> bool:
        current = self._files[-1]
        if current.count == 0:
            return False
        if self.max_file_size and self._stream.tell() >= self.max_file_size:
            return True
        return bool(self.max_file_duration_s) and current.first_ns is not None and \
            log_time_ns - current.first_ns >= self.max_file_duration_s * 1e9

    # -- public API ----------------------------------------------------------------------
    def add_topic(self, name: str, type_name: str, qos: list[dict] | dict | None = None) -> None:
        """Declare a topic; ``type_name`` as ``pkg/msg/Type``."""
        if self._closed:
            raise BagError("bag already closed")
        if name in self._topics:
            if self._topics[name].type != type_name:
                raise BagError(f"topic {name} already recorded as {self._topics[name].type}")
            return
        profiles = [qos] if isinstance(qos, dict) else list(qos or [qos_dict()])
        topic = _Topic(name, type_name, profiles, type_hash(type_name))
        self._register(topic)
        self._topics[name] = topic

    def write(self, topic: str, data: bytes, log_time_ns: int,
              publish_time_ns: int | None = None) -> None:
        """Write one serialized message (times in integer nanoseconds)."""
        if self._closed:
            raise BagError("bag already closed")
        entry = self._topics.get(topic)
        if entry is None:
            raise BagError(f"topic {topic} not declared; call add_topic first")
        log_time_ns = int(log_time_ns)
        if self._split_due(log_time_ns):
            self._finish_file()
            self._open_file()
        publish = log_time_ns if publish_time_ns is None else int(publish_time_ns)
        self._writer.add_message(channel_id=self._channel_ids[topic], log_time=log_time_ns,
                                 publish_time=publish, data=bytes(data), sequence=entry.count)
        entry.count += 1
        current = self._files[-1]
        current.count += 1
        current.first_ns = log_time_ns if current.first_ns is None else min(current.first_ns,
                                                                             log_time_ns)
        current.last_ns = max(current.last_ns, log_time_ns)
        self._unflushed += 1
        # The MCAP writer emits bytes only when a chunk closes; push each closed
        # chunk to the OS so that a killed process keeps it.
        position = self._stream.tell()
        if position != self._flushed_bytes:
            self._flushed_bytes = position
            self._stream.flush()
            self._chunk_opened = time.monotonic()
            self._unflushed = 0
        else:
            self.flush_due()

    def flush_due(self) -> bool:
        """Close the open chunk if it has been open ``chunk_interval_s``; True if it did."""
        if self._closed or not self.chunk_interval_s or not self._unflushed or \
                time.monotonic() - self._chunk_opened < self.chunk_interval_s:
            return False
        self._writer.flush()  # closes the chunk and flushes the stream
        self._flushed_bytes = self._stream.tell()
        self._chunk_opened = time.monotonic()
        self._unflushed = 0
        return True

    @property
    def message_count(self) -> int:
        return sum(t.count for t in self._topics.values())

    @property
    def file_names(self) -> list[str]:
        return [f.name for f in self._files]

    def bag_info(self) -> dict:
        """The ``rosbag2_bagfile_information`` mapping (bag version 9)."""
        starts = [f.first_ns for f in self._files if f.first_ns is not None]
        start = min(starts) if starts else 0
        duration = max(0, max(f.last_ns for f in self._files) - start) if starts else 0
        topics = [{"topic_metadata": {"name": t.name, "type": t.type,
                                      "serialization_format": "cdr",
                                      "offered_qos_profiles": t.qos,
                                      "type_description_hash": t.type_hash},
                   "message_count": t.count} for t in self._topics.values()]
        return {"rosbag2_bagfile_information": {
            "version": 9, "storage_identifier": "mcap",
            "duration": {"nanoseconds": duration},
            "starting_time": {"nanoseconds_since_epoch": start},
            "message_count": self.message_count,
            "topics_with_message_count": topics,
            "compression_format": "", "compression_mode": "",
            "relative_file_paths": self.file_names,
            "files": [f.info() for f in self._files],
            "custom_data": {}, "ros_distro": "jazzy"}}

    def close(self) -> None:
        """Finish the MCAP (metadata, statistics, summary) and write ``metadata.yaml``."""
        if self._closed:
            return
        self._closed = True
        self._finish_file()
        (self.path / "metadata.yaml").write_text(yaml.safe_dump(self.bag_info(), sort_keys=False))

    def __enter__(self) -> "BagWriter":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
