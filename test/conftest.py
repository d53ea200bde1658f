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
# studies/ (outside the installed package) imports from the repository root.
if str(REPO_ROOT) not in sys.path:
    sys.path.insert(0, str(REPO_ROOT))
#: Third-party data the tests read, copied into the repository with its licences:
#: a clone needs nothing beside it.
DATA = REPO_ROOT / "data"


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
def data_dir() -> Path:
    """The repository's ``data/`` folder (fl_thermal, rosbag2 samples)."""
    return DATA
