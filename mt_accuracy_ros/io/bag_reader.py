"""Read rosbag2 MCAP bags (ours or rosbag2's) without a ROS graph.

Accepts a bag directory (with or without ``metadata.yaml``; a bag split over
several ``*.mcap`` files is merged in time order) or a single ``.mcap`` file.
Messages whose encoding is not ``cdr`` are refused with :class:`BagError`;
decoding needs the type installed (``rclpy`` deserialisation).
"""
from __future__ import annotations

import heapq
import struct
import importlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.stream_reader import StreamReader

from ..core.errors import BagError


@dataclass(frozen=True)
class BagMessage:
    """One message: topic, type (pkg/msg/Type), CDR bytes, times [ns]."""

    topic: str
    type: str
    data: bytes
    log_time_ns: int
    publish_time_ns: int


def mcap_files(path: str | Path) -> list[Path]:
    """The MCAP files of a bag path, in name order."""
    path = Path(path)
    if path.is_file():
        return [path]
    if not path.is_dir():
        raise BagError(f"{path}: no such bag (directory or .mcap file)")
    files = sorted(path.glob("*.mcap"))
    if not files:
        raise BagError(f"{path}: no .mcap file in the bag directory")
    return files


def _file_messages(path: Path, topics: set[str] | None) -> Iterator[BagMessage]:
    try:
        with open(path, "rb") as stream:
            reader = make_reader(stream)
            for schema, channel, message in reader.iter_messages(
                    topics=list(topics) if topics else None, log_time_order=True):
                if channel.message_encoding != "cdr":
                    raise BagError(f"{path.name}: topic {channel.topic} has message encoding "
                                   f"{channel.message_encoding!r}; only 'cdr' (ROS 2) is supported")
                yield BagMessage(channel.topic, schema.name if schema else "", message.data,
                                 message.log_time, message.publish_time)
    except McapError as exc:
        raise BagError(f"{path}: not a readable MCAP file ({exc}); "
                       "a truncated file can be salvaged with mt_accuracy_ros.io.bag_reader.recover") from exc
    except (ValueError, EOFError) as exc:
        raise BagError(f"{path}: corrupt or foreign file ({exc})") from exc


def read_messages(path: str | Path, topics: list[str] | None = None) -> Iterator[BagMessage]:
    """All messages of a bag in log-time order (merged over split files)."""
    wanted = set(topics) if topics else None
    streams = [_file_messages(f, wanted) for f in mcap_files(path)]
    yield from heapq.merge(*streams, key=lambda m: m.log_time_ns)


def message_class(type_name: str):
    """The Python class of an installed message type ``pkg/msg/Type``."""
    package, _, name = type_name.partition("/msg/")
    try:
        return getattr(importlib.import_module(f"{package}.msg"), name)
    except (ImportError, AttributeError) as exc:
        raise BagError(f"message type {type_name} is not installed") from exc


def decode(message: BagMessage):
    """Deserialize a :class:`BagMessage` into its ROS message object."""
    from rclpy.serialization import deserialize_message

    return deserialize_message(message.data, message_class(message.type))


def bag_info(path: str | Path) -> dict:
    """Counts, duration and topics of a bag, like ``ros2 bag info``."""
    topics: dict[str, dict] = {}
    first, last, total = None, None, 0
    for f in mcap_files(path):
        try:
            with open(f, "rb") as stream:
                reader = make_reader(stream)
                summary = reader.get_summary()
                if summary is None or summary.statistics is None:
                    raise BagError(f"{f}: no summary/statistics (truncated?); use recover()")
                stats = summary.statistics
                for channel_id, channel in summary.channels.items():
                    schema = summary.schemas.get(channel.schema_id)
                    entry = topics.setdefault(channel.topic, {
                        "type": schema.name if schema else "", "count": 0,
                        "encoding": channel.message_encoding})
                    entry["count"] += stats.channel_message_counts.get(channel_id, 0)
                total += stats.message_count
                if stats.message_count:
                    first = stats.message_start_time if first is None else min(first, stats.message_start_time)
                    last = stats.message_end_time if last is None else max(last, stats.message_end_time)
        except McapError as exc:
            raise BagError(f"{f}: not a readable MCAP file ({exc})") from exc
    return {"files": [str(f) for f in mcap_files(path)], "message_count": total,
            "start_ns": first or 0, "end_ns": last or 0,
            "duration_s": ((last or 0) - (first or 0)) / 1e9, "topics": topics}


