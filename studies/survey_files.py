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
