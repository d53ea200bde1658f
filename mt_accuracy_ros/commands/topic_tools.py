"""``mt-accuracy topic list | info | echo | hz``: ``ros2 topic`` for the PyPI install.

Each works on the live graph (this host's ROS domain) or, with ``--bag``, on a
recorded bag, with the output conventions of ``ros2 topic``: ``list -t``
prints ``/name [pkg/msg/Type]``; ``info`` prints the type and the publisher
and subscription counts; ``echo`` prints each message as YAML followed by
``---``; ``hz`` prints ``average rate``, ``min``, ``max``, ``std dev`` and
``window`` (for a bag: once, over the recorded stamps).
"""
from __future__ import annotations

import array
import dataclasses
import sys
import time
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import yaml


# ----------------------------------------------------------------------- pure parts
def message_to_plain(message, *, no_arrays: bool = False, truncate: int = 0):
    """A rosidl message as nested dicts and lists, fields in declaration order."""
    if hasattr(message, "get_fields_and_field_types"):
        return {name: message_to_plain(getattr(message, name), no_arrays=no_arrays,
                                       truncate=truncate)
                for name in message.get_fields_and_field_types()}
    if dataclasses.is_dataclass(message):  # decoded with a bag's own (older) definition
        return {f.name: message_to_plain(getattr(message, f.name), no_arrays=no_arrays,
                                         truncate=truncate)
                for f in dataclasses.fields(message) if not f.name.startswith("__")}
    if isinstance(message, (array.array, np.ndarray, list, tuple)):
        values = list(message)
        if no_arrays:
            return f"<sequence, length: {len(values)}>"
        if truncate and len(values) > truncate:
            values = values[:truncate]
        plain = [message_to_plain(v, no_arrays=no_arrays, truncate=truncate) for v in values]
        return plain + (["..."] if truncate and len(message) > truncate else [])
    if isinstance(message, (bytes, bytearray)):
        return list(message)
    if isinstance(message, np.generic):
        return message.item()
    return message


def message_to_yaml(message, *, no_arrays: bool = False, truncate: int = 0) -> str:
    """YAML of a message as ``ros2 topic echo`` prints it (without the ``---``)."""
    return yaml.safe_dump(message_to_plain(message, no_arrays=no_arrays, truncate=truncate),
                          sort_keys=False, default_flow_style=False, allow_unicode=True)


@dataclass(frozen=True)
class RateStatistics:
    """``ros2 topic hz`` figures of a series of arrival times."""

    average_rate_hz: float
    min_period_s: float
    max_period_s: float
    std_dev_s: float
    window: int

    def text(self) -> str:
        return (f"average rate: {self.average_rate_hz:.3f}\n"
                f"\tmin: {self.min_period_s:.3f}s max: {self.max_period_s:.3f}s "
                f"std dev: {self.std_dev_s:.5f}s window: {self.window}")


def rate_statistics(times_ns: Iterable[int]) -> RateStatistics | None:
    """Rate of messages arriving at ``times_ns`` (None for fewer than two)."""
    times = np.sort(np.asarray(list(times_ns), dtype=np.float64)) / 1e9
    if times.size < 2:
        return None
    periods = np.diff(times)
    mean = float(np.mean(periods))
    return RateStatistics(1.0 / mean if mean > 0 else float("inf"), float(periods.min()),
                          float(periods.max()), float(np.std(periods)), int(times.size))


# ----------------------------------------------------------------------- bags
def bag_topics(bag) -> dict[str, str]:
    from ..io.bag_reader import topics

    return {name: info.type for name, info in topics(bag).items()}


def _bag_messages(bag, topic: str):
    from ..io.bag_reader import read_messages

    found = bag_topics(bag)
    if topic not in found:
        raise KeyError(f"topic {topic} is not in {bag}; topics: {', '.join(sorted(found))}")
    yield from read_messages(bag, [topic])


# ----------------------------------------------------------------------- live graph
def _node(name: str):
    import rclpy

    rclpy.init()
    return rclpy.create_node(name, start_parameter_services=False)


def _close(node) -> None:
    import rclpy

    node.destroy_node()
    rclpy.try_shutdown()


def _discover(node, seconds: float) -> dict[str, list[str]]:
    import rclpy

    end = time.monotonic() + seconds
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    return dict(node.get_topic_names_and_types())


