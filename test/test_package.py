"""The installable package: package.xml, setup.py, installed files, imports."""
from __future__ import annotations

import ast
import importlib
import re
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO_ROOT


def _setup_entry_points() -> dict[str, str]:
    tree = ast.parse((REPO_ROOT / "setup.py").read_text())
    for node in ast.walk(tree):
        if (isinstance(node, ast.Assign)
                and getattr(node.targets[0], "id", "") == "NODE_ENTRY_POINTS"):
            return ast.literal_eval(node.value)
    raise AssertionError("setup.py has no NODE_ENTRY_POINTS table")


def test_package_xml_is_format_3_ament_python():
    from catkin_pkg.package import parse_package

    package = parse_package(str(REPO_ROOT / "package.xml"))
    assert package.name == "mt_accuracy_ros"
    assert package.package_format == 3
    assert package.get_build_type() == "ament_python"
    exec_depends = {dep.name for dep in package.exec_depends}
    assert {"rclpy", "mt_accuracy_msgs", "python3-numpy", "python3-scipy"} <= exec_depends


def test_every_message_package_imported_is_an_exec_depend():
    from catkin_pkg.package import parse_package

    exec_depends = {dep.name for dep in parse_package(str(REPO_ROOT / "package.xml")).exec_depends}
    imported = set()
    pattern = re.compile(r"^\s*(?:from|import)\s+(\w+_(?:msgs|interfaces))\b", re.MULTILINE)
    for path in (REPO_ROOT / "mt_accuracy_ros").rglob("*.py"):
        imported.update(pattern.findall(path.read_text()))
    assert imported, "no message package import found - the scan is broken"
    assert imported <= exec_depends, f"imported but not declared: {imported - exec_depends}"


def test_package_xml_version_matches_setup_py():
    from catkin_pkg.package import parse_package

    package = parse_package(str(REPO_ROOT / "package.xml"))
    setup_text = (REPO_ROOT / "setup.py").read_text()
    assert f'version="{package.version}"' in setup_text


def test_installed_share_files_are_found_through_the_ament_index():
    from ament_index_python.packages import get_package_share_directory

    share = Path(get_package_share_directory("mt_accuracy_ros"))
    assert (share / "package.xml").read_text() == (REPO_ROOT / "package.xml").read_text()
    installed_configs = {p.name for p in (share / "config").glob("*.yaml")}
    assert installed_configs == {p.name for p in (REPO_ROOT / "config").glob("*.yaml")}
    assert Path(get_package_share_directory("mt_accuracy_msgs"), "msg", "ScaleBatch.msg").is_file()


@pytest.mark.parametrize("name,target", sorted(_setup_entry_points().items()))
def test_console_script_targets_exist_and_are_installed(name, target):
    module_name, function = target.split(":")
    module = importlib.import_module(module_name)
    assert callable(getattr(module, function))
    script = Path(sys.prefix, "bin", name)
    assert script.is_file(), f"console script {name} not installed in {script.parent}"
    from mt_accuracy_ros.commands.processes import NODE_MODULES

    assert NODE_MODULES[name] == module_name


def test_core_imports_without_ros():
    code = ("import sys, importlib, pkgutil, mt_accuracy_ros.core as c\n"
            "for m in pkgutil.walk_packages(c.__path__, 'mt_accuracy_ros.core.'):\n"
            "    importlib.import_module(m.name)\n"
            "import mt_accuracy_ros.sim\n"
            "bad = [m for m in sys.modules\n"
            "       if m.startswith(('rclpy', 'rosidl', 'mt_accuracy_msgs'))]\n"
            "assert not bad, bad\n")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=REPO_ROOT)


def test_interface_package_imports_in_a_clean_environment():
    # No AMENT_PREFIX_PATH, no LD_LIBRARY_PATH: the venv alone must suffice.
    env = {"PATH": "/usr/bin:/bin", "HOME": "/tmp"}
    code = ("from mt_accuracy_msgs.msg import ScaleBatch, ModelCheck; "
            "print(ScaleBatch().sample_period)")
    result = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                            cwd="/")
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "0.0"