class _Truncated(Exception):
    """Raised by :func:`_complete_records` at the first incomplete record."""


def _complete_records(path: Path, schemas: dict[int, str]):
    """Records of an MCAP file read as a stream, up to the first incomplete one.

    Fills ``schemas`` (id -> name) on the way; raises :class:`_Truncated` where
    the file stops making sense (a killed writer's last, open chunk).
    """
    from mcap.records import Schema

    with open(path, "rb") as stream:
        try:
            for record in StreamReader(stream, skip_magic=False, emit_chunks=False).records:
                if isinstance(record, Schema):
                    schemas[record.id] = record.name
                yield record
        except (McapError, EOFError, ValueError, struct.error) as exc:
            raise _Truncated() from exc


def recover(path: str | Path) -> list[BagMessage]:
    """Every message of the complete records of a truncated MCAP file.

    A writer killed mid-run leaves no summary; reading the file as a stream
    up to the first incomplete record returns every message of every chunk
    that was closed (and flushed) before the kill.
    """
    from mcap.records import Channel, Message

    path = Path(path)
    out: list[BagMessage] = []
    schemas: dict[int, str] = {}
    channels: dict = {}
    try:
        for record in _complete_records(path, schemas):
            if isinstance(record, Channel):
                channels[record.id] = record
            elif isinstance(record, Message) and record.channel_id in channels:
                channel = channels[record.channel_id]
                out.append(BagMessage(channel.topic, schemas.get(channel.schema_id, ""),
                                      record.data, record.log_time, record.publish_time))
    except _Truncated as exc:
        if not out and not channels:
            raise BagError(f"{path}: nothing recoverable ({exc.__cause__})") from exc
    return sorted(out, key=lambda m: m.log_time_ns)


@dataclass(frozen=True)
class TopicInfo:
    """What a bag says about one topic."""

    name: str
    type: str
    encoding: str
    offered_qos: tuple[dict, ...]


def _channel_info(channel, schema_name: str) -> TopicInfo:
    import yaml

    try:
        qos = yaml.safe_load(channel.metadata.get("offered_qos_profiles", "") or "[]") or []
    except yaml.YAMLError:
        qos = []
    return TopicInfo(channel.topic, schema_name, channel.message_encoding,
                     tuple(q for q in qos if isinstance(q, dict)))


def topics(path: str | Path) -> dict[str, TopicInfo]:
    """Topic name -> :class:`TopicInfo` over every file of a bag.

    Uses each file's summary; a file without one (a killed writer) is scanned
    up to its last complete record.
    """
    from mcap.records import Channel

    found: dict[str, TopicInfo] = {}
    for f in mcap_files(path):
        try:
            with open(f, "rb") as stream:
                summary = make_reader(stream).get_summary()
        except (McapError, ValueError, EOFError, struct.error) as exc:
            raise BagError(f"{f}: not a readable MCAP file ({exc})") from exc
        if summary is not None:
            for channel in summary.channels.values():
                schema = summary.schemas.get(channel.schema_id)
                found.setdefault(channel.topic, _channel_info(channel, schema.name if schema else ""))
            continue
        schemas: dict[int, str] = {}
        try:
            for record in _complete_records(f, schemas):
                if isinstance(record, Channel):
                    found.setdefault(record.topic,
                                     _channel_info(record, schemas.get(record.schema_id, "")))
        except _Truncated:
            pass  # keep what was complete
    return found
