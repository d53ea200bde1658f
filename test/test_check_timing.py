"""Whether the monitor's checks kept up (``commands/check_timing.py``): each check's
latency against the period after which the next falls due."""
from __future__ import annotations

import math

import pytest

from mt_accuracy_ros.commands.check_timing import check_timeliness, timeliness_line


def test_a_check_published_after_the_next_was_due_is_late():
    timing = check_timeliness([10.0, 21.1, 32.2], [15.0, 33.0, 43.3], period_s=11.1)
    assert timing["latency_s"] == [5.0, 11.9, 11.1]
    # 11.9 s > 11.1 s: late; exactly the period still comes before the next is due.
    assert timing["checks"] == 3 and timing["late"] == 1
    assert timing["latency_median_s"] == pytest.approx(11.1)
    assert timing["latency_max_s"] == pytest.approx(11.9)
    line = timeliness_line(timing, rate_factor=3.0)
    assert "1 of 3 LATE" in line and "4.0 s wall at 3x" in line


def test_every_check_on_time_and_none_at_all():
    timing = check_timeliness([10.0, 21.1], [12.0, 24.1], period_s=11.1)
    assert timing["late"] == 0
    assert timeliness_line(timing, 3.0).endswith("every check on time")
    timing.update(search_wall_s=[0.5, 0.7], search_cpu_s=[0.25, 0.35])
    assert timeliness_line(timing, 3.0).endswith(
        "every check on time; each search took 0.30 s of CPU (median; at most 0.35 s) in "
        "0.60 s wall")
    empty = check_timeliness([], [], period_s=11.1)
    assert empty["checks"] == 0 and math.isnan(empty["latency_max_s"])
    assert timeliness_line(empty, 3.0) == "model checks: none published"


def test_bad_input_is_one_clear_error():
    with pytest.raises(ValueError, match="2 check stamps but 1 arrival"):
        check_timeliness([1.0, 2.0], [3.0], period_s=11.1)
    with pytest.raises(ValueError, match="period must be positive"):
        check_timeliness([1.0], [3.0], period_s=0.0)
