"""Build ``msg_defs/`` into the rosidl interface package ``mt_accuracy_msgs``.

Messages (``msg_defs/msg/*.msg``) and services (``msg_defs/srv/*.srv``) alike: each
must be listed in ``msg_defs/CMakeLists.txt``; one that is not stops the build here.

The package is configured, generated, compiled and installed into the prefix of
the running interpreter (the project's virtual environment), where the
``ros-jazzy-*`` wheels keep ``share/``, ``lib/`` and ``include/``. Afterwards
``from mt_accuracy_msgs.msg import ScaleBatch`` (and ``from mt_accuracy_msgs.srv
import ChangeModel``) works in any process started from that environment, with no
``source`` step.

A content hash of ``msg_defs/`` is stored next to the install; a second run with
nothing changed only checks the hash and returns.

Usage: ``python tools/build_msgs.py [--force]``
"""
from __future__ import annotations

import argparse
import hashlib
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SOURCE = ROOT / "msg_defs"
BUILD = ROOT / "build" / "mt_accuracy_msgs"
PREFIX = Path(sys.prefix)
STAMP = PREFIX / "share" / "mt_accuracy_msgs" / ".source_hash"


def source_hash() -> str:
    digest = hashlib.sha256()
    for path in sorted(SOURCE.rglob("*")):
        if path.is_file():
            digest.update(str(path.relative_to(SOURCE)).encode())
            digest.update(path.read_bytes())
    digest.update(sys.version.encode())
    return digest.hexdigest()


def interfaces() -> dict[str, list[str]]:
    """The interface names per kind ("msg", "srv") that ``msg_defs/`` defines."""
    return {kind: sorted(p.stem for p in (SOURCE / kind).glob(f"*.{kind}"))
            for kind in ("msg", "srv")}


def unlisted() -> list[str]:
    """Interface files that ``msg_defs/CMakeLists.txt`` does not list (never generated)."""
    listed = (SOURCE / "CMakeLists.txt").read_text()
    return [f"{kind}/{name}.{kind}" for kind, names in interfaces().items() for name in names
            if f'"{kind}/{name}.{kind}"' not in listed]


def importable() -> bool:
    """Every message and service of ``msg_defs/`` imports in a fresh interpreter."""
    imports = "; ".join(f"from mt_accuracy_msgs.{kind} import {', '.join(names)}"
                        for kind, names in interfaces().items() if names)
    probe = subprocess.run([sys.executable, "-c", imports], capture_output=True)
    return probe.returncode == 0


def run(cmd: list[str], env: dict[str, str], log: Path) -> None:
    with log.open("w") as handle:
        result = subprocess.run(cmd, env=env, stdout=handle, stderr=subprocess.STDOUT)
    if result.returncode != 0:
        sys.stderr.write(log.read_text()[-6000:])
        raise SystemExit(f"build_msgs: '{' '.join(cmd[:3])} ...' failed; full log in {log}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--force", action="store_true", help="rebuild even if unchanged")
    args = parser.parse_args()

    missing = unlisted()
    if missing:
        raise SystemExit(f"build_msgs: {', '.join(missing)} not listed in "
                         "msg_defs/CMakeLists.txt (rosidl_generate_interfaces)")
    wanted = source_hash()
    if not args.force and STAMP.exists() and STAMP.read_text() == wanted and importable():
        print("mt_accuracy_msgs is up to date")
        return 0

    for tool in ("cmake", "cc"):
        if shutil.which(tool) is None:
            raise SystemExit(f"build_msgs: '{tool}' not found on PATH; "
                             "it is needed to build msg_defs/")

    started = time.monotonic()
    if BUILD.exists():
        shutil.rmtree(BUILD)
    BUILD.mkdir(parents=True)
    env = dict(os.environ)
    env["AMENT_PREFIX_PATH"] = str(PREFIX)
    env["CMAKE_PREFIX_PATH"] = str(PREFIX)
    env["PATH"] = f"{PREFIX / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    run(
        [
            "cmake", "-S", str(SOURCE), "-B", str(BUILD),
            f"-DCMAKE_INSTALL_PREFIX={PREFIX}",
            f"-DPython3_EXECUTABLE={sys.executable}",
            "-DBUILD_TESTING=OFF",
            "-DCMAKE_BUILD_TYPE=Release",
        ],
        env, BUILD / "configure.log",
    )
    run(["cmake", "--build", str(BUILD), "-j", str(os.cpu_count() or 2)], env, BUILD / "build.log")
    run(["cmake", "--install", str(BUILD)], env, BUILD / "install.log")
    if not importable():
        raise SystemExit("build_msgs: installed, but importing mt_accuracy_msgs' messages or "
                         "services still fails")
    STAMP.write_text(wanted)
    print(f"mt_accuracy_msgs built and installed into {PREFIX} "
          f"in {time.monotonic() - started:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
