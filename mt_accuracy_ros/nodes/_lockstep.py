"""Lockstep: the virtual machine streams in data time, as fast as its slowest consumer.

In a real-time run the virtual machine streams at the wall clock's pace and a
loaded host changes the outcome: corrections arrive too late to apply, a check
ends seconds of data after its readings, a model goes live late. In a lockstep
run (parameter ``lockstep`` on every node of the loop) each participant
reports on ``lockstep`` (``mt_accuracy_msgs/DataProgress``) how far it has
handled the data, and the machine streams the next batch only once every
participant has caught up. Every node then sees the same data in the same
order, and every decision falls at the same data time, on any host: slower
hosts take longer, they do not get other results.

A participant is named in the machine's ``lockstep_nodes`` as ``node:stream``;
the stream says what it must have handled before the batch covering data time
[start, end) goes out (``B`` = end - start):

``scales``
    the scale batches up to ``start - lockstep_lead_s`` (the estimator);
``compensation``
    the batches up to ``start + B - compensation_delay_s``: every correction the
    CNC applies in this batch is in before it (the broadcaster; needs
    ``compensation_delay_s >= B``);
``reference``
    every reference reading the machine published (the monitor: a reading
    starting a check counts as handled once the check is published);
``temperatures``
    published every temperature stamped up to ``start`` (the temperature
    publisher follows the machine's own progress: the position of the stream,
    which the machine says on ``lockstep/stream`` whenever such a participant may
    wait for it - not on ``lockstep``, whose reports only the machine needs);
``checks``
    acted on every check any participant published (a user).

Besides, every participant that follows model versions (``model_version_settled
>= 0``) must have settled - made live or refused - the newest version any
participant published. A participant silent for ``lockstep_timeout_s`` of wall
time while the machine waits on it is left out, with a WARN: a dead node must
not hang the machine. The WARN is repeated with every status the machine sends
(``warning.<n>``, :class:`._health.DeliveryHealth`), so the main job's summary
names the participant left out among its warnings, whenever it listened.
"""
from __future__ import annotations

from dataclasses import dataclass

STREAMS = ("scales", "compensation", "reference", "temperatures", "checks")
#: The participants' reports, heard by the machine.
PROGRESS_TOPIC = "lockstep"
#: The machine's stream position, heard by what follows it (the temperature source): a
#: topic of its own, so that neither hears the reports it has no use for - every report
#: costs each subscriber a callback, several reports per batch.
STREAM_TOPIC = "lockstep/stream"


@dataclass
class Progress:
    """One participant's latest ``DataProgress`` (stamps in ns of the run's time base)."""

    handled_ns: int = 0
    last_check_ns: int = 0
    check_handled_ns: int = 0
    model_version_published: int = -1
    model_version_settled: int = -1

    def merged(self, other: "Progress") -> "Progress":
        """Field by field the further of the two: a report never goes back."""
        return Progress(*(max(a, b) for a, b in zip(
            (self.handled_ns, self.last_check_ns, self.check_handled_ns,
             self.model_version_published, self.model_version_settled),
            (other.handled_ns, other.last_check_ns, other.check_handled_ns,
             other.model_version_published, other.model_version_settled))))


def parse_participants(entries: list[str]) -> dict[str, str]:
    """``["yaw_estimator:scales", ...]`` -> {node: stream}; a clear error otherwise."""
    participants: dict[str, str] = {}
    for entry in entries:
        if not entry:
            continue
        node, _, stream = entry.partition(":")
        if not node or stream not in STREAMS:
            raise ValueError(f"lockstep participant {entry!r}: give node:stream, the stream one "
                             f"of {', '.join(STREAMS)}")
        if node in participants:
            raise ValueError(f"lockstep participant {node!r} named twice")
        participants[node] = stream
    return participants


class LockstepGate:
    """Whether the machine may stream its next batch: pure bookkeeping, no ROS.

    Parameters
    ----------
    participants : dict
        node name -> stream (see the module's description).
    lead_ns : int
        How far ``scales`` participants may trail the stream [ns].
    compensation_delay_ns : int
        The CNC's fixed delay from a correction's stamp to its application [ns].
    """

    def __init__(self, participants: dict[str, str], *, lead_ns: int,
                 compensation_delay_ns: int) -> None:
        self.participants = dict(participants)
        self.lead_ns = int(lead_ns)
        self.delay_ns = int(compensation_delay_ns)
        self.progress: dict[str, Progress] = {}
        self.left_out: dict[str, str] = {}   # node -> why it no longer holds the stream

    def update(self, node: str, progress: Progress) -> None:
        """A participant's report; reports going back in data time are kept monotone."""
        old = self.progress.get(node)
        if old is not None:
            progress = old.merged(progress)
        self.progress[node] = progress

    def leave_out(self, node: str, reason: str) -> None:
        self.left_out[node] = reason

    def stream_awaited(self, position_ns: int) -> bool:
        """Whether a ``temperatures`` participant may still wait for the stream to reach
        ``position_ns`` [ns]: one that has not reported, or has published only the
        readings stamped before it. True without such a participant (a node following the
        stream without holding it then hears every position, as before)."""
        followers = [n for n, s in self.participants.items()
                     if s == "temperatures" and n not in self.left_out]
        return not followers or any(
            n not in self.progress or self.progress[n].handled_ns < position_ns
            for n in followers)

    def waiting_for(self, start_ns: int, end_ns: int, last_reference_ns: int | None,
                    stream_start_ns: int) -> tuple[str, str] | None:
        """(node, what it has not done yet) holding the batch [start, end), or None.

        ``last_reference_ns`` is the stamp of the newest reference reading the machine
        published (None: none yet); ``stream_start_ns`` the stamp of the run's first
        sample - nothing before it needs handling.
        """
        active = {n: s for n, s in self.participants.items() if n not in self.left_out}
        for node in active:
            if node not in self.progress:
                return node, "has not reported yet"
        newest_check = max((p.last_check_ns for p in self.progress.values()), default=0)
        newest_version = max((p.model_version_published for p in self.progress.values()),
                             default=-1)
        for node, stream in active.items():
            p = self.progress[node]
            scales_needed = start_ns - self.lead_ns
            if stream == "scales" and scales_needed > stream_start_ns and \
                    p.handled_ns < scales_needed:
                return node, f"scales handled to {p.handled_ns} ns, needed {scales_needed}"
            corrections_needed = end_ns - self.delay_ns
            if stream == "compensation" and corrections_needed > stream_start_ns and \
                    p.handled_ns < corrections_needed:
                return node, "the corrections this batch applies are not in"
            if stream == "reference" and last_reference_ns is not None and \
                    p.handled_ns <= last_reference_ns:
                return node, f"reference reading {last_reference_ns} ns not handled"
            if stream == "temperatures" and p.handled_ns < start_ns:
                return node, "temperatures before the batch not published"
            if stream == "checks" and p.check_handled_ns < newest_check:
                return node, f"check {newest_check} ns not acted on"
            if p.model_version_settled >= 0 and p.model_version_settled < newest_version:
                return node, f"model version {newest_version} not settled"
        return None


