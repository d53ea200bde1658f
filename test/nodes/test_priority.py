"""The compensation path's niceness: every thread of the node's process takes it (DDS's
threads too, and threads started later), /diagnostics says what it runs at, and a host
that does not permit it gets a warning, not a dead node."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from graph_helpers import spin_until
from mt_accuracy_ros.commands.processes import start_node

CHILD = """
import os, sys, threading
from mt_accuracy_ros.nodes._priority import take_niceness
if sys.argv[1] == "nobody":
    os.setgroups([]); os.setgid(65534); os.setuid(65534)     # no CAP_SYS_NICE any more
early = threading.Thread(target=threading.Event().wait, args=(5,), daemon=True)
early.start()
taken, text = take_niceness(int(sys.argv[2]))
late = {}
def report():
    late["nice"] = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
thread = threading.Thread(target=report); thread.start(); thread.join()
print(taken, os.getpriority(os.PRIO_PROCESS, early.native_id), late["nice"],
      os.getpriority(os.PRIO_PROCESS, 0), text, sep="|")
"""

root = pytest.mark.skipif(os.geteuid() != 0, reason="a negative niceness needs CAP_SYS_NICE")


def _child(user: str, niceness: int) -> list[str]:
    out = subprocess.run([sys.executable, "-c", CHILD, user, str(niceness)],
                         capture_output=True, text=True, check=True, timeout=60)
    return out.stdout.strip().split("|")


def _thread_niceness(pid: int) -> list[int]:
    """Niceness of every thread of ``pid``: field 19 of /proc/<pid>/task/<tid>/stat."""
    out = []
    for stat in Path(f"/proc/{pid}/task").glob("*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue        # a thread that ended meanwhile
        out.append(int(fields[16]))
    return out


@root
def test_every_thread_takes_the_niceness_and_later_threads_inherit_it():
    taken, early, late, main, text = _child("root", -7)
    assert taken == "True" and (early, late, main) == ("-7", "-7", "-7")
    assert text.startswith("niceness -7 (")


def test_without_the_right_the_process_runs_on_and_says_why():
    if os.geteuid() == 0:
        taken, early, late, main, text = _child("nobody", -7)
    else:
        taken, early, late, main, text = _child("self", -7)
    assert taken == "False" and main == early == late == "0"
    assert "not permitted" in text and "CAP_SYS_NICE" in text


def test_a_niceness_outside_linux_range_is_refused():
    from mt_accuracy_ros.nodes._priority import take_niceness

    with pytest.raises(ValueError, match="-20..19"):
        take_niceness(-21)


@root
def test_a_node_on_the_path_runs_at_its_niceness_and_reports_it(rclpy_context):
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray

    node = rclpy.create_node("priority_listener")
    notes = []

    def on_diagnostics(message):
        for status in message.status:
            if status.name == "/compensation_broadcaster: delivery":
                notes.extend(v.value for v in status.values if v.key == "scheduling")

    node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, 50)
    broadcaster = start_node("compensation_broadcaster", {"niceness": -6}, quiet=True)
    try:
        assert spin_until(node, lambda: bool(notes), 60)
        assert notes[-1].startswith("niceness -6 (")
        # Every thread of the real process - its executor and DDS's - runs at -6.
        pid = broadcaster.popen.pid
        niceness = _thread_niceness(pid)
        assert len(niceness) >= 2 and set(niceness) == {-6}
        # Its model gate (a worker process, no deadline) does not keep the path's priority.
        # (Its worker sets that as it starts: waited for, bounded.)
        def gate_at_zero():
            children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
            gates = [int(c) for c in children if "spawn_main" in
                     Path(f"/proc/{c}/cmdline").read_text(errors="replace")]
            return bool(gates) and all(set(_thread_niceness(c)) == {0} for c in gates)

        assert spin_until(node, gate_at_zero, 60)
    finally:
        broadcaster.stop()
        node.destroy_node()
