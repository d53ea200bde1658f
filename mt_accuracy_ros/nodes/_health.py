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
#: Key prefix of the warnings a node has said, sent with every status
#: (``warning.0``, ``warning.1`` ...): see :func:`warnings_of`.
WARNING_KEY = "warning"


def warnings_of(values: dict[str, str]) -> list[str]:
    """The warnings in a ``<node>: delivery`` status' values (key -> value), in order."""
    numbered = [(int(key.split(".", 1)[1]), text) for key, text in values.items()
                if key.startswith(f"{WARNING_KEY}.") and key.split(".", 1)[1].isdigit()]
    return [text for _, text in sorted(numbered)]


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
        #: Every WARN this node has said, in order: repeated with every status as
        #: ``warning.<n>`` so that a listener that missed the moment (or came late)
        #: still hears it - a run's summary must carry them all.
        self.warnings: list[str] = []
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
        if message not in self.warnings:
            self.warnings.append(message)
        self._send([self._status(DiagnosticStatus.WARN, message, self._note_values())])

    def _note_values(self) -> list[KeyValue]:
        return [KeyValue(key=key, value=value) for key, value in sorted(self.notes.items())] + \
            [KeyValue(key=f"{WARNING_KEY}.{k}", value=text)
             for k, text in enumerate(self.warnings)]

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


class LiveSensorWatch:
    """Each live temperature sensor judged reading by reading, by the rules the offline
    judge uses (:mod:`mt_accuracy_ros.core.inputs.sensor_health`): no value (NaN, inf),
    a physically absent value (outside ``PHYSICAL_RANGE_C``: an open thermocouple's
    -180 degC), a value outside the workshop's range, or frozen - the very same value
    over ``STUCK_MIN_ROWS`` readings in a row while another sensor moves by
    ``OTHERS_MOVE_K`` or more over them. Live, "frozen" is bit-identical (the offline
    rule's one-quantum tolerance needs the whole log to find the quantum; a live window
    is too short to tell a 0.01 K logger from a stuck one).

    Pure bookkeeping, no ROS: the node says what :meth:`judge` finds on /diagnostics.
    """

    def __init__(self, window: int | None = None) -> None:
        from collections import deque

        from ..core.inputs.sensor_health import STUCK_MIN_ROWS

        self.window = int(window or STUCK_MIN_ROWS)
        self._recent: dict[str, "deque[float]"] = {}
        self._deque = deque

    def judge(self, readings: dict[str, float]
              ) -> tuple[dict[str, float], dict[str, tuple[str, str]]]:
        """One message's readings [degC] (in data-time order): (the readings the model may
        use, sensor -> (kind, why it is left out)), the kinds those of the offline judge
        ("dropout", "dead", "out_of_range", "stuck"), e.g. ("dead", "reads -180 degC, a
        physically absent value (outside -50 ... 200 degC: dead)")."""
        import numpy as np

        from ..core.inputs.sensor_health import (OTHERS_MOVE_K, PHYSICAL_RANGE_C,
                                                 WORKSHOP_RANGE_C, dead_rows, out_of_range_rows)

        for name, value in readings.items():
            self._recent.setdefault(name, self._deque(maxlen=self.window)).append(float(value))
        good, bad = {}, {}
        for name, value in readings.items():
            one = np.array([value], dtype=np.float64)
            if not np.isfinite(value):
                bad[name] = ("dropout", f"no value ({value})")
            elif dead_rows(one)[0]:
                low, high = PHYSICAL_RANGE_C
                bad[name] = ("dead", f"reads {value:.4g} degC, a physically absent value "
                             f"(outside {low:g} ... {high:g} degC: dead)")
            elif out_of_range_rows(one)[0]:
                low, high = WORKSHOP_RANGE_C
                bad[name] = ("out_of_range", f"reads {value:.4g} degC, outside a workshop's "
                             f"{low:g} ... {high:g} degC (a wrong unit or channel?)")
            elif self._frozen(name, OTHERS_MOVE_K):
                bad[name] = ("stuck", f"frozen at {value:.6g} degC for {self.window} readings "
                             f"while another sensor moves by {OTHERS_MOVE_K:g} K or more")
            else:
                good[name] = float(value)
        return good, bad

    def _frozen(self, name: str, others_move_k: float) -> bool:
        import numpy as np

        from ..core.inputs.sensor_health import PHYSICAL_RANGE_C as physical

        mine = self._recent[name]
        if len(mine) < self.window or len(set(mine)) != 1:
            return False
        for other, values in self._recent.items():
            seen = np.array(values, dtype=np.float64)
            low, high = physical
            seen = seen[np.isfinite(seen) & (seen >= low) & (seen <= high)]   # sane ones only
            if other != name and len(values) == self.window and seen.size >= 2 and \
                    np.ptp(seen) >= others_move_k:
                return True
        return False
