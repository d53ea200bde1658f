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