def _live_type(node, topic: str, seconds: float) -> str:
    """The topic's type, as soon as discovery shows it (at most ``seconds``)."""
    import rclpy

    end = time.monotonic() + seconds
    found = dict(node.get_topic_names_and_types())
    while topic not in found and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
        found = dict(node.get_topic_names_and_types())
    if topic not in found:
        raise KeyError(f"topic {topic} is not published on this domain (after {seconds:g} s "
                       f"of discovery); topics: {', '.join(sorted(found)) or 'none'}")
    return found[topic][0]


def _subscribe(node, topic: str, type_name: str, callback):
    """Subscribe with QoS that matches any publisher: best effort, volatile."""
    from rclpy.qos import qos_profile_sensor_data

    from ..io.bag_reader import message_class

    return node.create_subscription(message_class(type_name), topic, callback,
                                    qos_profile_sensor_data)


# ----------------------------------------------------------------------- commands
def cmd_list(args, out=None) -> int:
    out = out or sys.stdout
    if args.bag:
        found = bag_topics(args.bag)
    else:
        node = _node("mt_accuracy_topic_list")
        try:
            found = {name: types[0] for name, types in _discover(node, spin_time(args)).items()}
        finally:
            _close(node)
    for name in sorted(found):
        print(f"{name} [{found[name]}]" if args.show_types else name, file=out)
    return 0


def cmd_info(args, out=None) -> int:
    out = out or sys.stdout
    if args.bag:
        from ..io.bag_reader import bag_info

        found = bag_topics(args.bag)
        if args.topic not in found:
            raise KeyError(f"topic {args.topic} is not in {args.bag}")
        count = bag_info(args.bag)["topics"].get(args.topic, {}).get("count", 0)
        print(f"Type: {found[args.topic]}\nMessage count: {count}", file=out)
        return 0
    node = _node("mt_accuracy_topic_info")
    try:
        type_name = _live_type(node, args.topic, spin_time(args))
        print(f"Type: {type_name}\nPublisher count: {node.count_publishers(args.topic)}\n"
              f"Subscription count: {node.count_subscribers(args.topic)}", file=out)
    finally:
        _close(node)
    return 0


def cmd_echo(args, out=None) -> int:
    out = out or sys.stdout
    options = {"no_arrays": args.no_arr, "truncate": args.truncate_length}
    limit = 1 if args.once else args.count
    if args.bag:
        from ..io.bag_reader import decode

        for shown, message in enumerate(_bag_messages(args.bag, args.topic)):
            if limit and shown >= limit:
                break
            print(message_to_yaml(decode(message), **options) + "---", file=out)
        return 0
    import rclpy

    node = _node("mt_accuracy_topic_echo")
    shown = [0]

    def on_message(message) -> None:
        if not limit or shown[0] < limit:
            print(message_to_yaml(message, **options) + "---", file=out, flush=True)
            shown[0] += 1

    try:
        _subscribe(node, args.topic, _live_type(node, args.topic, spin_time(args)), on_message)
        end = time.monotonic() + args.duration if args.duration else float("inf")
        while rclpy.ok() and (not limit or shown[0] < limit) and time.monotonic() < end:
            rclpy.spin_once(node, timeout_sec=0.05)
    except KeyboardInterrupt:
        pass
    finally:
        _close(node)
    return 0


def cmd_hz(args, out=None) -> int:
    out = out or sys.stdout
    if args.bag:
        from ..io.bag_reader import decode
        from ..io.fields import stamp_to_nanoseconds

        times = []
        for message in _bag_messages(args.bag, args.topic):
            if args.use_header_stamp:
                times.append(stamp_to_nanoseconds(decode(message).header.stamp))
            else:
                times.append(message.log_time_ns)
        statistics = rate_statistics(times[-args.window:] if args.window else times)
        print(statistics.text() if statistics else "no new messages", file=out)
        return 0
    import rclpy

    node = _node("mt_accuracy_topic_hz")
    arrivals: list[int] = []
    reports = 0
    try:
        _subscribe(node, args.topic, _live_type(node, args.topic, spin_time(args)),
                   lambda _: arrivals.append(time.monotonic_ns()))
        end = time.monotonic() + args.duration if args.duration else float("inf")
        next_report = time.monotonic() + 1.0
        while rclpy.ok() and time.monotonic() < end:
            rclpy.spin_once(node, timeout_sec=0.02)
            if time.monotonic() >= next_report:
                next_report += 1.0
                statistics = rate_statistics(arrivals[-args.window:] if args.window else arrivals)
                print(statistics.text() if statistics else "no new messages", file=out,
                      flush=True)
                reports += 1
                if args.count and reports >= args.count:
                    break
    except KeyboardInterrupt:
        pass
    finally:
        _close(node)
    return 0


