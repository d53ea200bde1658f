"""``mt-accuracy iso230-2 RUN.csv``: a laser interferometer's positioning runs, evaluated.

Reads the run (:mod:`~mt_accuracy_ros.io.laser_run`), refers the deviations to 20 degC
when a material temperature and its expansion coefficient are given, evaluates the
ISO 230-2 figures (:func:`~mt_accuracy_ros.core.scales.repeatability.iso230_2`),
prints them with a per-target table, and writes the JSON and the report section
(the same section a bag's report shows for the runs it finds).
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from ..core.errors import InputDataError
from ..core.scales.repeatability import (STANDARD_RUNS, corrected_to_20c, iso230_2,
                                         runs_by_target)

#: (attribute, symbol, meaning) of the axis figures, the standard's order.
FIGURES = (("accuracy", "A", "accuracy, bidirectional"),
           ("accuracy_up", "A↑", "accuracy, approaches from below"),
           ("accuracy_down", "A↓", "accuracy, approaches from above"),
           ("systematic_deviation", "E", "systematic positional deviation, bidirectional"),
           ("systematic_deviation_up", "E↑", "systematic positional deviation, from below"),
           ("systematic_deviation_down", "E↓", "systematic positional deviation, from above"),
           ("mean_deviation_range", "M", "range of the mean bidirectional deviation"),
           ("repeatability", "R", "repeatability, bidirectional"),
           ("repeatability_up_axis", "R↑", "repeatability, from below"),
           ("repeatability_down_axis", "R↓", "repeatability, from above"),
           ("reversal_value", "B", "reversal value"),
           ("mean_reversal", "B̄", "mean reversal value"))


def evaluate_run(path: Path, flags: list[str], axis: str = "X",
                 expansion_per_k: float | None = None) -> dict:
    """The ISO 230-2 evaluation of the runs in ``path``: figures SI and in um, per target."""
    from ..io.laser_run import read_laser_run

    run = read_laser_run(path, flags)
    notes = []
    deviation = run.deviation_m
    if expansion_per_k is not None:
        if run.temperature_c is None:
            raise InputDataError("--expansion given but no temperature column (--col "
                                 "temperature=COLUMN:degC): nothing to correct to 20 degC")
        deviation = corrected_to_20c(run.target_m, deviation, run.temperature_c,
                                     expansion_per_k)
        notes.append(f"Deviations referred to 20 °C: alpha = {expansion_per_k * 1e6:.3g} "
                     f"µm/m/K, material {np.min(run.temperature_c):.2f}-"
                     f"{np.max(run.temperature_c):.2f} °C.")
    elif run.temperature_c is not None:
        notes.append("A material temperature was read but no expansion coefficient given "
                     "(--expansion): the deviations are NOT referred to 20 °C.")
    targets, up, down = runs_by_target(run.target_m, deviation, run.direction, run.run)
    if targets.size < 2:
        raise InputDataError(f"one target position ({targets[0] * 1e3:.4g} mm): ISO 230-2 "
                             "evaluates an axis at several")
    if up.shape[1] < STANDARD_RUNS:
        notes.append(f"{up.shape[1]} runs: the standard test has {STANDARD_RUNS}; the "
                     "repeatability figures rest on fewer.")
    result = iso230_2(targets, up, down)
    return {"data": str(path), "kind": "iso230_2", "axis": axis, "columns": run.columns,
            "rows_note": run.rows_note, "units_note": run.units_note(),
            "targets": int(targets.size), "runs": int(up.shape[1]),
            "figures_m": result.summary(),
            "figures_um": {symbol: getattr(result, name) * 1e6 for name, symbol, _ in FIGURES},
            "per_target": [{"target_mm": float(t * 1e3), "mean_up_um": float(a * 1e6),
                            "mean_down_um": float(b * 1e6), "s_up_um": float(c * 1e6),
                            "s_down_um": float(d * 1e6), "reversal_um": float(e * 1e6),
                            "repeatability_um": float(f * 1e6)}
                           for t, a, b, c, d, e, f in zip(
                               result.targets, result.mean_up, result.mean_down, result.s_up,
                               result.s_down, result.reversal,
                               result.repeatability_bidirectional)],
            "refused_rows": run.refused, "notes": notes, "_result": result}


def print_run(result: dict) -> None:
    print(f"{result['rows_note']}; {result['targets']} targets x {result['runs']} runs "
          f"x 2 directions, axis {result['axis']}")
    print(result["units_note"])
    for name, symbol, meaning in FIGURES:
        print(f"  {symbol:3s} {result['figures_um'][symbol]:9.3f} um   {meaning}")
    print(f"  {'target [mm]':>12s} {'x↑ [um]':>9s} {'x↓ [um]':>9s} {'s↑ [um]':>8s} "
          f"{'s↓ [um]':>8s} {'B_i [um]':>9s} {'R_i [um]':>9s}")
    for row in result["per_target"]:
        print(f"  {row['target_mm']:12.3f} {row['mean_up_um']:9.3f} {row['mean_down_um']:9.3f} "
              f"{row['s_up_um']:8.3f} {row['s_down_um']:8.3f} {row['reversal_um']:9.3f} "
              f"{row['repeatability_um']:9.3f}")
    for reason in result.get("refused_rows", []):
        print(f"refused: {reason}")
    for note in result["notes"]:
        print(f"note: {note}")


def write_run_outputs(result: dict, json_path: str | None, report_path: str | None) -> None:
    evaluation = result.pop("_result")
    if report_path:
        from ..report import Report, render
        from ..report.sections import iso230_2_section

        path = Path(report_path)
        path.parent.mkdir(parents=True, exist_ok=True)
        section = iso230_2_section([(result["axis"], evaluation)], path.parent,
                                   path.with_suffix("").name, notes=result["notes"])
        report = Report("mt-accuracy iso230-2", f"Positioning runs of {result['data']}",
                        [section])
        render(report, path)
        result["report"] = report.as_dict()
    if json_path:
        Path(json_path).parent.mkdir(parents=True, exist_ok=True)
        Path(json_path).write_text(json.dumps(result, indent=2, default=float))


# ------------------------------------------------------------------ the command line
#: Expansion coefficients a material may have [um/m/K] (Invar ~1, steel 11.5, aluminium
#: 23, polymers up to ~200); below :data:`EXPANSION_PER_K_LIKE` a value is one in 1/K.
EXPANSION_LIMIT_UM_M_K = 300.0
EXPANSION_PER_K_LIKE = 1e-3


def validate_iso230_2(args: argparse.Namespace) -> None:
    """An expansion coefficient in um/m/K (one in 1/K refused, naming it), an axis name
    without spaces, the outputs."""
    from ..core.errors import ParameterError
    from ..core.inputs.options import in_range
    from ..io.output_paths import Output, check_outputs

    in_range("--expansion", args.expansion, low=-EXPANSION_LIMIT_UM_M_K,
             high=EXPANSION_LIMIT_UM_M_K, unit="um/m/K")
    if args.expansion is not None and 0 < abs(args.expansion) < EXPANSION_PER_K_LIKE:
        raise ParameterError(f"--expansion must be in um/m/K (steel 11.5), got "
                             f"{args.expansion:g}: that looks like 1/K (times 1e6: "
                             f"{args.expansion * 1e6:g})")
    if not args.axis.strip() or any(c.isspace() for c in args.axis):
        raise ParameterError(f"--axis must be an axis name without spaces (X, Y, Z, A), got "
                             f"{args.axis!r}")
    check_outputs([Output("--json", args.json), Output("--report", args.report)], [args.run])


def iso230_2_command(args: argparse.Namespace) -> int:
    """Evaluate the run, print its figures, write its outputs."""
    expansion = None if args.expansion is None else args.expansion * 1e-6
    result = evaluate_run(Path(args.run), args.col or [], args.axis.upper(), expansion)
    print_run(result)
    write_run_outputs(result, args.json, args.report)
    return 0


def add_parser(commands) -> None:
    """``iso230-2`` on the subcommands ``commands``."""
    iso = commands.add_parser("iso230-2", help="ISO 230-2 figures of a laser interferometer's "
                              "positioning runs (CSV)")
    iso.add_argument("run", help="CSV: one reading per row, in the order measured")
    iso.add_argument("--col", action="append", metavar="ROLE=COLUMN[:UNIT]",
                     help="target, measured or deviation, direction, run, temperature "
                          "(default: read off the header, e.g. target_mm, deviation_um)")
    iso.add_argument("--axis", default="X", help="the axis' name in the outputs")
    iso.add_argument("--expansion", type=float, default=None, metavar="UM_PER_M_K",
                     help="the material's expansion coefficient [um/m/K] (steel 11.5): with "
                          "a temperature column, deviations are referred to 20 degC")
    iso.add_argument("--json", help="JSON summary path")
    iso.add_argument("--report", help="HTML report path")
    iso.set_defaults(handler=iso230_2_command, validate=validate_iso230_2)
