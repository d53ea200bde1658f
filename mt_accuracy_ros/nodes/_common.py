"""Helpers every node shares: QoS profiles, stamps, parameter descriptors."""
from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

# Message-field conversions live in io (the simulator's bag export needs them too);
# re-exported here for the nodes.
from ..io.fields import (nanoseconds_to_stamp, pack_float64, stamp_to_nanoseconds,  # noqa: F401
                         unpack_float64)

#: Raw sensor streams (scales, temperatures): best effort and volatile like
#: ``qos_profile_sensor_data`` - a retransmitted sample is worth less than the
#: next one - but keep last 100 instead of 5: a batch holds many samples, and a
#: subscriber whose process stalls for a few hundred ms on a loaded 2-core
#: machine must not lose batches it already received.
SENSOR_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.BEST_EFFORT,
                        durability=DurabilityPolicy.VOLATILE, history=HistoryPolicy.KEEP_LAST)

#: After the publisher sees its subscribers matched, the subscribers may not yet
#: have matched the publisher (discovery is not symmetric in time); a best-effort
#: sample sent in that gap is lost. Streams that must be complete wait this long.
MATCH_SETTLE_S = 0.5

#: Results (yaw batches, profiles, compensation): reliable, keep last 50.
RESULT_QOS = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE,
                        durability=DurabilityPolicy.VOLATILE, history=HistoryPolicy.KEEP_LAST)

#: Tables a late joiner must still get: reliable + transient local, keep last 1.
LATCHED_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL,
                         history=HistoryPolicy.KEEP_LAST)

#: Compensation tables, one message per axis: a late joiner must get all of them.
TABLE_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL, history=HistoryPolicy.KEEP_LAST)

#: Real-time compensation: reliable, keep last 2000 (20 s at the default 100 Hz): a
#: subscriber that stalls for seconds still gets every correction; ``sequence`` shows
#: any gap beyond that.
COMPENSATION_QOS = QoSProfile(depth=2000, reliability=ReliabilityPolicy.RELIABLE,
                              durability=DurabilityPolicy.VOLATILE,
                              history=HistoryPolicy.KEEP_LAST)

#: What a controller subscribes the real-time compensation with: best effort,
#: keep last 100. A correction is worth something only until its deadline (tens of
#: ms), so it must never wait: on a reliable subscription one sample lost in
#: transport holds every later one until the writer's heartbeat repairs the gap
#: (Fast DDS's default period is 3 s), and the CNC then refuses ~2-3 s of
#: corrections as stale in one burst. Best effort delivers the next
#: correction at once; a lost one is counted from ``sequence`` (``compensation.lost``
#: on ``/diagnostics``) and the CNC holds the last valid correction for 10 ms.
#: The publisher stays reliable (COMPENSATION_QOS), so recorders and listeners
#: that want every correction still get them; the two are compatible.
CONTROL_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.BEST_EFFORT,
                         durability=DurabilityPolicy.VOLATILE, history=HistoryPolicy.KEEP_LAST)


def float_descriptor(description: str, low: float, high: float,
                     read_only: bool = False) -> ParameterDescriptor:
    """Descriptor of a double parameter with an inclusive range."""
    return ParameterDescriptor(
        description=description, read_only=read_only,
        floating_point_range=[FloatingPointRange(from_value=float(low), to_value=float(high))])


def int_descriptor(description: str, low: int, high: int,
                   read_only: bool = False) -> ParameterDescriptor:
    """Descriptor of an integer parameter with an inclusive range."""
    return ParameterDescriptor(
        description=description, read_only=read_only,
        integer_range=[IntegerRange(from_value=int(low), to_value=int(high), step=1)])


def plain_descriptor(description: str, read_only: bool = False) -> ParameterDescriptor:
    """Descriptor with a description only."""
    return ParameterDescriptor(description=description, read_only=read_only)


def refuse(reason: str) -> SetParametersResult:
    """A failed set-parameters result carrying ``reason``."""
    return SetParametersResult(successful=False, reason=reason)


def accept() -> SetParametersResult:
    """A successful set-parameters result."""
    return SetParametersResult(successful=True)




def node_executor(node, *, events: bool = False):
    """An executor holding ``node`` for good: rclpy's C++ ``EventsExecutor`` with
    ``events``, else a single-threaded one.

    ``rclpy.spin_once(node)`` adds the node to the global executor and removes it
    again on every call, so the executor rebuilds its wait set each time: measured
    in a lockstep main job, that rebuilding was 40 % of the virtual machine's CPU.
    Loops that spin a node repeatedly keep one of these instead. Even kept, the
    single-threaded executor rebuilds its wait set in Python at every wake-up: 0.43 ms
    of CPU per message received one at a time, against 0.18 ms in the events executor
    (``python -m bench.executor_cost``, docs/benchmarks.md) - most of the CPU of the
    nodes that take a message per scale batch. The events executor (rclpy's
    experimental one) is taken by the nodes whose tests pass with it (:func:`run_node`'s
    ``events``); the recorder is not one of them (its ``spin_once`` raised SystemError).
    """
    if events:
        from rclpy.experimental.events_executor import EventsExecutor

        executor = EventsExecutor(context=node.context)
    else:
        from rclpy.executors import SingleThreadedExecutor

        executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    return executor


