"""The layers of the package, checked on the source: who may import whom.

* the numerical core imports no ROS, no simulator, no node, no I/O;
* the simulator imports no node and no ROS client library;
* only the nodes that *are* the virtual machine import the simulator;
* nothing installed imports the studies or the benchmarks, and neither is installed.
"""
from __future__ import annotations

import ast
import sysconfig
from pathlib import Path

import pytest

from conftest import REPO_ROOT

PACKAGE = REPO_ROOT / "mt_accuracy_ros"
ROS_ROOTS = ("rclpy", "rosidl", "rcl_interfaces", "builtin_interfaces", "std_msgs", "sensor_msgs",
             "diagnostic_msgs", "rosgraph_msgs", "std_srvs", "geometry_msgs", "mt_accuracy_msgs")
#: The nodes that stand in for the machine's hardware (and their shared helper).
VIRTUAL_MACHINE_NODES = {"encoder_publisher", "temperature_publisher", "_scenario"}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(REPO_ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path) -> set[str]:
    """Absolute names of every module ``path`` imports (top level or inside functions)."""
    module = _module_name(path)
    package = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            name = ".".join(base + ([node.module] if node.module else []))
            found.add(name)
            found.update(f"{name}.{alias.name}" for alias in node.names)
    return found


def _sources(subpackage: str) -> list[Path]:
    return sorted((PACKAGE / subpackage).rglob("*.py"))


def _offending(paths, forbidden_prefixes) -> dict[str, list[str]]:
    bad = {}
    for path in paths:
        hits = sorted(name for name in imports_of(path)
                      if any(name == p or name.startswith(p + ".") for p in forbidden_prefixes))
        if hits:
            bad[str(path.relative_to(REPO_ROOT))] = hits
    return bad


def test_import_resolution_sees_relative_imports():
    # Not vacuous: the checker must see the simulator in a virtual-machine node.
    assert "mt_accuracy_ros.sim.machine_tool" in imports_of(
        PACKAGE / "nodes" / "encoder_publisher.py")
    assert "mt_accuracy_ros.core.errors" in imports_of(PACKAGE / "core" / "scales" / "knn.py")


def test_core_imports_no_ros_simulator_node_or_io():
    forbidden = ROS_ROOTS + ("mt_accuracy_ros.sim", "mt_accuracy_ros.nodes", "mt_accuracy_ros.io",
                             "mt_accuracy_ros.commands", "mt_accuracy_ros.cli",
                             "mt_accuracy_ros.report", "studies", "bench")
    assert _offending(_sources("core"), forbidden) == {}


def test_the_command_floor_is_one_room():
    """What ``mt-accuracy`` runs lives in commands/; the top level holds the command line,
    the allocator setting and the package's rooms (issue 28)."""
    top = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert top == ["__init__.py", "allocator.py", "cli.py"]
    commands = sorted(p.stem for p in (PACKAGE / "commands").glob("*.py"))
    assert commands == ["__init__", "bags", "check", "check_log", "check_result",
                        "check_timing", "check_walk", "demo", "fleet", "iso230", "model_tools",
                        "play", "processes", "record", "rotary_tools", "simulate", "topic_tools"]
    # Nodes run on real machines: none of them imports a command.
    assert _offending(_sources("nodes"), ("mt_accuracy_ros.commands", "mt_accuracy_ros.cli")) \
        == {}


def test_core_is_split_by_domain_and_each_subpackage_says_what_it_holds():
    flat = sorted(p.name for p in (PACKAGE / "core").glob("*.py") if p.name != "__init__.py")
    assert flat == ["errors.py", "validation.py"]
    for sub in ("scales", "kinematics", "thermal", "compensation", "effects", "workbench",
                "inputs", "fleet"):
        init = PACKAGE / "core" / sub / "__init__.py"
        doc = ast.get_docstring(ast.parse(init.read_text()))
        assert doc and len(doc.splitlines()) >= 3, f"{init} needs a docstring saying what it holds"


def test_only_the_fleet_command_imports_dask():
    """Issue 42: Dask is for ``mt-accuracy fleet``; no other command, node or core module
    needs it installed (nor pays its import)."""
    hits = _offending(sorted(PACKAGE.rglob("*.py")), ("dask", "distributed"))
    assert set(hits) == {"mt_accuracy_ros/commands/fleet.py"}


