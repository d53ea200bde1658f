"""Read rosbag2 MCAP bags (ours or rosbag2's) without a ROS graph.

Accepts a bag directory (with or without ``metadata.yaml``; a bag split over
several ``*.mcap`` files is merged in time order) or a single ``.mcap`` file.
Messages whose encoding is not ``cdr`` are refused with :class:`BagError`;
decoding needs the type installed (``rclpy`` deserialisation).

Every file is identified by its first and last bytes before it is parsed
(:func:`identify_bag_file`): an image, an archive, a CSV, a rosbag2 SQLite bag, an
empty file, a truncated MCAP (a killed recorder: ``recover`` helps) and an MCAP of
another kind (not the ``ros2`` profile) are each refused in one line naming what it is.
"""
from __future__ import annotations

import heapq
import struct
import importlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from mcap.exceptions import McapError
from zstandard import ZstdError
from mcap.reader import make_reader
from mcap.stream_reader import StreamReader

from ..core.errors import BagError
from ..core.inputs.file_kinds import IDENTIFY_BYTES, MCAP_MAGIC, looks_like_text, signature_kind


#: What parsing a damaged or foreign file can raise inside the mcap library and
#: its decompressors (zstd, lz4: RuntimeError). Every one is the file's fault and
#: becomes a BagError naming the file - MemoryError too: the library allocates
#: what a (corrupt) record length field says before it reads the record.
DAMAGED_FILE = (McapError, ValueError, EOFError, struct.error, OSError, KeyError, IndexError,
                TypeError, AttributeError, RuntimeError, OverflowError, MemoryError, ZstdError)


@dataclass(frozen=True)
class BagMessage:
    """One message: topic, type (pkg/msg/Type), CDR bytes, times [ns].

    ``schema`` (the recorded ``.msg`` text) and ``type_hash`` (the recorded
    RIHS01 hash) let :func:`decode` read a message recorded with another
    version of its type.
    """

    topic: str
    type: str
    data: bytes
    log_time_ns: int
    publish_time_ns: int
    schema: bytes = b""
    type_hash: str = ""


#: The MCAP profile of a ROS 2 (rosbag2) bag.
ROS2_PROFILE = "ros2"
#: The command lines that read a CSV, said when one is given for a bag.
CSV_READERS = ("`mt-accuracy check {path} --target COLUMN` (a thermal log) or "
               "`--columns MAP.yaml` (a survey) reads it")


def _not_mcap(path: Path, head: bytes) -> str:
    """One line saying what ``path`` (no MCAP magic; first bytes ``head``) is instead."""
    kind = signature_kind(head)
    if kind:
        return f"{path} is {kind}, not an MCAP bag or a CSV"
    if looks_like_text(head):
        kind = "a CSV" if path.suffix.lower() in (".csv", ".txt", ".tsv") else \
            "a text file (a CSV?)"
        return f"{path} is {kind}, not an MCAP bag; {CSV_READERS.format(path=path)}"
    return f"{path} is not an MCAP file (no MCAP magic) nor text"


def _header_profile(head: bytes) -> str | None:
    """The profile of the Header record right after the magic (None: none readable)."""
    start = len(MCAP_MAGIC)
    if len(head) < start + 13 or head[start] != 0x01:
        return None
    (length,) = struct.unpack_from("<I", head, start + 9)
    profile = head[start + 13:start + 13 + length]
    return profile.decode("utf-8", errors="replace") if len(profile) == length else None


def _foreign_encodings(path: Path) -> list[str]:
    """The message encodings a complete MCAP file's summary lists ([] when unread)."""
    try:
        with open(path, "rb") as stream:
            summary = make_reader(stream).get_summary()
    except DAMAGED_FILE:
        return []
    if summary is None:
        return []
    return sorted({c.message_encoding for c in summary.channels.values()})


