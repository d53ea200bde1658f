"""A generated survey written as a data logger would: CSV in mm, um, degC and minutes,
with the column map that tells ``mt-accuracy check`` what each column is."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from studies.foreign_machine import Trial

HEADER = "minutes,X_mm,Y_mm,Z_mm,dev_x_um,dev_y_um,dev_z_um,T_col,T_bed,T_spin,T_amb"


def write_logger_survey(trial: Trial, csv_path: Path, map_path: Path) -> None:
    """``trial``'s survey and measured errors as a logger CSV, and its column map (YAML)."""
    s = trial.survey
    columns = [s.time_s / 60, *(s.positions[a] * 1e3 for a in "XYZ"),
               *(trial.measured_m[:, i] * 1e6 for i in range(3)),
               *(s.temperatures[k] for k in ("column", "bed", "spindle", "ambient"))]
    # 12 digits: minutes of a 1e5-reading survey still increase at every row.
    np.savetxt(csv_path, np.column_stack(columns), delimiter=",", fmt="%.12g", comments="",
               header=HEADER)
    Path(map_path).write_text(yaml.safe_dump({
        "time": {"column": "minutes", "unit": "min"},
        "positions": {a: {"column": f"{a}_mm", "unit": "mm"} for a in "XYZ"},
        "errors": {c: {"column": f"dev_{c}_um", "unit": "um"} for c in "xyz"},
        "temperatures": {k: {"column": c, "unit": "degC"} for k, c in (
            ("column", "T_col"), ("bed", "T_bed"), ("spindle", "T_spin"), ("ambient", "T_amb"))},
        "uncertainty": {"value": 1.4, "unit": "um"}}))


#: The shapes of survey the speed panel times (``bench.engine_speed --panel``): which
#: columns a logger recorded, and the machine ``check`` is told about (None: none, a
#: generic Cartesian machine from the data).
PANEL_SHAPES = {
    "positions": {"machine": "kidani_hmc", "motion": False, "temperatures": False,
                  "model": None},
    "full": {"machine": "kidani_hmc", "motion": True, "temperatures": True, "model": None},
    "machine_3axis": {"machine": "kidani_hmc", "motion": True, "temperatures": True,
                      "model": "{machine: kidani_hmc}"},
    "machine_5axis": {"machine": "khan_chen_rpppr", "motion": True, "temperatures": True,
                      "model": "{machine: khan_chen_rpppr}"},
}


def write_panel_survey(trial: Trial, csv_path: Path, map_path: Path, *, motion: bool,
                       temperatures: bool) -> None:
    """``trial``'s survey as a logger CSV (mm, deg, um, min) with its column map.

    Parameters
    ----------
    trial : Trial
        The generated survey (any machine of ``studies.foreign_machine``; rotary
        positions are written in degrees).
    csv_path, map_path : Path
        Where the CSV and its column map (YAML) go.
    motion : bool
        Also the axes' velocities [mm/min] and accelerations [m/s^2], and the spindle
        speed [rpm].
    temperatures : bool
        Also the four temperatures (ambient, bed, column, spindle) [degC].
    """
    s = trial.survey
    names, columns = ["minutes"], [s.time_s / 60]
    mapping: dict = {"time": {"column": "minutes", "unit": "min"}, "positions": {},
                     "errors": {c: {"column": f"dev_{c}_um", "unit": "um"} for c in "xyz"},
                     "uncertainty": {"value": 1.4, "unit": "um"}}
    for axis, q in s.positions.items():
        rotary = axis in "ABC"
        names.append(f"{axis}_deg" if rotary else f"{axis}_mm")
        columns.append(np.degrees(q) if rotary else q * 1e3)
        mapping["positions"][axis] = {"column": names[-1], "unit": "deg" if rotary else "mm"}
    names += [f"dev_{c}_um" for c in "xyz"]
    columns += [trial.measured_m[:, i] * 1e6 for i in range(3)]
    if motion:
        mapping["velocities"], mapping["accelerations"] = {}, {}
        for axis in s.positions:
            if axis in "ABC":
                continue
            names += [f"feed_{axis}", f"acc_{axis}"]
            columns += [s.velocities[axis] * 6e4, s.accelerations[axis]]
            mapping["velocities"][axis] = {"column": f"feed_{axis}", "unit": "mm/min"}
            mapping["accelerations"][axis] = {"column": f"acc_{axis}", "unit": "m/s^2"}
        names.append("S_rpm")
        columns.append(s.spindle_speed_rad_s * 60 / (2 * np.pi))
        mapping["spindle_speed"] = {"column": "S_rpm", "unit": "rpm"}
    if temperatures:
        mapping["temperatures"] = {}
        for sensor in ("ambient", "bed", "column", "spindle"):
            names.append(f"T_{sensor}")
            columns.append(s.temperatures[sensor])
            mapping["temperatures"][sensor] = {"column": names[-1], "unit": "degC"}
    np.savetxt(csv_path, np.column_stack(columns), delimiter=",", fmt="%.12g", comments="",
               header=",".join(names))
    Path(map_path).write_text(yaml.safe_dump(mapping))
