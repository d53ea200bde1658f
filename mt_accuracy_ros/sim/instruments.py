"""Reference instruments of the virtual machine tool.

* **Laser interferometer** like the Renishaw XM60 (Kidani Table 3.3):
  angular accuracy +-(0.006 |A| + 0.5 + 0.1 M) urad (A the displayed angle in
  urad, M the distance from the laser in m), linear accuracy +-0.5 ppm. The
  stated accuracies are taken as 2 sigma (k = 2). Readings are relative to
  the first point (the zero reference of Kidani section 3.3.1.2) and averaged
  over each stop.
* **Ball bar** (ISO 230-4): radial deviation of the TCP from the nominal circle,
  +-0.5 um (2 sigma) with 0.1 um resolution.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .machine_tool import SimulationResult


def xm60_angular_accuracy_rad(angle_rad, distance_m) -> NDArray[np.float64]:
    """+-(0.006 A + 0.5 + 0.1 M) urad of Kidani Table 3.3, as radians (2 sigma)."""
    angle_urad = np.abs(np.asarray(angle_rad, dtype=np.float64)) * 1e6
    return (0.006 * angle_urad + 0.5 + 0.1 * np.abs(np.asarray(distance_m))) * 1e-6


def xm60_linear_accuracy_m(distance_m) -> NDArray[np.float64]:
    """+-0.5 ppm of the measured distance (2 sigma), Kidani Table 3.3."""
    return 0.5e-6 * np.abs(np.asarray(distance_m, dtype=np.float64))


@dataclass
class LaserReading:
    """Laser results at stops: positions [m], yaw [rad], positioning error [m], 2-sigma bands."""

    positions_m: NDArray[np.float64]
    yaw_rad: NDArray[np.float64]
    yaw_uncertainty_rad: NDArray[np.float64]
    positioning_error_m: NDArray[np.float64]
    positioning_uncertainty_m: NDArray[np.float64]
    sample_indices: list[NDArray[np.int64]]


def laser_at_stops(result: SimulationResult, axis: str, groups: list[NDArray[np.int64]],
                   *, seed: int = 0, laser_distance_m: float = 1.0) -> LaserReading:
    """Yaw and positioning error of ``axis`` measured by the laser at each stop.

    Parameters
    ----------
    result : SimulationResult
    axis : str
        The measured axis (its scale pair's yaw; TCP positioning along it).
    groups : list of index arrays
        Samples of each stop (e.g. :meth:`SimulationResult.dwell_groups`).
    seed : int
        Seed of the instrument noise (independent of the machine's).
    laser_distance_m : float
        Distance M of the laser head from the optics [m] (Table 3.3's M).
    """
    rng = np.random.default_rng(np.random.SeedSequence([result.scenario.seed, 0x1A5E, seed]))
    direction = "XYZ".index(axis)
    positions = np.array([result.actual[axis][g].mean() for g in groups])
    yaw_true = np.array([result.yaw_truth[axis][g].mean() for g in groups])
    picks = np.array([g[len(g) // 2] for g in groups])
    tcp = result.tcp_error(picks)[:, direction]
    yaw_relative = yaw_true - yaw_true[0]
    yaw_band = xm60_angular_accuracy_rad(yaw_relative, laser_distance_m)
    travel = positions - positions[0]
    linear_band = xm60_linear_accuracy_m(travel) + 1e-9
    yaw = yaw_relative + rng.normal(0.0, 0.5 * yaw_band)
    yaw[0] = 0.0
    positioning = (tcp - tcp[0]) + rng.normal(0.0, 0.5 * linear_band)
    positioning[0] = 0.0
    return LaserReading(positions, yaw, yaw_band, positioning, linear_band, list(groups))


@dataclass
class BallBarReading:
    """Ball-bar trace: angle [rad] and radial deviation [m] of each sample."""

    angle_rad: NDArray[np.float64]
    radial_deviation_m: NDArray[np.float64]


def ball_bar(result: SimulationResult, *, stride: int = 1, seed: int = 0,
             noise_m: float = 0.25e-6, resolution_m: float = 0.1e-6) -> BallBarReading:
    """Radial deviation along a ``circle`` program (ISO 230-4) at every ``stride``-th sample."""
    program = result.program
    if not hasattr(program, "radius_m"):
        raise ValueError("the ball bar needs a 'circle' program")
    rng = np.random.default_rng(np.random.SeedSequence([result.scenario.seed, 0xBA11, seed]))
    index = np.arange(0, result.time_s.size, stride)
    first, second = program.axes
    error = result.tcp_error(index)
    i, j = "XYZ".index(first), "XYZ".index(second)
    cx = result.command[first][index] - program.center_m[0]
    cy = result.command[second][index] - program.center_m[1]
    radius = np.hypot(cx, cy)
    radial = (error[:, i] * cx + error[:, j] * cy) / radius
    radial = radial + rng.normal(0.0, noise_m, radial.size)
    if resolution_m > 0:
        radial = np.round(radial / resolution_m) * resolution_m
    return BallBarReading(np.arctan2(cy, cx), radial)


def calibrate_machine(result: SimulationResult, *, step_m: float = 0.02, seed: int = 0) -> dict:
    """A machine description as a laser calibration of this virtual machine would give it.

    Every motion error of every linear axis measured at ``step_m`` steps over
    its stroke (ISO 230-2 style), with XM60-like noise (Table 3.3, k = 2), and
    the squareness errors as a ball-bar/diagonal test would give them; returned
    as a machine-description mapping (``machine_from_dict``) with error tables -
    what a machine carries from its installation calibration.
    """
    from ..core.kinematics.machine import COMPONENTS

    scenario = result.scenario
    machine = scenario.machine
    rng = np.random.default_rng(np.random.SeedSequence([scenario.seed, 0xCA1, seed]))
    axes = {}
    for axis in machine.axis_order:
        spec = machine.axes[axis]
        entry = {"stroke": list(spec.stroke), "offset": spec.offset.tolist(), "sign": spec.sign}
        if not spec.is_rotary and axis in result._profiles and \
                "geometric" in scenario.enabled:
            low, high = spec.stroke
            grid = np.arange(low, high + 1e-9, step_m)
            errors = {}
            for component in COMPONENTS:
                truth = result._profiles[axis][component](grid)
                if component in "XYZ":
                    noise = rng.normal(0.0, 0.5 * xm60_linear_accuracy_m(grid - low) + 0.05e-6)
                else:
                    noise = rng.normal(0.0, 0.5 * xm60_angular_accuracy_rad(truth, 1.0))
                errors[f"E{component}{axis}"] = {"table": {"positions": grid.tolist(),
                                                           "values": (truth + noise).tolist()}}
            entry["errors"] = errors
        location = {f"E{c}0{axis}": v for c, v in spec.location_errors.items()}
        if "squareness" in scenario.enabled:
            for name, value in scenario.parameters("squareness")["errors_rad"].items():
                if name.endswith(axis):
                    location[name] = float(value) + float(rng.normal(0.0, 0.5e-6))
        if location:
            entry["location_errors"] = location
        axes[axis] = entry
    return {"name": f"{machine.name}_calibrated", "description":
            f"{machine.name} as calibrated on the virtual machine tool (seed {scenario.seed})",
            "chain": machine.chain, "tool": machine.tool.tolist(),
            "workpiece": machine.workpiece.tolist(),
            "scale_distance_m": dict(machine.scale_distance_m), "axes": axes,
            **({"structure_length_m": machine.structure_length_m}
               if machine.structure_length_m is not None else {}),
            **({"cnc": dict(machine.cnc)} if machine.cnc else {})}