def identify_bag_file(path: str | Path, *, truncated_ok: bool = False) -> None:
    """Refuse ``path`` in one line unless it is a complete ROS 2 MCAP file.

    What it is instead is named from its first bytes: empty, an image, an archive, a
    rosbag2 SQLite bag, text (a CSV: the command that reads it), other bytes; an MCAP
    file that does not end with the MCAP magic is truncated (a recorder killed mid-run:
    ``recover`` saves its closed chunks) unless ``truncated_ok`` (the readers that scan
    up to the last complete record); one whose profile is not ``ros2`` is a foreign
    MCAP (its messages are not CDR: no reader here decodes them).

    Raises
    ------
    BagError
        Naming ``path`` and what it is.
    """
    path = Path(path)
    try:
        size = path.stat().st_size
        with open(path, "rb") as stream:
            head = stream.read(IDENTIFY_BYTES)
            stream.seek(max(0, size - len(MCAP_MAGIC)))
            tail = stream.read()
    except OSError as exc:
        raise BagError(f"{path}: cannot read ({exc.strerror})") from exc
    if size == 0:
        raise BagError(f"{path} is empty (0 bytes), not an MCAP bag")
    if not head.startswith(MCAP_MAGIC):
        raise BagError(_not_mcap(path, head))
    profile = _header_profile(head)
    if profile is not None and profile != ROS2_PROFILE:
        encodings = _foreign_encodings(path)
        held = f", {'/'.join(encodings)} messages" if encodings else ""
        raise BagError(f"{path} is an MCAP file of another kind (profile {profile!r}{held}), "
                       f"not a ROS 2 bag (profile 'ros2', CDR messages, rosbag2 metadata): "
                       "record it with `mt-accuracy record` or `ros2 bag record`")
    if not truncated_ok and (size < 2 * len(MCAP_MAGIC) or tail != MCAP_MAGIC):
        raise BagError(f"{path} is a truncated MCAP file (it ends without its footer and "
                       f"summary: a recorder killed mid-run?); `mt-accuracy recover {path} "
                       "NEW_BAG` saves its closed chunks")


def mcap_files(path: str | Path, *, truncated_ok: bool = False) -> list[Path]:
    """The MCAP files of a bag path, in name order, each identified
    (:func:`identify_bag_file`: a file that is none is refused in one line)."""
    path = Path(path)
    if path.is_file():
        files = [path]
    elif not path.is_dir():
        raise BagError(f"{path}: no such bag (directory or .mcap file)")
    else:
        files = sorted(path.glob("*.mcap"))
        if not files:
            others = sorted(p.name for p in path.glob("*.db3"))
            raise BagError(f"{path}: no .mcap file in the bag directory" +
                           (f" ({others[0]} is a rosbag2 SQLite bag: `ros2 bag convert` it "
                            "to MCAP)" if others else ""))
    for file in files:
        identify_bag_file(file, truncated_ok=truncated_ok)
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
                                 message.log_time, message.publish_time,
                                 schema.data if schema else b"",
                                 channel.metadata.get("topic_type_hash", ""))
    except BagError:
        raise
    except DAMAGED_FILE as exc:
        # Identified before (complete, ros2 profile): the damage is inside the file.
        raise BagError(f"{path}: damaged MCAP file ({exc}); `mt-accuracy recover {path} "
                       "NEW_BAG` saves the complete chunks before the damage") from exc


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


_INSTALLED_HASHES: dict[str, str] = {}
_RECORDED_TYPES: dict[tuple[str, bytes], object] = {}


def _installed_hash(type_name: str) -> str:
    if type_name not in _INSTALLED_HASHES:
        from .msg_definitions import type_hash

        try:
            _INSTALLED_HASHES[type_name] = type_hash(type_name)
        except (BagError, OSError):
            _INSTALLED_HASHES[type_name] = ""
    return _INSTALLED_HASHES[type_name]


def decode(message: BagMessage):
    """Deserialize a :class:`BagMessage` into a message object.

    With the installed type when it is the recorded one (rclpy); when the bag
    recorded another version of the type (its hash differs), with the bag's own
    definition (the ``rosbags`` type system), so old bags stay readable - fields
    the old version lacks are simply absent.
    """
    from rclpy.serialization import deserialize_message

    installed = _installed_hash(message.type)
    if not message.type_hash or not message.schema or message.type_hash == installed:
        try:
            return deserialize_message(message.data, message_class(message.type))
        except BagError:
            if not message.schema:
                raise
        except Exception as exc:  # rclpy raises its own RMWError types
            if not message.schema:
                raise BagError(f"{message.topic}: cannot decode as {message.type} ({exc})") from exc
    return _decode_recorded(message)


