"""Shared fixtures. ROS traffic of a test run stays on this host and its own domain."""
from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

# Every process started by the tests inherits these: a domain of its own so that
# two test runs (or a developer's demo) on one machine do not hear each other.
os.environ.setdefault("ROS_DOMAIN_ID", str(20 + os.getpid() % 80))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
os.environ.setdefault("AMENT_PREFIX_PATH", sys.prefix)

REPO_ROOT = Path(__file__).resolve().parent.parent
# shared/ sits beside the checkout (as in CI); MT_ACCURACY_SHARED points elsewhere.
SHARED = Path(os.environ.get("MT_ACCURACY_SHARED", REPO_ROOT.parent / "shared"))
SHARED_DATA = SHARED / "data"
SEEDS = SHARED / "seeds"


@pytest.fixture
def rclpy_context():
    """``rclpy.init(); yield; rclpy.shutdown()`` as in rclpy's own tests."""
    import rclpy

    rclpy.init()
    try:
        yield
    finally:
        rclpy.try_shutdown()


@pytest.fixture
def shared_data() -> Path:
    if not SHARED_DATA.is_dir():
        pytest.fail(f"shared data not found at {SHARED_DATA}")
    return SHARED_DATA