def test_simulator_imports_no_node_and_no_ros_client():
    assert _offending(_sources("sim"), ("mt_accuracy_ros.nodes", "studies", "bench")) == {}
    # CDR serialization for its bag export is fine; the graph (nodes, executors) is not.
    graph = {path: [n for n in names if n.startswith("rclpy") and
                    not n.startswith("rclpy.serialization")]
             for path, names in _offending(_sources("sim"), ("rclpy",)).items()}
    assert {path: names for path, names in graph.items() if names} == {}


def test_the_simulators_truth_shares_no_physics_with_the_model_it_judges():
    """Issue 38: the virtual machine makes its truth with its own rigid bodies - no module
    of the simulator imports the kinematic chain, its HTMs, the error model or the effect
    catalogue (the machine description, which is data, it may read)."""
    physics = ("mt_accuracy_ros.core.kinematics.chain", "mt_accuracy_ros.core.kinematics.htm",
               "mt_accuracy_ros.core.compensation", "mt_accuracy_ros.core.effects",
               "mt_accuracy_ros.core.workbench")
    assert _offending(_sources("sim"), physics) == {}


@pytest.mark.parametrize("path", _sources("nodes"), ids=lambda p: p.stem)
def test_only_the_virtual_machine_nodes_import_the_simulator(path):
    hits = _offending([path], ("mt_accuracy_ros.sim",))
    if path.stem in VIRTUAL_MACHINE_NODES:
        return
    assert hits == {}, f"{path.stem} must run on a real machine without the simulator"


def test_installed_library_imports_neither_studies_nor_bench():
    assert _offending(sorted(PACKAGE.rglob("*.py")), ("studies", "bench")) == {}


def test_studies_and_bench_are_not_installed():
    site = Path(sysconfig.get_paths()["purelib"])
    for name in ("studies", "bench", "test"):
        assert not (site / name).exists(), f"{name}/ must not be installed as a package"
    assert (site / "mt_accuracy_ros" / "templates" / "report.html.j2").is_file()


def test_one_module_writes_html():
    writers = [p for p in PACKAGE.rglob("*.py")
               if "<html" in p.read_text().lower() or "<table" in p.read_text().lower()]
    assert writers == [], "HTML lives in templates/, rendered by report.py"


def test_the_independent_generators_import_nothing_of_the_package():
    """The proofs' data must not come from the code they judge (issue 39): the foreign
    machine, the Cartesian surveys, the five-axis R-test, the multi-day thermal logs
    (issue 40) and the shapes they share import
    no module of mt_accuracy_ros, directly or through another study."""
    studies = REPO_ROOT / "studies"
    generators = ["foreign_machine.py", "cartesian_surveys.py", "five_axis_rtest.py",
                  "multirun_logs.py", "shapes.py", "convention_surveys.py"]
    assert _offending([studies / name for name in generators], ("mt_accuracy_ros",)) == {}
    # Not vacuous: the trial runners beside them do use the package.
    assert _offending([studies / "catalogue_trials.py"], ("mt_accuracy_ros",))
    shared = {name for path in generators for name in imports_of(studies / path)
              if name.startswith("studies")}
    assert all(name.startswith("studies.shapes") for name in shared), shared


def _imports_through_studies(path: Path) -> set[str]:
    """Every module ``path`` imports, following the studies it imports transitively."""
    seen, todo, found = set(), [path], set()
    while todo:
        current = todo.pop()
        if current in seen:
            continue
        seen.add(current)
        names = imports_of(current)
        found |= names
        for name in names:
            if name.startswith("studies."):
                candidate = REPO_ROOT / Path(*name.split(".")).with_suffix(".py")
                if candidate.is_file():
                    todo.append(candidate)
    return found


def test_the_convention_generator_reaches_nothing_of_the_package_by_any_path():
    """The randomized-convention generator's data judge the physics: nothing of the
    package may reach it, directly, through another study, or by a module named at run
    time (importlib, __import__)."""
    path = REPO_ROOT / "studies" / "convention_surveys.py"
    reached = _imports_through_studies(path)
    assert not [n for n in reached if n == "mt_accuracy_ros" or n.startswith("mt_accuracy_ros.")]
    assert not [n for n in reached if n == "importlib" or n.startswith("importlib.")]
    calls = {node.func.id for node in ast.walk(ast.parse(path.read_text()))
             if isinstance(node, ast.Call) and isinstance(node.func, ast.Name)}
    assert not calls & {"__import__", "exec", "eval"}
    # Not vacuous: the follower sees a study's own study imports.
    assert "studies.shapes" in _imports_through_studies(REPO_ROOT / "studies" /
                                                        "foreign_machine.py")
