"""CPU of one lockstep main job, process by process, and the end-state figures it gave.

The suite's four main-job tests run ``mt-accuracy demo --lockstep``; their time is the
graph's CPU (data time: a slower host takes longer, it gets the same figures). This runs
the command once and prints JSON: wall time, user + sys CPU of the command and every
node process (``os.wait4``'s rusage covers the command and the nodes it reaped), each
node's CPU sampled from ``/proc`` every 0.2 s (its last 0.2 s is not seen), and the
end-state figures of ``summary.json`` to compare two versions of the code::

    ROS_DOMAIN_ID=95 .venv/bin/python -m bench.demo_cpu --machine kidani_hmc --out /tmp/d
    ROS_DOMAIN_ID=95 PYTHONPATH=/path/to/other/checkout .venv/bin/python -m bench.demo_cpu ...

``--burners N`` runs N CPU-burning processes alongside (the loaded case).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

CLOCK_TICK = os.sysconf("SC_CLK_TCK")


def _children() -> dict[int, list[int]]:
    """pid -> its children's pids, from /proc."""
    tree: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            stat = Path(f"/proc/{entry}/stat").read_text()
        except OSError:
            continue
        parent = int(stat.rsplit(")", 1)[1].split()[1])
        tree.setdefault(parent, []).append(int(entry))
    return tree


def _descendants(pid: int) -> list[tuple[int, int]]:
    """(descendant, its parent) pairs of ``pid``, parents before their children."""
    tree, found, todo = _children(), [], [pid]
    while todo:
        parent = todo.pop(0)
        for child in tree.get(parent, []):
            found.append((child, parent))
            todo.append(child)
    return found


def _cpu_and_name(pid: int) -> tuple[float, str] | None:
    """user + sys CPU [s] of ``pid`` and the node module it runs (None once gone)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        command = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    except OSError:
        return None
    module = next((c.decode() for c in command if c.startswith(b"mt_accuracy_ros.nodes.")),
                  "other")
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICK, module.rsplit(".", 1)[-1]


def end_state(summary: dict) -> dict:
    """The figures the main job's tests read: the last closed-loop state per component."""
    loop = summary.get("closed_loop") or [{}]
    keep = ("model_checks", "compensation_applied", "compensation_stale", "bag_messages",
            "end_state_conformance", "added_version_live_at_s", "failures")
    return {"end_state": loop[-1], **{k: summary.get(k) for k in keep},
            "actions": [a.get("added") for a in summary.get("actions", [])]}


def run(machine: str, out: Path, burners: int) -> dict:
    hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(burners)]
    try:
        started = time.monotonic()
        demo = subprocess.Popen([sys.executable, "-m", "mt_accuracy_ros.cli", "demo", "--lockstep",
                                 "--machine", machine, "--out", str(out)],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        nodes: dict[int, tuple[float, str]] = {}
        printed = []
        reader = threading.Thread(target=lambda: printed.append(demo.stdout.read()))
        reader.start()
        while True:
            # wait4, not poll(): the command's rusage (with its reaped nodes') comes with it.
            pid, status, usage = os.wait4(demo.pid, os.WNOHANG)
            if pid:
                break
            for child, parent in _descendants(demo.pid):
                seen = _cpu_and_name(child)
                if seen is None:
                    continue
                # The name from the first sighting (an exited process's cmdline is empty);
                # a node's helper processes (the monitor's search workers) count as its own.
                name = nodes[child][1] if child in nodes else \
                    nodes[parent][1] if seen[1] == "other" and parent in nodes else seen[1]
                nodes[child] = (seen[0], name)
            time.sleep(0.2)
        wall = time.monotonic() - started
        demo.returncode = os.waitstatus_to_exitcode(status)
        reader.join()
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()
    printed = b"".join(printed).decode(errors="replace")
    per_node: dict[str, float] = {}
    for cpu, name in nodes.values():
        per_node[name] = round(per_node.get(name, 0.0) + cpu, 1)
    summary_path = out / "summary.json"
    summary = json.loads(summary_path.read_text()) if summary_path.is_file() else {}
    return {"machine": machine, "burners": burners, "exit": demo.returncode,
            "wall_s": round(wall, 1),
            "cpu_s": round(usage.ru_utime + usage.ru_stime, 1),
            "node_cpu_s": dict(sorted(per_node.items(), key=lambda kv: -kv[1])),
            "figures": end_state(summary), "printed_tail": printed.splitlines()[-3:]}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--machine", default="kidani_hmc")
    parser.add_argument("--out", default="/tmp/demo_cpu")
    parser.add_argument("--burners", type=int, default=0)
    args = parser.parse_args()
    print(json.dumps(run(args.machine, Path(args.out), args.burners), indent=1, default=str))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
