"""Small helpers for tests that drive a real multi-process graph."""
from __future__ import annotations

import time


def spin_until(node, condition, timeout_s: float = 30.0, step_s: float = 0.05) -> bool:
    """Spin ``node`` until ``condition()`` holds; a guard against a hung graph."""
    import rclpy

    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return True
        rclpy.spin_once(node, timeout_sec=step_s)
    return bool(condition())


def spin_for(node, seconds: float) -> None:
    import rclpy

    end = time.monotonic() + seconds
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.02)


def call_service(node, client, request, timeout_s: float = 60.0, attempt_s: float = 5.0):
    """Call a service until it answers; the response.

    A request sent before the server has matched the client's response reader is
    dropped by the RMW ("failed to send response (timeout)"), which a loaded host
    makes likely: asking again is the client's job, as ``ros2 param get`` does on
    a slow graph. Only idempotent requests may be sent this way. Every request sent
    stays awaited and the first answer counts: a server slower than ``attempt_s`` (a
    model gate on a loaded host) answers its requests one after the other, and a
    client that kept only its newest would always wait behind the ones it gave up.
    """
    deadline = time.monotonic() + timeout_s
    assert client.wait_for_service(timeout_sec=timeout_s), f"no service {client.srv_name}"
    futures = []
    try:
        while time.monotonic() < deadline:
            futures.append(client.call_async(request))
            if spin_until(node, lambda: any(f.done() for f in futures),
                          timeout_s=min(attempt_s, max(0.0, deadline - time.monotonic()))):
                return next(f for f in futures if f.done()).result()
    finally:
        for future in futures:
            if not future.done():
                client.remove_pending_request(future)
    raise AssertionError(f"{client.srv_name} did not answer in {timeout_s} s")


def set_parameter_again_until_answered(node, target: str, name: str, value,
                                       timeout_s: float = 60.0) -> tuple[bool, str]:
    """Set a parameter of ``target`` through its service, asking again while unanswered
    (see ``call_service``): only for settings whose repetition changes nothing - a
    refused value, or the same plain value twice. (accepted, reason)."""
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter

    client = node.create_client(SetParameters, f"{target}/set_parameters")
    try:
        request = SetParameters.Request(
            parameters=[Parameter(name, value=value).to_parameter_msg()])
        result = call_service(node, client, request, timeout_s=timeout_s).results[0]
        return bool(result.successful), str(result.reason)
    finally:
        node.destroy_client(client)


def scale_batch(first_index, stamp_ns, period, n=50):
    """A ScaleBatch of two scale channels and the X, Y, Z command, ``n`` samples of
    constant readings: input for the nodes' bad-input tests."""
    from mt_accuracy_msgs.msg import ScaleBatch
    from mt_accuracy_ros.io.fields import nanoseconds_to_stamp, pack_float64

    message = ScaleBatch()
    message.header.stamp = nanoseconds_to_stamp(stamp_ns)
    message.first_sample_index = first_index
    message.sample_period = period
    message.channel_names = ["x1", "x2"]
    message.positions = pack_float64([0.1] * (2 * n))
    message.command_axes = ["x", "y", "z"]
    message.command_positions = pack_float64([0.1, 0.2, -0.1] * n)
    return message
