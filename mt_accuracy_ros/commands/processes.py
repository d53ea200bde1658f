"""Start nodes of this package as separate processes (a small stand-in for ros2 launch)."""
from __future__ import annotations

import atexit
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

#: node name -> module, the same table as setup.py's console_scripts.
NODE_MODULES = {
    "encoder_publisher": "mt_accuracy_ros.nodes.encoder_publisher",
    "temperature_publisher": "mt_accuracy_ros.nodes.temperature_publisher",
    "yaw_estimator": "mt_accuracy_ros.nodes.yaw_estimator",
    "compensation_broadcaster": "mt_accuracy_ros.nodes.compensation_broadcaster",
    "model_monitor": "mt_accuracy_ros.nodes.model_monitor",
    "recorder": "mt_accuracy_ros.nodes.recorder",
    "bag_player": "mt_accuracy_ros.nodes.player",
    "foxglove_bridge": "mt_accuracy_ros.nodes.foxglove_bridge",
    "cnc_bridge": "mt_accuracy_ros.nodes.cnc_bridge",
}


def format_parameter(value) -> str:
    """A parameter value in the YAML form ``--ros-args -p name:=value`` expects."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return json.dumps(list(value))
    return str(value)


def ros_arguments(parameters: Mapping[str, object] | None = None, namespace: str | None = None,
                  params_file: str | None = None,
                  remappings: Mapping[str, str] | None = None) -> list[str]:
    """The ``--ros-args`` part of a node command line."""
    args = ["--ros-args"]
    if params_file:
        args += ["--params-file", params_file]
    for name, value in (parameters or {}).items():
        args += ["-p", f"{name}:={format_parameter(value)}"]
    if namespace:
        args += ["-r", f"__ns:={namespace}"]
    for source, target in (remappings or {}).items():
        args += ["-r", f"{source}:={target}"]
    return args


@dataclass
class NodeProcess:
    """One node running in its own process."""

    name: str
    popen: subprocess.Popen
    command: list[str] = field(default_factory=list)

    def stop(self, timeout_s: float = 10.0, while_waiting=None) -> int:
        """SIGINT, then SIGKILL after ``timeout_s``; returns the exit code.
        ``while_waiting()``, when given, is called every 0.05 s until the process ends
        (a command's progress line while a node writes its backlog)."""
        if self.popen.poll() is None:
            self.popen.send_signal(signal.SIGINT)
            deadline = time.monotonic() + timeout_s
            while True:
                step = timeout_s if while_waiting is None else 0.05
                try:
                    self.popen.wait(timeout=max(0.0, min(step, deadline - time.monotonic())))
                    break
                except subprocess.TimeoutExpired:
                    if time.monotonic() >= deadline:
                        self.popen.kill()
                        self.popen.wait()
                        break
                    if while_waiting is not None:
                        while_waiting()
        return self.popen.returncode


#: Every node process started here; whatever is still running when this interpreter
#: exits (a failed test, an interrupted demo) is stopped rather than left behind.
_STARTED: list["NodeProcess"] = []


@atexit.register
def _stop_leftovers() -> None:
    for process in _STARTED:
        if process.popen.poll() is None:
            process.stop(timeout_s=3.0)


def start_node(name: str, parameters: Mapping[str, object] | None = None, *,
               namespace: str | None = None, params_file: str | None = None,
               remappings: Mapping[str, str] | None = None,
               extra_args: Sequence[str] = (), env: Mapping[str, str] | None = None,
               quiet: bool = False) -> NodeProcess:
    """Start node ``name`` (a key of :data:`NODE_MODULES`) in a new process."""
    if name not in NODE_MODULES:
        raise KeyError(f"unknown node '{name}'; known: {', '.join(sorted(NODE_MODULES))}")
    command = [sys.executable, "-m", NODE_MODULES[name], *extra_args,
               *ros_arguments(parameters, namespace, params_file, remappings)]
    process_env = dict(os.environ)
    process_env.update(env or {})
    output = subprocess.DEVNULL if quiet else None
    popen = subprocess.Popen(command, env=process_env, stdout=output, stderr=output)
    process = NodeProcess(name=name, popen=popen, command=command)
    _STARTED[:] = [p for p in _STARTED if p.popen.poll() is None] + [process]
    return process
