"""Thermal logs of many days, made outside the package: cold starts, a different duty
cycle each day, a sensor that drifts, a day with a dead sensor.

This generator shares **no code** with the workbench or the error model. A
machine's structure is a lumped thermal network integrated by scipy's ODE
solver (not the package's exact-lag recurrence):

* the spindle shaft (unmeasured, 8 min) and housing (25 min) heat with spindle
  power ~ speed^1.5;
* the column's front (70 min) follows the housing, its rear (2 h) the air;
* the bed (3 h) follows the air; the air follows a daily cycle whose level
  changes from day to day.

Each day starts cold (every node at the morning's air temperature), runs a
program of spindle speeds drawn for that day (a day of roughing at high
speed, a day of finishing, a day of idling with bursts), and is logged once a
minute with its clock restarting at 0. The displacement gauge at the spindle
nose reads the shaft's and housing's growth along z, the column's bending
(front minus rear) and the bed's growth, with 0.1 um noise.

Eight thermocouples (0.02 K noise): housing, column front, column rear, bed,
air, a housing/front midpoint, a second front sensor whose calibration
drifts 0.08 K a day, and a rear sensor's near twin. On one day the front
sensor is dead (an open thermocouple: ``nan``).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

#: Node time constants [s]: shaft, housing, column front, column rear, bed.
TAU_S = {"shaft": 480.0, "housing": 1500.0, "front": 4200.0, "rear": 7200.0, "bed": 10800.0}

#: Gauge sensitivities [um/K]: growth of the shaft and housing, the column's bending
#: (front - rear), the bed.
GAIN_UM_PER_K = {"shaft": 3.0, "housing": 4.5, "bend": -6.0, "bed": 1.5}

SENSORS = ("T_housing", "T_front", "T_rear", "T_bed", "T_air", "T_mid", "T_front_b",
           "T_rear_b")


@dataclass
class Day:
    """One run: its clock [s] from 0, spindle speed [rpm], node temperatures [degC]."""

    time_s: np.ndarray
    speed_rpm: np.ndarray
    nodes: dict[str, np.ndarray]
    air: np.ndarray


def _program(rng: np.random.Generator, hours: float, style: str) -> tuple[np.ndarray, np.ndarray]:
    """(segment start times [s], speeds [rpm]) of one day's spindle program."""
    speeds = {"roughing": ([6000, 9000, 12000, 0], [0.3, 0.35, 0.25, 0.1]),
              "finishing": ([3000, 6000, 0], [0.45, 0.35, 0.2]),
              "bursts": ([0, 12000], [0.75, 0.25])}[style]
    starts, values, t = [], [], 0.0
    while t < hours * 3600.0:
        starts.append(t)
        values.append(float(rng.choice(speeds[0], p=speeds[1])))
        t += float(rng.uniform(15, 40 if style == "bursts" else 90)) * 60.0
    return np.array(starts), np.array(values)


def simulate_day(rng: np.random.Generator, hours: float, style: str, air_level_c: float,
                 period_s: float = 60.0) -> Day:
    """One cold start: every node at the morning's air temperature."""
    starts, speeds = _program(rng, hours, style)
    phase = float(rng.uniform(0, 2 * np.pi))

    def air(t):
        return air_level_c + 1.2 * np.sin(2 * np.pi * t / 86400.0 + phase)

    def speed(t):
        return speeds[np.searchsorted(starts, t, side="right") - 1]

    def rates(t, y):
        shaft, housing, front, rear, bed = y
        a = air(t)
        power = 14.0 * (speed(t) / 10000.0) ** 1.5      # K above air at steady state
        return [(a + power - shaft) / TAU_S["shaft"],
                (a + 0.7 * (shaft - a) - housing) / TAU_S["housing"],
                (a + 0.6 * (housing - a) - front) / TAU_S["front"],
                (a + 0.25 * (front - a) - rear) / TAU_S["rear"],
                (a - bed) / TAU_S["bed"]]

    t = np.arange(0.0, hours * 3600.0, period_s)
    a0 = air(0.0)
    solution = solve_ivp(rates, (0.0, t[-1]), [a0] * 5, t_eval=t, max_step=30.0,
                         rtol=1e-8, atol=1e-8)
    nodes = dict(zip(("shaft", "housing", "front", "rear", "bed"), solution.y))
    return Day(t, np.array([speed(v) for v in t]), nodes, air(t))


