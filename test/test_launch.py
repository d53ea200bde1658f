"""launch/mt_accuracy.launch.xml, checked without the launch package (not on PyPI):
every executable, parameter, parameter file and remapping it names exists, and it is
installed where ``ros2 launch`` looks."""
from __future__ import annotations

import ast
import re
import sysconfig
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import yaml

from conftest import REPO_ROOT

LAUNCH = REPO_ROOT / "launch" / "mt_accuracy.launch.xml"
PACKAGE = "mt_accuracy_ros"


def _entry_points() -> dict[str, str]:
    tree = ast.parse((REPO_ROOT / "setup.py").read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == \
                "NODE_ENTRY_POINTS":
            return ast.literal_eval(node.value)
    raise AssertionError("setup.py has no NODE_ENTRY_POINTS")


def _module_source(executable: str) -> str:
    module = _entry_points()[executable].split(":")[0]
    return (REPO_ROOT / (module.replace(".", "/") + ".py")).read_text()


def _declared(executable: str) -> set[str]:
    """Parameters a node declares: in its module and the helpers every node shares."""
    sources = [_module_source(executable)] + [
        (REPO_ROOT / PACKAGE / "nodes" / name).read_text()
        for name in ("_priority.py", "_cnc_input.py", "_model_inputs.py", "_scenario.py")]
    return {name for source in sources
            for name in re.findall(r"declare_parameter\(\s*\"(\w+)\"", source)}


def _arguments(root) -> dict[str, str]:
    return {arg.get("name"): arg.get("default") for arg in root.iter("arg")}


def _resolve(text: str, arguments: dict[str, str], share: Path) -> str:
    text = text.replace(f"$(find-pkg-share {PACKAGE})", str(share))
    return re.sub(r"\$\(var (\w+)\)", lambda m: _resolve(arguments[m.group(1)], arguments,
                                                         share), text)


def test_every_node_parameter_file_and_remapping_it_names_exists():
    root = ElementTree.parse(LAUNCH).getroot()
    assert root.tag == "launch"
    arguments = _arguments(root)
    assert {"namespace", "config", "bag", "record"} <= set(arguments)
    # One namespace argument puts the whole graph under it (a second machine).
    (push,) = root.iter("push_ros_namespace")
    assert push.get("namespace") == "$(var namespace)"
    nodes = list(root.iter("node"))
    executables = [node.get("exec") for node in nodes]
    # The graph the main job starts (the demo), each node once.
    assert sorted(executables) == sorted(["encoder_publisher", "temperature_publisher",
                                          "yaw_estimator", "compensation_broadcaster",
                                          "model_monitor", "recorder"])
    entry_points = _entry_points()
    share = REPO_ROOT          # the repository's layout is the share directory's
    for node in nodes:
        executable = node.get("exec")
        assert node.get("pkg") == PACKAGE and executable in entry_points
        assert node.get("name") == executable
        declared = _declared(executable)
        for param in node.iter("param"):
            if param.get("from"):
                path = Path(_resolve(param.get("from"), arguments, share))
                assert path.is_file(), path
                content = yaml.safe_load(path.read_text())
                key = f"/**/{executable}"
                assert key in content, f"{path.name} has nothing for {executable}"
                unknown = set(content[key]["ros__parameters"]) - declared
                assert not unknown, f"{executable} declares no {sorted(unknown)}"
            else:
                assert param.get("name") in declared, (executable, param.get("name"))
        for remap in node.iter("remap"):
            topic = remap.get("from").lstrip("/")
            assert f'"{topic}"' in _module_source(executable), (executable, topic)
    # Every node of the parameter file is started here.
    content = yaml.safe_load(Path(_resolve(arguments["config"], arguments, share)).read_text())
    assert {key.split("/")[-1] for key in content} <= set(executables)


def test_the_launch_file_is_installed_where_ros2_launch_looks():
    share = Path(sysconfig.get_paths()["data"]) / "share" / PACKAGE
    installed = share / "launch" / LAUNCH.name
    assert installed.is_file() and installed.read_text() == LAUNCH.read_text()
    assert (share / "config" / "demo.yaml").is_file()