def check_compensation_delay(delay_s: float, batch_s: float, participants: dict[str, str]) -> None:
    """A ``compensation`` participant can only keep up when the CNC's delay covers a batch."""
    if "compensation" in participants.values() and delay_s + 1e-12 < batch_s:
        raise ValueError(f"lockstep with a compensation participant needs compensation_delay_s "
                         f"({delay_s:g} s) >= batch_period_s ({batch_s:g} s): a batch's "
                         "corrections must be computable before it goes out")


# ------------------------------------------------------------------ ROS glue
def lockstep_qos():
    """Reliable, transient local: a late subscriber gets each participant's newest
    report; keep last 100 so that one participant's reports never push out another's."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    return QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL,
                      history=HistoryPolicy.KEEP_LAST)


class ProgressReporter:
    """Publishes one node's ``DataProgress`` on ``topic`` (:data:`PROGRESS_TOPIC`, or the
    machine's :data:`STREAM_TOPIC`): at each change (a report that changes nothing is not
    sent) and every 0.25 s of wall time (so a machine that subscribes late still hears
    it)."""

    def __init__(self, node, name: str | None = None, *, follows_models: bool = False,
                 publishes_models: bool = False, topic: str = PROGRESS_TOPIC) -> None:
        from rclpy.clock import Clock, ClockType

        from mt_accuracy_msgs.msg import DataProgress

        self._type = DataProgress
        self.node = node
        self.name = name or node.get_name()
        self.state = Progress(model_version_published=0 if publishes_models else -1,
                              model_version_settled=0 if follows_models else -1)
        self._publisher = node.create_publisher(DataProgress, topic, lockstep_qos())
        node.create_timer(0.25, self.publish, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.publish()

    def report(self, *, handled_ns: int | None = None, last_check_ns: int | None = None,
               check_handled_ns: int | None = None, published: int | None = None,
               settled: int | None = None) -> None:
        state = self.state.merged(Progress(
            handled_ns or 0, last_check_ns or 0, check_handled_ns or 0,
            -1 if published is None else int(published),
            -1 if settled is None else int(settled)))
        # A report that changes nothing tells the machine nothing: every participant
        # receives every report, and repeats cost each of them a callback per batch.
        # The 0.25 s heartbeat still repeats the state for a late subscriber.
        if state != self.state:
            self.state = state
            self.publish()

    def publish(self) -> None:
        from ._common import nanoseconds_to_stamp

        message = self._type()
        message.header.stamp = nanoseconds_to_stamp(self.state.handled_ns)
        message.node = self.name
        message.last_check = nanoseconds_to_stamp(self.state.last_check_ns)
        message.check_handled = nanoseconds_to_stamp(self.state.check_handled_ns)
        message.model_version_published = int(self.state.model_version_published)
        message.model_version_settled = int(self.state.model_version_settled)
        self._publisher.publish(message)


def progress_from_message(message) -> Progress:
    from ._common import stamp_to_nanoseconds

    return Progress(stamp_to_nanoseconds(message.header.stamp),
                    stamp_to_nanoseconds(message.last_check),
                    stamp_to_nanoseconds(message.check_handled),
                    int(message.model_version_published), int(message.model_version_settled))


def batch_end_ns(message) -> int:
    """The stamp just after a ``ScaleBatch``'s last sample: what handling it covers [ns]."""
    from ._common import stamp_to_nanoseconds

    if len(message.command_axes):
        samples = len(message.command_positions) // len(message.command_axes)
    else:
        samples = len(message.positions) // max(1, len(message.channel_names))
    return stamp_to_nanoseconds(message.header.stamp) + int(round(
        samples * float(message.sample_period) * 1e9))


def report_after(reporter: ProgressReporter | None, callback):
    """``callback`` for ``ScaleBatch`` messages, then (lockstep) the batch reported
    handled - refused or not: a bad batch must not hold the machine."""
    if reporter is None:
        return callback

    def handle(message) -> None:
        try:
            callback(message)
        finally:
            reporter.report(handled_ns=batch_end_ns(message))
    return handle
