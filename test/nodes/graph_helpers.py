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
    a slow graph. Only idempotent requests may be sent this way.
    """
    deadline = time.monotonic() + timeout_s
    assert client.wait_for_service(timeout_sec=timeout_s), f"no service {client.srv_name}"
    while time.monotonic() < deadline:
        future = client.call_async(request)
        if spin_until(node, future.done, timeout_s=attempt_s):
            return future.result()
        client.remove_pending_request(future)
    raise AssertionError(f"{client.srv_name} did not answer in {timeout_s} s")