#: Discovery on the live graph when --spin-time is not given [s].
SPIN_TIME_S = 1.5
#: Options that only the live graph reads (argparse name: as typed); hz's -n counts live
#: reports too.
LIVE_ONLY = {"spin_time": "--spin-time", "duration": "--duration"}
#: Options that only a bag's reading takes.
BAG_ONLY = {"use_header_stamp": "--use-header-stamp"}


def spin_time(args) -> float:
    """Seconds of discovery on the live graph: --spin-time or :data:`SPIN_TIME_S`."""
    return SPIN_TIME_S if args.spin_time is None else args.spin_time


def validate_args(args) -> None:
    """Refuse, in one line, an option out of its range or given where the verb does not
    read it (live-graph options with --bag, bag options without)."""
    from ..core.inputs.options import in_range, not_applicable

    live_only = dict(LIVE_ONLY, **({"count": "-n/--count"} if args.verb == "hz" else {}))
    for name, flag in live_only.items():
        if args.bag and getattr(args, name, None) is not None:
            raise not_applicable(flag, "the live graph", f"a bag (--bag {args.bag})")
    for name, flag in BAG_ONLY.items():
        if not args.bag and getattr(args, name, False):
            raise not_applicable(flag, "a bag (--bag)", "the live graph")
    in_range("--spin-time", getattr(args, "spin_time", None), low=0, low_open=True, unit="s")
    in_range("--duration", getattr(args, "duration", None), low=0, unit="s; 0: no limit")
    in_range("-n/--count", getattr(args, "count", None), low=0, what="an integer",
             unit="0: no limit")
    in_range("--truncate-length", getattr(args, "truncate_length", None), low=0,
             what="an integer", unit="0: whole arrays")
    in_range("-w/--window", getattr(args, "window", None), low=0, what="an integer",
             unit="messages; 0: all")


def add_parser(commands) -> None:
    """The ``topic`` sub-command and its verbs."""
    topic = commands.add_parser("topic", help="inspect topics, live or in a bag (like ros2 topic)")
    verbs = topic.add_subparsers(dest="verb", required=True)

    def common(parser, needs_topic: bool = True) -> None:
        if needs_topic:
            parser.add_argument("topic", help="topic name, e.g. /scales")
        parser.add_argument("--bag", help="read a recorded bag instead of the live graph")
        parser.add_argument("--spin-time", type=float, default=None,
                            help=f"seconds of discovery on the live graph (default "
                                 f"{SPIN_TIME_S:g})")

    listing = verbs.add_parser("list", help="topic names")
    common(listing, needs_topic=False)
    listing.add_argument("-t", "--show-types", action="store_true")
    listing.set_defaults(handler=cmd_list, validate=validate_args)
    info = verbs.add_parser("info", help="type, publisher and subscription counts")
    common(info)
    info.set_defaults(handler=cmd_info, validate=validate_args)
    echo = verbs.add_parser("echo", help="messages as YAML")
    common(echo)
    echo.add_argument("--once", action="store_true")
    echo.add_argument("-n", "--count", type=int, default=0, help="stop after N messages")
    echo.add_argument("--no-arr", action="store_true", help="print array lengths only")
    echo.add_argument("--truncate-length", type=int, default=0, metavar="N",
                      help="print at most N elements of each array")
    echo.add_argument("--duration", type=float, default=None, help="live: stop after S seconds")
    echo.set_defaults(handler=cmd_echo, validate=validate_args)
    hz = verbs.add_parser("hz", help="publishing rate")
    common(hz)
    hz.add_argument("-w", "--window", type=int, default=10000)
    hz.add_argument("--use-header-stamp", action="store_true",
                    help="bag: rate of the header stamps instead of the receive times")
    hz.add_argument("-n", "--count", type=int, default=None, help="live: stop after N reports")
    hz.add_argument("--duration", type=float, default=None, help="live: stop after S seconds")
    hz.set_defaults(handler=cmd_hz, validate=validate_args)
