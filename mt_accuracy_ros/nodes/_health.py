"""Delivery you can count: what each node processed, refused and lost, on /diagnostics.

Every stream a node subscribes to has counters; every callback runs inside
:meth:`DeliveryHealth.guard`, so a message that makes the code raise - of any
exception type - becomes a counted refusal with its reason instead of killing
the node. Streams that carry a ``sequence`` (or ``first_sample_index``) are
checked for gaps, so losses between publisher and subscriber are counted too.
A ``DiagnosticStatus`` named ``<node>: delivery`` goes out once a second
(steady clock, so it also runs while a replay's ``/clock`` is paused), and a
refusal is reported at once with its reason.
"""
from __future__ import annotations

from collections import Counter, defaultdict

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.clock import Clock, ClockType

#: Counters kept per stream.
COUNTERS = ("processed", "refused", "lost", "out_of_order", "late")


class DeliveryHealth:
    """Per-stream counters of one node and their diagnostics."""

    def __init__(self, node, *, period_s: float = 1.0) -> None:
        self._node = node
        self._publisher = node.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self.counts: dict[str, Counter] = defaultdict(Counter)
        self.last_reason: dict[str, str] = {}
        self._next_sequence: dict[str, int] = {}
        self._reported: dict[str, Counter] = defaultdict(Counter)
        #: Facts about the node sent with every status (e.g. ``scheduling``).
        self.notes: dict[str, str] = {}
        node.create_timer(period_s, self.publish, clock=Clock(clock_type=ClockType.STEADY_TIME))
        # rclpy refuses a value outside its descriptor (range, type, read-only) before any
        # on-set callback runs: counted here, before that check, so that every refused
        # parameter is on /diagnostics (a pre-set callback sees every request).
        node.add_pre_set_parameters_callback(self._count_descriptor_refusals)

    # ------------------------------------------------------------------ counting
    def processed(self, stream: str, count: int = 1) -> None:
        self.counts[stream]["processed"] += count

    def late(self, stream: str, count: int = 1) -> None:
        """Count input that arrived after the data time it belonged to had been processed
        (it is still used, from the next data on: a replay would differ there)."""
        self.counts[stream]["late"] += count

    def refused(self, stream: str, reason: str) -> None:
        """Count a refused message or parameter and report the reason at once."""
        self.counts[stream]["refused"] += 1
        self.last_reason[stream] = reason
        self._node.get_logger().warning(f"{stream}: refused: {reason}")
        self._send([self._status(DiagnosticStatus.WARN, f"{stream}: refused: {reason}",
                                 self._values(stream))])

    def warn(self, message: str) -> None:
        """A WARN on /diagnostics now (and in the log): a condition the node runs on with."""
        self._node.get_logger().warning(message)
        self._send([self._status(DiagnosticStatus.WARN, message, self._note_values())])

    def _note_values(self) -> list[KeyValue]:
        return [KeyValue(key=key, value=value) for key, value in sorted(self.notes.items())]

    def alarm(self, message: str, topic: str = "model") -> None:
        """An ERROR on /diagnostics (``<node>: <topic>``): something the operator must act on."""
        self._node.get_logger().error(message)
        self._send([DiagnosticStatus(level=DiagnosticStatus.ERROR, name=
                                     f"{self._node.get_fully_qualified_name()}: {topic}",
                                     message=message, hardware_id="", values=[])])

    def _count_descriptor_refusals(self, parameters):
        for parameter in parameters:
            problem = descriptor_problem(self._node, parameter)
            if problem:
                self.refused("parameters", problem)
        return parameters

    def sequence(self, stream: str, sequence: int, count: int = 1, *,
                 restart: bool = False) -> int:
        """Check a stream's running ``sequence``; return how many were lost before it.

        ``count`` is how many items the message carries (samples of a batch).
        A sequence below the expected one (a restarted publisher, a replay) is
        counted as out of order and restarts the count there.
        """
        sequence = int(sequence)
        expected = self._next_sequence.get(stream)
        lost = 0
        if restart and expected is not None:
            # The stream was followed again from a new position (StreamHistory): the
            # jump is not samples lost.
            self.counts[stream]["out_of_order"] += 1
        elif expected is None:
            # Where this node joined the stream: earlier items are not "lost" to it.
            self.counts[stream]["first_seen"] = sequence
        else:
            if sequence > expected:
                lost = sequence - expected
                self.counts[stream]["lost"] += lost
            elif sequence < expected:
                self.counts[stream]["out_of_order"] += 1
        self._next_sequence[stream] = sequence + count
        return lost

    def guard(self, stream: str, callback):
        """``callback`` wrapped so that any exception is a counted refusal."""
        def guarded(message):
            try:
                callback(message)
            except Exception as exc:  # noqa: BLE001 - no message may kill the node
                self.refused(stream, f"{type(exc).__name__}: {exc}")
        guarded.__name__ = getattr(callback, "__name__", "guarded")
        return guarded

    # ------------------------------------------------------------------ reporting
    def _values(self, stream: str) -> list[KeyValue]:
        values = [KeyValue(key=f"{stream}.{name}", value=str(self.counts[stream][name]))
                  for name in COUNTERS + ("first_seen",)]
        if stream in self.last_reason:
            values.append(KeyValue(key=f"{stream}.last_refusal", value=self.last_reason[stream]))
        return values

    def _status(self, level: int, message: str, values: list[KeyValue]) -> DiagnosticStatus:
        return DiagnosticStatus(level=level, name=f"{self._node.get_fully_qualified_name()}: "
                                "delivery", message=message, hardware_id="", values=values)

    def publish(self) -> None:
        """One status with every stream's counters; WARN if anything was lost or refused since
        the last report."""
        values, news = [], []
        for stream in sorted(self.counts):
            values.extend(self._values(stream))
            for name in ("refused", "lost", "late"):
                new = self.counts[stream][name] - self._reported[stream][name]
                if new:
                    news.append(f"{stream}: {new} {name}")
            self._reported[stream] = Counter(self.counts[stream])
        level = DiagnosticStatus.WARN if news else DiagnosticStatus.OK
        self._send([self._status(level, "; ".join(news) or "all streams complete",
                                 values + self._note_values())])

    def _send(self, statuses: list[DiagnosticStatus]) -> None:
        array = DiagnosticArray(status=statuses)
        array.header.stamp = self._node.get_clock().now().to_msg()
        self._publisher.publish(array)