def displacement_um(day: Day, start_air_c: float) -> np.ndarray:
    """The gauge's reading without noise [um] relative to a machine at ``start_air_c``."""
    n = day.nodes
    return (GAIN_UM_PER_K["shaft"] * (n["shaft"] - start_air_c)
            + GAIN_UM_PER_K["housing"] * (n["housing"] - start_air_c)
            + GAIN_UM_PER_K["bend"] * (n["front"] - n["rear"])
            + GAIN_UM_PER_K["bed"] * (n["bed"] - start_air_c))


def write_log(path: Path, seed: int, *, days: int = 8, zeroed: bool = False,
              hours: tuple[float, float] = (7.0, 10.0), dead_day: int | None = 4) -> dict:
    """A log of ``days`` runs as a CSV (``day``, ``time_s`` restarting each day, ``spindle_rpm``,
    the eight sensors in degC, ``gauge_um``); returns what was hidden in it."""
    rng = np.random.default_rng(seed)
    styles = ["roughing", "finishing", "bursts"]
    reference_air = 20.0
    mount_offset_um = float(rng.uniform(-50, 50))
    lines = ["day,time_s,spindle_rpm," + ",".join(s + "_C" for s in SENSORS) + ",gauge_um"]
    truth = {"seed": seed, "days": days, "zeroed": zeroed, "dead_day": dead_day,
             "drifting_sensor": "T_front_b_C", "drift_k_per_day": 0.08, "styles": []}
    for d in range(days):
        style = styles[int(rng.integers(0, 3))]
        truth["styles"].append(style)
        day = simulate_day(rng, float(rng.uniform(*hours)), style,
                           reference_air + float(rng.normal(0, 1.5)))
        n, m = day.nodes, day.time_s.size
        noise = lambda: rng.normal(0, 0.02, m)   # noqa: E731
        readings = {
            "T_housing": n["housing"] + noise(), "T_front": n["front"] + noise(),
            "T_rear": n["rear"] + noise(), "T_bed": n["bed"] + noise(),
            "T_air": day.air + noise(), "T_mid": 0.5 * (n["housing"] + n["front"]) + noise(),
            "T_front_b": n["front"] + 0.08 * d + noise(),
            "T_rear_b": 0.9 * n["rear"] + 0.1 * day.air + noise()}
        gauge = displacement_um(day, reference_air) + mount_offset_um + rng.normal(0, 0.1, m)
        if zeroed:
            gauge = gauge - gauge[0]
        for k in range(m):
            cells = [f"day{d + 1}", f"{day.time_s[k]:.0f}", f"{day.speed_rpm[k]:.0f}"]
            for sensor in SENSORS:
                dead = dead_day is not None and d == dead_day and sensor == "T_front"
                cells.append("nan" if dead else f"{readings[sensor][k]:.4f}")
            cells.append(f"{gauge[k]:.4f}")
            lines.append(",".join(cells))
    Path(path).write_text("\n".join(lines) + "\n")
    return truth


def cut_into_runs(source: Path, out: Path, hours: float, zeroed: bool) -> Path:
    """A recorded log (``time_s`` first, displacement channels ``ch*``) cut into runs of
    ``hours``, written with a ``day`` column (``day1``, ...): each run's clock restarts at 0
    and, ``zeroed``, every displacement channel is referred to its run's first reading."""
    import csv

    rows = list(csv.reader(open(source)))
    header, data = rows[0], np.array(rows[1:], dtype=float)
    run = (data[:, 0] // (hours * 3600.0)).astype(int)
    cut = data.copy()
    for r in np.unique(run):
        rows_r = np.flatnonzero(run == r)
        cut[rows_r, 0] -= data[rows_r[0], 0]
        if zeroed:
            for j, name in enumerate(header):
                if name.startswith("ch"):
                    cut[rows_r, j] -= data[rows_r[0], j]
    lines = [",".join(["day"] + header)]
    lines += [f"day{r + 1}," + ",".join(f"{v:.10g}" for v in row) for r, row in zip(run, cut)]
    Path(out).write_text("\n".join(lines) + "\n")
    return Path(out)