#: How long a finished node waits at most for its reliable readers to acknowledge
#: everything it published [s]: a reader that died must not hold it for ever.
ACK_WAIT_S = 10.0


def linger(node, seconds: float = 0.5, executor=None) -> None:
    """Keep a finished node alive until its last messages are out: DDS delivers them from
    the writer's history only while the writer exists. ``seconds`` of spinning (best
    effort has no acknowledgement to wait for), then until every reliable reader has
    acknowledged every message (at most :data:`ACK_WAIT_S`): on a loaded host a reader
    may be seconds behind a player at ``--rate 1000``."""
    import time

    import rclpy
    from rclpy.duration import Duration

    executor = executor or node_executor(node)
    end = time.monotonic() + seconds
    while rclpy.ok() and time.monotonic() < end:
        executor.spin_once(timeout_sec=0.05)
    deadline = time.monotonic() + ACK_WAIT_S
    for publisher in list(node.publishers):
        left = deadline - time.monotonic()
        if not rclpy.ok() or left <= 0:
            break
        publisher.wait_for_all_acked(Duration(nanoseconds=int(left * 1e9)))


@contextmanager
def signals_held():
    """SIGINT and SIGTERM held off for the block (main thread, POSIX): Python turns a
    SIGINT into a KeyboardInterrupt at any bytecode, and inside the MCAP writer one
    leaves a chunk half written that the finished file then indexes (seen in a loaded
    run: the bag's last chunk unreadable). A signal that arrives meanwhile is delivered
    when the block ends."""
    if not hasattr(signal, "pthread_sigmask") or \
            threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def run_node(node_class, args: list[str] | None, *, until_finished: bool = False,
             on_exit=None, events: bool = False) -> int:
    """The Jazzy main-loop idiom every node module's ``main()`` shares.

    ``rclpy.init``; construct the node (a configuration error -> message and exit
    code 2); spin - or, ``until_finished``, spin until ``node.finished`` and let
    the last messages out; always ``on_exit(node)``, ``destroy_node()`` and
    ``rclpy.try_shutdown()``. ``events``: spin in rclpy's events executor
    (:func:`node_executor`), for nodes that take a message per scale batch. Its own
    ``spin()`` stays in C++: in this rclpy a SIGINT never reached Python and parameter
    requests went unanswered (test/nodes/test_events_executor.py), so it is spun here
    one callback (or 50 ms) at a time.
    """
    import sys

    import rclpy
    from rclpy.executors import ExternalShutdownException

    from ..core.errors import MtAccuracyError

    rclpy.init(args=args if args is not None else sys.argv)
    from rclpy.exceptions import (InvalidParameterTypeException, InvalidParameterValueException,
                                  NameValidationException, ParameterException)

    try:
        node = node_class()
    except (MtAccuracyError, ParameterException, InvalidParameterTypeException,
            InvalidParameterValueException, NameValidationException, TypeError,
            ValueError) as exc:
        # A configuration error: one line and exit 2, never a traceback.
        print(f"{node_class.__name__}: {' '.join(str(exc).split())}", file=sys.stderr)
        rclpy.try_shutdown()
        return 2
    executor = None
    try:
        if until_finished or events:
            executor = node_executor(node, events=events)
        if until_finished:
            while rclpy.ok() and not node.finished:
                executor.spin_once(timeout_sec=0.05)
            linger(node, executor=executor)
        elif executor is not None:
            while rclpy.ok():
                executor.spin_once(timeout_sec=0.05)
        else:
            rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except RuntimeError:
        # A timer or callback that ran into the shutdown half-way (its context was
        # invalidated by SIGTERM): the node was stopping anyway; anything else is a bug.
        if node.context.ok():
            raise
    finally:
        if on_exit is not None:
            on_exit(node)
        if executor is not None and events:
            executor.shutdown()   # its C++ side lets go of the node's entities first
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


def matching_subscription_qos(node, topic: str, depth: int = 1000):
    """QoS that receives from every current publisher of ``topic``, and what they offer.

    Reliable only if every publisher is, transient local only if every one is
    (what rosbag2 and foxglove_bridge do). Returns ``(QoSProfile, offered)``
    with ``offered`` the publishers' profiles as rosbag2 dicts, or None while
    the topic has no publisher.
    """
    from ..io.bag_writer import qos_from_rclpy

    publishers = node.get_publishers_info_by_topic(topic)
    if not publishers:
        return None
    offered = [qos_from_rclpy(p.qos_profile) for p in publishers]
    reliable = all(q["reliability"] == "reliable" for q in offered)
    latched = all(q["durability"] == "transient_local" for q in offered)
    qos = QoSProfile(depth=depth, history=HistoryPolicy.KEEP_LAST,
                     reliability=ReliabilityPolicy.RELIABLE if reliable
                     else ReliabilityPolicy.BEST_EFFORT,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL if latched
                     else DurabilityPolicy.VOLATILE)
    return qos, offered
