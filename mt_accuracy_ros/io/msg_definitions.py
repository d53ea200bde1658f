"""Message definitions and type hashes of installed interface packages, as rosbag2 stores them.

rosbag2's MCAP storage keeps, per type, a schema with encoding ``ros2msg``
whose data is the type's ``.msg`` text verbatim, followed for each dependency
not yet included (depth first) by a line of 80 ``=``, a line
``MSG: <pkg>/<Type>`` and that type's ``.msg`` text.
"""
from __future__ import annotations

import json
import os
import re
import sys
from functools import lru_cache
from pathlib import Path

from ..core.errors import BagError

SEPARATOR = "=" * 80
_PRIMITIVES = {"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
               "int32", "uint32", "int64", "uint64", "string", "wstring"}


def _prefixes() -> list[Path]:
    paths = [Path(p) for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    if Path(sys.prefix) not in paths:
        paths.append(Path(sys.prefix))
    return paths


def split_type(type_name: str) -> tuple[str, str]:
    """``pkg/msg/Type`` or ``pkg/Type`` -> (pkg, Type)."""
    parts = type_name.split("/")
    if len(parts) == 3 and parts[1] == "msg":
        return parts[0], parts[2]
    if len(parts) == 2:
        return parts[0], parts[1]
    raise BagError(f"not a message type name: {type_name!r} (expected pkg/msg/Type)")


def _share_file(package: str, name: str, suffix: str) -> Path:
    for prefix in _prefixes():
        candidate = prefix / "share" / package / "msg" / f"{name}{suffix}"
        if candidate.is_file():
            return candidate
    raise BagError(f"definition of {package}/msg/{name} not installed "
                   f"(looked for share/{package}/msg/{name}{suffix} in {_prefixes()})")


@lru_cache(maxsize=None)
def msg_text(type_name: str) -> str:
    """The ``.msg`` text of an installed type."""
    package, name = split_type(type_name)
    return _share_file(package, name, ".msg").read_text()


def _dependencies(package: str, text: str) -> list[str]:
    found = []
    for line in text.splitlines():
        tokens = line.split("#", 1)[0].split()
        if len(tokens) < 2:
            continue
        field_type = tokens[0]
        if "=" in " ".join(tokens[1:]):
            continue  # a constant (bounded types like string<=8 keep their '=' in tokens[0])
        base = re.sub(r"\[.*\]$", "", field_type)
        base = re.sub(r"<=\d+$", "", base)
        if base in _PRIMITIVES or base.startswith(("string<", "wstring<")):
            continue
        if base == "Header":
            found.append("std_msgs/Header")
        elif "/" in base:
            found.append(base)
        else:
            found.append(f"{package}/{base}")
    return found


@lru_cache(maxsize=None)
def schema_text(type_name: str) -> str:
    """rosbag2's ``ros2msg`` schema text of a type (the type and its dependencies)."""
    package, name = split_type(type_name)
    parts = [msg_text(type_name).rstrip("\n")]
    seen = {f"{package}/{name}"}

    def visit(pkg: str, text: str) -> None:
        for dependency in _dependencies(pkg, text):
            dep_pkg, dep_name = split_type(dependency)
            key = f"{dep_pkg}/{dep_name}"
            if key in seen:
                continue
            seen.add(key)
            dep_text = msg_text(key)
            parts.append(f"{SEPARATOR}\nMSG: {key}\n{dep_text.rstrip(chr(10))}")
            visit(dep_pkg, dep_text)

    visit(package, parts[0])
    return "\n".join(parts) + "\n"


@lru_cache(maxsize=None)
def type_hash(type_name: str) -> str:
    """``RIHS01_...`` hash of a type, from ``share/<pkg>/msg/<T>.json``."""
    package, name = split_type(type_name)
    data = json.loads(_share_file(package, name, ".json").read_text())
    wanted = f"{package}/msg/{name}"
    for entry in data.get("type_hashes", []):
        if entry.get("type_name") == wanted:
            return entry["hash_string"]
    raise BagError(f"{wanted}: no type hash in its .json description")