def _decode_recorded(message: BagMessage):
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg

    key = (message.type, message.schema)
    store = _RECORDED_TYPES.get(key)
    if store is None:
        store = get_typestore(Stores.EMPTY)
        try:
            text = message.schema.decode()
            blocks = text.split("=" * 80 + "\n")
            store.register(get_types_from_msg(blocks[0], message.type))
            for block in blocks[1:]:
                header, _, body = block.partition("\n")
                name = header.removeprefix("MSG: ").strip()
                if "/msg/" not in name:
                    name = name.replace("/", "/msg/")
                store.register(get_types_from_msg(body, name))
        except Exception as exc:  # noqa: BLE001 - any schema problem is the bag's
            raise BagError(f"{message.topic}: the recorded definition of {message.type} "
                           f"cannot be parsed ({exc})") from exc
        _RECORDED_TYPES[key] = store
    try:
        return store.deserialize_cdr(message.data, message.type)
    except Exception as exc:  # noqa: BLE001
        raise BagError(f"{message.topic}: cannot decode with the recorded definition of "
                       f"{message.type} ({exc})") from exc


def bag_info(path: str | Path) -> dict:
    """Counts, duration and topics of a bag, like ``ros2 bag info``."""
    topics: dict[str, dict] = {}
    first, last, total = None, None, 0
    files = mcap_files(path)
    for f in files:
        try:
            with open(f, "rb") as stream:
                reader = make_reader(stream)
                summary = reader.get_summary()
                if summary is None or summary.statistics is None:
                    raise McapError("no summary section")
                stats = summary.statistics
                for channel_id, channel in summary.channels.items():
                    schema = summary.schemas.get(channel.schema_id)
                    entry = topics.setdefault(channel.topic, {
                        "type": schema.name if schema else "", "count": 0,
                        "encoding": channel.message_encoding})
                    entry["count"] += stats.channel_message_counts.get(channel_id, 0)
                total += stats.message_count
                if stats.message_count:
                    start, end = stats.message_start_time, stats.message_end_time
                    first = start if first is None else min(first, start)
                    last = end if last is None else max(last, end)
        except DAMAGED_FILE as exc:
            raise BagError(f"{f}: damaged MCAP file ({exc}); `mt-accuracy recover {f} "
                           "NEW_BAG` saves the complete chunks before the damage") from exc
    return {"files": [str(f) for f in files], "message_count": total,
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
        except DAMAGED_FILE as exc:
            raise _Truncated() from exc


def recover(path: str | Path) -> list[BagMessage]:
    """Every message of the complete records of a truncated MCAP file.

    A writer killed mid-run leaves no summary; reading the file as a stream
    up to the first incomplete record returns every message of every chunk
    that was closed (and flushed) before the kill.
    """
    from mcap.records import Channel, Message

    path = Path(path)
    identify_bag_file(path, truncated_ok=True)
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
    for f in mcap_files(path, truncated_ok=True):
        try:
            with open(f, "rb") as stream:
                summary = make_reader(stream).get_summary()
        except DAMAGED_FILE:
            summary = None  # no footer (a killed writer): scan the complete records below
        if summary is not None:
            for channel in summary.channels.values():
                schema = summary.schemas.get(channel.schema_id)
                found.setdefault(channel.topic,
                                 _channel_info(channel, schema.name if schema else ""))
            continue
        schemas: dict[int, str] = {}
        channels = 0
        try:
            for record in _complete_records(f, schemas):
                if isinstance(record, Channel):
                    channels += 1
                    found.setdefault(record.topic,
                                     _channel_info(record, schemas.get(record.schema_id, "")))
        except _Truncated as exc:
            if not channels:
                # Nothing complete before the damage: no topic to list (and none to recover).
                raise BagError(f"{f}: damaged MCAP file, no topic readable before the damage "
                               f"({exc.__cause__})") from exc
            # else keep what was complete
    return found