def descriptor_problem(node, parameter) -> str:
    """Why rclpy will refuse ``parameter`` by its descriptor ("" if it will not)."""
    from rclpy.parameter import Parameter

    if not node.has_parameter(parameter.name):
        return ""   # undeclared: rclpy raises to the caller; nothing of ours to count
    descriptor = node.describe_parameter(parameter.name)
    if descriptor.read_only:
        return f"{parameter.name} is read-only"
    if descriptor.dynamic_typing or parameter.type_ == Parameter.Type.NOT_SET:
        return ""
    if parameter.type_.value != descriptor.type:
        return (f"{parameter.name}: wrong type {parameter.type_.name}, expected "
                f"{Parameter.Type(descriptor.type).name}")
    ranges = descriptor.integer_range if parameter.type_ == Parameter.Type.INTEGER else \
        descriptor.floating_point_range if parameter.type_ == Parameter.Type.DOUBLE else []
    if ranges:
        low, high, value = ranges[0].from_value, ranges[0].to_value, parameter.value
        # rclpy's own tolerance for doubles at the ends of a range
        slack = 1e-9 * max(abs(low), abs(high), 1.0) if parameter.type_ == \
            Parameter.Type.DOUBLE else 0
        if not (low - slack <= value <= high + slack):
            return f"{parameter.name}: {value} outside [{low}, {high}]"
    return ""
