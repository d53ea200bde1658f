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

Chunks (optionally zstd-compressed) are flushed to disk as they close, so a
process killed mid-write leaves every closed chunk readable
(see :func:`mt_accuracy_ros.io.bag_reader.recover`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import yaml
from mcap.writer import CompressionType, Writer

from ..core.errors import BagError
from .msg_definitions import schema_text, type_hash

#: rosbag2's "unset" duration for deadline / lifespan / liveliness lease.
INFINITE_DURATION = {"sec": 2147483647, "nsec": 4294967295}


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
    channel_id: int
    type_hash: str
    count: int = 0


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
        Bytes per chunk before it is closed and flushed.
    """

    path: Path
    compression: str | None = "zstd"
    chunk_size: int = 1024 * 1024
    _topics: dict[str, _Topic] = field(default_factory=dict, init=False)
    _schemas: dict[str, int] = field(default_factory=dict, init=False)
    _first_ns: int | None = field(default=None, init=False)
    _last_ns: int = field(default=0, init=False)
    _closed: bool = field(default=False, init=False)

    def __post_init__(self) -> None:
        self.path = Path(self.path)
        if self.path.exists():
            raise BagError(f"{self.path} already exists; refusing to overwrite a bag")
        if self.compression not in (None, "zstd"):
            raise BagError(f"compression must be 'zstd' or None, got {self.compression!r}")
        self.path.mkdir(parents=True)
        self.file_name = f"{self.path.name}_0.mcap"
        self._stream = open(self.path / self.file_name, "wb")
        self._writer = Writer(
            self._stream, chunk_size=self.chunk_size,
            compression=CompressionType.ZSTD if self.compression else CompressionType.NONE)
        self._writer.start(profile="ros2", library="mt_accuracy_ros")
        self._flushed_bytes = 0

    def add_topic(self, name: str, type_name: str, qos: list[dict] | dict | None = None) -> None:
        """Declare a topic; ``type_name`` as ``pkg/msg/Type``."""
        if name in self._topics:
            if self._topics[name].type != type_name:
                raise BagError(f"topic {name} already recorded as {self._topics[name].type}")
            return
        if type_name not in self._schemas:
            self._schemas[type_name] = self._writer.register_schema(
                name=type_name, encoding="ros2msg", data=schema_text(type_name).encode())
        profiles = [qos] if isinstance(qos, dict) else list(qos or [qos_dict()])
        hash_string = type_hash(type_name)
        channel = self._writer.register_channel(
            topic=name, message_encoding="cdr", schema_id=self._schemas[type_name],
            metadata={"offered_qos_profiles": yaml.safe_dump(profiles, sort_keys=False),
                      "topic_type_hash": hash_string})
        self._topics[name] = _Topic(name, type_name, profiles, channel, hash_string)

    def write(self, topic: str, data: bytes, log_time_ns: int,
              publish_time_ns: int | None = None) -> None:
        """Write one serialized message."""
        if self._closed:
            raise BagError("bag already closed")
        entry = self._topics.get(topic)
        if entry is None:
            raise BagError(f"topic {topic} not declared; call add_topic first")
        publish = log_time_ns if publish_time_ns is None else publish_time_ns
        self._writer.add_message(channel_id=entry.channel_id, log_time=int(log_time_ns),
                                 publish_time=int(publish), data=bytes(data),
                                 sequence=entry.count)
        entry.count += 1
        self._first_ns = log_time_ns if self._first_ns is None else min(self._first_ns, log_time_ns)
        self._last_ns = max(self._last_ns, log_time_ns)
        # The MCAP writer emits bytes only when a chunk closes; push each closed
        # chunk to the OS so that a killed process keeps it.
        position = self._stream.tell()
        if position != self._flushed_bytes:
            self._flushed_bytes = position
            self._stream.flush()

    @property
    def message_count(self) -> int:
        return sum(t.count for t in self._topics.values())

    def bag_info(self) -> dict:
        """The ``rosbag2_bagfile_information`` mapping (bag version 9)."""
        start = self._first_ns or 0
        duration = max(0, self._last_ns - start)
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
            "relative_file_paths": [self.file_name],
            "files": [{"path": self.file_name,
                       "starting_time": {"nanoseconds_since_epoch": start},
                       "duration": {"nanoseconds": duration},
                       "message_count": self.message_count}],
            "custom_data": {}, "ros_distro": "jazzy"}}

    def close(self) -> None:
        """Finish the MCAP (metadata, statistics, summary) and write ``metadata.yaml``."""
        if self._closed:
            return
        self._closed = True
        info = yaml.safe_dump(self.bag_info(), sort_keys=False)
        self._writer.add_metadata("rosbag2", {"serialized_metadata": info})
        self._writer.finish()
        self._stream.close()
        (self.path / "metadata.yaml").write_text(info)

    def __enter__(self) -> "BagWriter":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
