"""Vectorised volumetric error map vs a plain per-point 4x4 loop, same run.

Both evaluate the exact HTM chain of a machine with non-zero error functions
(all six motion errors per axis as tables/polynomials, squareness). The loop
runs on a subset (it would take minutes at 1,000,000 points) and is compared
per point; the two results are checked to agree on that subset.

Usage: ``python -m bench.volumetric_map [--n 1000000] [--loop-n 5000] [--machine kidani_hmc]``
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np

from mt_accuracy_ros.core.kinematics.htm import error_htm_exact, rotation, translation
from mt_accuracy_ros.core.kinematics.chain import KinematicModel, volumetric_map
from mt_accuracy_ros.core.kinematics.machine import load_machine, machine_from_dict


def machine_with_errors(name: str):
    base = load_machine(name)
    data = {"name": base.name, "chain": base.chain, "tool": base.tool.tolist(),
            "workpiece": base.workpiece.tolist(), "axes": {}}
    for letter in base.axis_order:
        axis = base.axes[letter]
        low, high = axis.stroke
        grid = np.linspace(low, high, 21)
        errors = {}
        for i, component in enumerate("XYZABC"):
            scale = 5e-6 if component in "XYZ" else 10e-6
            errors[f"E{component}{letter}"] = (
                {"table": {"positions": grid.tolist(),
                           "values": (scale * np.sin(3 * grid + i)).tolist()}}
                if i % 2 else {"polynomial": [scale * 0.1, scale, -scale]})
        data["axes"][letter] = {"stroke": [low, high], "offset": axis.offset.tolist(),
                                "errors": errors,
                                "location_errors": {"EC0" + letter: 1e-5} if letter in "YZ" else {}}
    return machine_from_dict(data, "bench")


def per_point(model: KinematicModel, positions: dict, n: int) -> np.ndarray:
    m = model.machine
    out = np.empty((n, 3))
    for i in range(n):
        rel = []
        for axes, end in ((m.tool_branch, m.tool), (m.workpiece_branch, m.workpiece)):
            act, nom = np.eye(4), np.eye(4)
            parent = np.zeros(3)
            for a in axes:
                spec = m.axes[a]
                q = positions[a][i]
                move = (rotation("xyz"[spec.direction], q) if spec.is_rotary
                        else translation(*(np.eye(3)[spec.direction] * q)))
                loc = np.array([spec.location_errors.get(c, 0.0) for c in "XYZABC"])
                err = np.array([float(spec.motion_errors[c](q)) for c in "XYZABC"])
                act = (act @ translation(*parent) @ error_htm_exact(loc) @ move
                       @ error_htm_exact(err))
                nom = nom @ translation(*parent) @ move
                parent = spec.offset
            point = np.append(parent + end, 1.0)
            rel.append((act @ point)[:3] - (nom @ point)[:3])
        out[i] = rel[0] - rel[1]
    return out


def run(n: int, loop_n: int, machine: str) -> dict:
    model = KinematicModel(machine_with_errors(machine))
    rng = np.random.default_rng(0)
    positions = {a: rng.uniform(*model.machine.axes[a].stroke, n) for a in model.machine.axis_order}
    volumetric_map(model, {a: v[:1000] for a, v in positions.items()})  # warm-up
    started = time.perf_counter()
    fast = volumetric_map(model, positions)
    fast_s = time.perf_counter() - started
    started = time.perf_counter()
    slow = per_point(model, positions, loop_n)
    loop_s = time.perf_counter() - started
    per_point_fast = fast_s / n
    per_point_loop = loop_s / loop_n
    return {"machine": machine, "n": n, "vectorised_s": fast_s, "loop_points": loop_n,
            "loop_s": loop_s, "vectorised_us_per_point": per_point_fast * 1e6,
            "loop_us_per_point": per_point_loop * 1e6,
            "speedup": per_point_loop / per_point_fast,
            "max_abs_difference_m": float(np.max(np.abs(fast["position"][:loop_n] - slow)))}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--loop-n", type=int, default=5000)
    parser.add_argument("--machine", default="kidani_hmc")
    args = parser.parse_args()
    result = run(args.n, args.loop_n, args.machine)
    print(json.dumps(result, indent=2))
    return 0 if result["max_abs_difference_m"] < 1e-12 else 1


if __name__ == "__main__":
    raise SystemExit(main())
