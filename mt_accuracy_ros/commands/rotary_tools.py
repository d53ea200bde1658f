"""``mt-accuracy ballbar|probe|export``: rotary-axis calibration and CNC tables.

* ``ballbar FILE --radius-mm R`` - Zhu ch. 5 two-setup calibration of a rotary
  table; ``--simulate`` first writes FILE from the virtual table (Table 5.2-size
  errors; ``--backlash`` adds a lost motion).
* ``probe FILE --machine M --sphere-radius-mm r`` - the rotary axes' location
  errors from a probed sphere; ``--simulate`` writes FILE from the virtual
  machine with known location errors (and prints them).
* ``export MODEL --spacing-mm h --out DIR`` - per-axis bilateral tables and the
  volumetric parameter file, read back, applied and compared with the model.

Each can write ``--report`` (HTML with plots) and ``--json``; outputs are
written whole or not at all.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np


def _finish(sections, title: str, subtitle: str, report: str | None, summary: dict,
            json_path: str | None) -> None:
    from ..io.rotary_csv import atomic_write_text
    from ..report import Report, render

    if report:
        render(Report(title, subtitle, sections), Path(report))
        print(f"  report: {report}")
    if json_path:
        atomic_write_text(json_path, json.dumps(summary, indent=1, default=float) + "\n")
        print(f"  json: {json_path}")


def _report_dir(report: str) -> tuple[Path, str]:
    path = Path(report)
    path.parent.mkdir(parents=True, exist_ok=True)
    return path.parent, path.with_suffix("").name


def ballbar_command(args: argparse.Namespace) -> int:
    from ..core.rotary.ballbar import ARCSEC, calibrate
    from ..io.rotary_csv import (BALLBAR_UNITS_NOTE, atomic_write_text, ballbar_csv_text,
                                 read_ballbar_csv)
    from ..sim.rotary_instruments import BallBarPlan, RotaryTableTruth, ballbar_test

    if args.simulate is not None and args.scenario:
        from dataclasses import replace

        from ..nodes._scenario import resolve_scenario
        from ..sim.rotary_instruments import table_truth

        truth = replace(table_truth(resolve_scenario(args.scenario), args.axis),
                        reversal_lost_motion_rad=1e-4 if args.backlash else 0.0)
    elif args.simulate is not None:
        truth = RotaryTableTruth(radial_m=(15e-6, -15e-6), axial_m=2.68e-6,
                                 tilt_rad=(7.93 * ARCSEC, 7.38 * ARCSEC), positioning_rad=0.15e-3,
                                 reversal_lost_motion_rad=1e-4 if args.backlash else 0.0,
                                 reversal_tilt_rad=(0.0, 12e-6) if args.backlash else (0.0, 0.0))
    if args.simulate is not None:
        plan = BallBarPlan(radius_m=args.radius_mm * 1e-3)
        data = ballbar_test(truth, plan, seed=args.simulate)
        atomic_write_text(args.file, ballbar_csv_text(data.angles_deg, data.short, data.long,
                                                      plan.short_bar_m, plan.long_bar_m))
        print(f"simulated ball-bar runs written to {args.file} (true E_x "
              f"{truth.tilt_rad[0] / ARCSEC:.2f}\", E_y {truth.tilt_rad[1] / ARCSEC:.2f}\", "
              f"D_z {truth.axial_m * 1e6:.2f} um"
              f"{', with a rotary backlash' if args.backlash else ''})")
    short, long = read_ballbar_csv(args.file, args.radius_mm * 1e-3, args.socket_height_mm * 1e-3)
    result = calibrate(short, long, socket_change_m=args.socket_change_um * 1e-6)
    print(f"{args.file}: {BALLBAR_UNITS_NOTE}")
    print(result.text())
    if args.report or args.json:
        from ..report.rotary import ballbar_sections

        sections = ballbar_sections(result, *_report_dir(args.report)) if args.report else []
        _finish(sections, "mt-accuracy ballbar", f"Rotary-table calibration from {args.file} "
                "(Zhu 2008, ch. 5)", args.report,
                {**result.as_dict(), "units": BALLBAR_UNITS_NOTE}, args.json)
    return 0


def probe_command(args: argparse.Namespace) -> int:
    from ..core.kinematics.machine import load_machine
    from ..core.rotary.probing import fit_sphere, identify_location_errors
    from ..io.rotary_csv import (atomic_write_text, probing_csv_text, probing_units_note,
                                 read_probing_csv)
    from ..sim.rotary_instruments import ProbingPlan, probe_sphere

    scenario_truth = None
    if args.scenario:
        from ..nodes._scenario import resolve_scenario
        from ..sim.rotary_instruments import location_errors_of

        scenario = resolve_scenario(args.scenario)
        machine, scenario_truth = scenario.machine, location_errors_of(scenario)
    else:
        machine = load_machine(args.machine)
    rotary = {a for a in machine.axis_order if machine.axes[a].is_rotary}
    if not rotary:
        raise ValueError(f"machine {machine.name} has no rotary axis to probe")
    sphere = np.array(args.sphere_mm, float) * 1e-3
    if args.simulate is not None:
        truth = {"EY0A": 20e-6, "EZ0A": -15e-6, "EB0A": 30e-6, "EC0A": -25e-6,
                 "EA0B": 15e-6, "EC0B": -20e-6}
        truth = {k: v for k, v in truth.items() if k[-1] in rotary} \
            if scenario_truth is None else scenario_truth
        linear = {a: float(np.mean(machine.axes[a].stroke)) for a in machine.axis_order
                  if a not in rotary}
        plan = ProbingPlan({a: list(np.arange(-60.0, 61.0, 20.0)) for a in sorted(rotary)},
                           linear, sphere_m=tuple(sphere),
                           sphere_radius_m=args.sphere_radius_mm * 1e-3, repeats=2)
        data = probe_sphere(machine, plan, truth, seed=args.simulate)
        atomic_write_text(args.file, probing_csv_text(data["positions"], data["touch_points_m"],
                                                      rotary))
        print(f"simulated probing written to {args.file}; the virtual machine's location "
              "errors: " + ", ".join(f"{k} {v * 1e6:+.1f}" for k, v in truth.items()))
    positions, touches = read_probing_csv(args.file, machine.axis_order, rotary)
    centres = np.array([fit_sphere(points, args.sphere_radius_mm * 1e-3,
                                   tolerance_m=args.tolerance_um * 1e-6,
                                   label=f"cycle {i + 1}").centre_m
                        for i, points in enumerate(touches)])
    result = identify_location_errors(machine, positions, centres,
                                      args.parameters.split(",") if args.parameters else None,
                                      sphere_nominal_m=sphere)
    units = probing_units_note(tuple(machine.axis_order), rotary)
    print(f"{args.file}: {units}")
    print(result.text())
    if args.report or args.json:
        from ..report.rotary import probing_section

        _finish([probing_section(result)], "mt-accuracy probe",
                f"Rotary-axis location errors of {machine.name} from {args.file}", args.report,
                {**result.as_dict(), "units": units}, args.json)
    return 0


#: Points per axis above which a table is refused (a typo such as --spacing-mm 0.001
#: would write hundreds of MB that no control loads).
MAX_TABLE_POINTS = 100_000


def _controller_tables(args: argparse.Namespace, model, band: float, asked: float | None,
                       max_points: int | None, controller: dict):
    """(files' texts, notes, summary, spacing [m]) of the positioning tables a control
    loads (``--controller``)."""
    from ..core.compensation.controller_tables import (fanuc_pitch, isg_leadscrew_lists,
                                                       linuxcnc_comp_files, siemens_eec,
                                                       spacing_for, uncovered_effects)

    texts, notes = {}, []
    choice = spacing_for(model, band, asked_m=asked, max_points=max_points)
    spacing = choice.spacing_m
    if args.controller == "siemens":
        text, shifts = siemens_eec(model, spacing)
        texts["AX_EEC.INI"] = text
        moved = {a: v for a, v in shifts.items() if abs(v) > 0}
        if moved:
            notes.append("the value at each reference point is zero (SINUMERIK's rule): "
                         "shifted by " + ", ".join(f"{a} {v * 1e6:.3g} um"
                                                   for a, v in moved.items()))
    elif args.controller == "linuxcnc":
        files, ini = linuxcnc_comp_files(model, spacing, file_type=args.comp_file_type)
        texts.update(files)
        notes.append("add to the INI file (a joint with COMP_FILE uses no BACKLASH): " +
                     "; ".join(v.replace("\n", " ") for v in ini.values()))
    elif args.controller == "twincat":
        lists, _ = isg_leadscrew_lists(model, spacing, bilateral=not args.unilateral)
        texts.update(lists)
    else:
        text, _ = fanuc_pitch(model, spacing, step_limit=int(
            args.fanuc_step_limit or controller["step_limit"]),
            detection_unit_m=args.detection_unit_um * 1e-6)
        texts["PITCH_ERROR.TXT"] = text
    uncovered = uncovered_effects(model)
    if uncovered:
        notes.append(f"positioning tables do not hold {', '.join(uncovered)}: the "
                     "control's cross/volumetric compensation (volumetric_isg.csv) or the "
                     "real-time offset carries them")
    if choice.limited_by:
        notes.append(choice.limited_by)
    summary = {"controller": args.controller, "spacing_m": spacing,
               "max_error_m": choice.max_error_m, "errors_m": choice.errors_m,
               "periods_m": choice.periods_m, "limited_by": choice.limited_by,
               "band_m": band}
    return texts, notes, summary, spacing


def _generic_tables(args: argparse.Namespace, model, band: float, asked: float | None):
    """(files' texts, notes, summary, spacing [m], round trip) of the per-axis bilateral
    tables and the volumetric ISG-CSV, every one computed before anything is written."""
    from ..core.compensation.cnc_export import (bilateral_tables, round_trip, write_bilateral_csv,
                                               write_isg_csv)
    from ..core.compensation.controller_tables import (period_problems, periodic_periods,
                                                       volumetric_spacing)
    from ..core.errors import ParameterError

    notes = []
    if asked is None:
        spacing = volumetric_spacing(model, band)
    else:
        spacing = asked
        short = period_problems(periodic_periods(model), spacing)
        if short:
            raise ParameterError(
                f"spacing {args.spacing_mm:g} mm cannot hold this model: "
                f"{'; '.join(short)}; a spacing that holds it: "
                f"{volumetric_spacing(model, band) * 1e3:g} mm")
    # Everything is computed before anything is written: a bad spacing writes nothing.
    texts = {f"{axis}_bilateral.csv": write_bilateral_csv(table, model.machine.name)
             for axis, table in bilateral_tables(model, spacing).items()}
    texts["volumetric_isg.csv"] = write_isg_csv(model, spacing)
    check = round_trip(model, spacing)
    if check.tcp_max_error_m > band and asked is not None:
        notes.append(f"warning: at {spacing * 1e3:g} mm the tables leave up to "
                     f"{check.tcp_max_error_m * 1e6:.3g} um at the TCP, over the band "
                     f"{args.band_um:g} um")
    held, left_out = _what_the_file_holds(model, spacing)
    notes += held
    summary = {"files": list(texts), **check.as_dict(), "band_m": band,
               "not_in_file": {c.name: c.gap_rms_m for c in left_out}}
    return texts, notes, summary, spacing, check


def _what_the_file_holds(model, spacing: float) -> tuple[list[str], list]:
    """Notes on what the volumetric file holds of the model: each fitted geometric effect
    through the file against the model's own prediction (one the file cannot hold - a
    rotary axis' own error motion - said, never left out), a survey's set-up (no file's),
    a line error that stands for a sum (the survey's poses could not part it). Returns the
    notes and the effects not carried (:class:`~..core.compensation.cnc_export.CarriedEffect`)."""
    from ..core.compensation.cnc_export import SET_UP_FAMILIES, carried_effects
    from ..core.effects.geometric import inseparable_sentence

    notes = []
    rotary = [a for a in model.machine.axis_order if model.machine.axes[a].is_rotary]
    set_up = {a: model.machine.setup_angle(a) for a in rotary}
    left_out = [c for c in carried_effects(model, spacing) if not c.carried]
    for effect in left_out:
        share = effect.gap_rms_m / effect.model_rms_m if effect.model_rms_m else 1.0
        held = "does not hold" if share > 0.9 else f"holds only {100 * (1 - share):.0f} % of"
        why = ""
        if effect.name.split(":")[0] in ("rotary_location", "angular") and \
                any(abs(v) > 0 for v in set_up.values()):
            why = (" - the file's line errors are ISO 230-7's (the body turning by the raw "
                   "command); with the set-up at " + ", ".join(
                       f"{a} = {np.degrees(v):g} deg" for a, v in set_up.items()) +
                   " this check, which turns each body from its set-up angle, reads an outer "
                   "axis' line otherwise: check the compensation on the machine")
        notes.append(f"warning: volumetric_isg.csv {held} {effect.name} "
                     f"({effect.model_rms_m * 1e6:.3g} um RMS at the TCP; the file leaves "
                     f"{effect.gap_rms_m * 1e6:.3g} um of it): compensate the rest in real "
                     f"time (the broadcaster's stream){why}")
    for name, entry in model.effects.items():
        if isinstance(entry, dict) and entry.get("family") in SET_UP_FAMILIES:
            notes.append(f"{name} is where the survey's work or tool was located (its "
                         "set-up), not the machine: a new part set-up takes out its own, so "
                         "no file holds it")
        folded = inseparable_sentence(((entry.get("setting") or {}).get("inseparable", ""))
                                      if isinstance(entry, dict) else "")
        if folded and entry.get("family") == "rotary_location":
            notes.append(f"{name}: {folded} - the file holds the values as fitted, right on "
                         "poses like the survey's")
    return notes, left_out


def _refuse_too_many_points(args: argparse.Namespace, machine, asked: float | None,
                            max_points: int | None, controller: dict) -> None:
    """A spacing asked for that needs more points than any table (or the control) holds."""
    from ..core.compensation.controller_tables import table_points
    from ..core.errors import ParameterError

    if asked is None or asked <= 0:
        return
    linear = [a for a in machine.axis_order if not machine.axes[a].is_rotary]
    points = max(table_points(machine.axes[a].stroke, asked).size for a in linear)
    if points > MAX_TABLE_POINTS:
        raise ParameterError(f"spacing {args.spacing_mm:g} mm needs {points} points per "
                             f"axis (about {points * 6 * 2 * 20 / 1e6:.0f} MB of bilateral "
                             f"tables): refused above {MAX_TABLE_POINTS}")
    if max_points and points > max_points:
        raise ParameterError(f"spacing {args.spacing_mm:g} mm needs {points} points per "
                             f"axis; {controller.get('name', 'the control')} holds "
                             f"{max_points} (--max-points)")


def export_command(args: argparse.Namespace) -> int:
    """The model's CNC tables written to ``--out`` (a control's, or the generic bilateral
    and volumetric ones read back and checked against the model), said line by line."""
    from ..core.compensation.controller_tables import CONTROLLERS
    from ..core.compensation.error_model import resolve_model
    from ..core.compensation.user_tables import fitted_user_effects, table_axis
    from ..io.rotary_csv import atomic_write_text

    model = resolve_model(args.model)
    band = args.band_um * 1e-6
    controller = CONTROLLERS.get(args.controller or "", {})
    max_points = args.max_points or controller.get("max_points")
    asked = None if args.spacing_mm is None else args.spacing_mm * 1e-3
    _refuse_too_many_points(args, model.machine, asked, max_points, controller)
    if args.controller:
        texts, notes, summary, spacing = _controller_tables(args, model, band, asked,
                                                            max_points, controller)
        check = None
    else:
        texts, notes, summary, spacing, check = _generic_tables(args, model, band, asked)
    out = Path(args.out)
    for name, text in texts.items():
        atomic_write_text(out / name, text)
    chosen = "" if asked is not None else f", chosen for a band of {args.band_um:g} um"
    print(f"wrote {', '.join(texts)} to {out} (spacing {spacing * 1e3:g} mm{chosen})")
    if check is not None:
        print(f"  round trip: tables read back and applied differ from the model by at most "
              f"{check.tcp_max_error_m * 1e6:.3f} um at the TCP (RMS "
              f"{check.tcp_rms_error_m * 1e6:.3f} um); interpolation bound "
              f"{check.tcp_bound_m * 1e6:.3f} um")
    else:
        print(f"  the table leaves at most {summary['max_error_m'] * 1e6:.3f} um of positioning "
              f"error between its points (band {args.band_um:g} um)")
    for note in notes:
        print(f"  {note}")
    for name, entry in fitted_user_effects(model).items():
        axis, why = table_axis(model, name, entry)
        print(f"  user effect {name}: " + (f"in the {axis} tables" if axis else why))
    if (args.report or args.json) and check is not None:
        from ..report.rotary import export_section

        _finish([export_section(check, list(texts))], "mt-accuracy export",
                f"CNC compensation tables of {args.model}", args.report, summary, args.json)
    elif args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps({**summary, "files": list(texts),
                                               "notes": notes}, indent=2, default=float))
    return 0


# ------------------------------------------------------------------ the options checked
def _validate_seed_and_simulation_options(args: argparse.Namespace,
                                          simulation_only: dict[str, str]) -> None:
    """--simulate SEED >= 0, and the options only a simulation reads refused without it."""
    from ..core.inputs.options import in_range, not_applicable

    in_range("--simulate", args.simulate, low=0, what="an integer seed")
    if args.simulate is None:
        for name, flag in simulation_only.items():
            if getattr(args, name) not in (None, False):
                raise not_applicable(flag, "a simulated measurement (--simulate SEED)",
                                     f"a measured file ({args.file})")


def _file_outputs(args: argparse.Namespace) -> None:
    """--json, --report and, with --simulate, FILE (written first) checked as outputs."""
    from ..io.output_paths import Output, check_outputs

    outputs = [Output("--json", args.json), Output("--report", args.report)]
    if args.simulate is not None:
        outputs.append(Output("FILE (written by --simulate)", args.file))
    check_outputs(outputs, [] if args.simulate is not None else [args.file])


def validate_ballbar(args: argparse.Namespace) -> None:
    """The ball bar's geometry in range, simulation-only options only with --simulate."""
    from ..core.inputs.options import in_range

    in_range("--radius-mm", args.radius_mm, low=0, low_open=True, unit="mm")
    in_range("--socket-height-mm", args.socket_height_mm, unit="mm")
    in_range("--socket-change-um", args.socket_change_um, low=0, unit="um")
    _validate_seed_and_simulation_options(args, {"scenario": "--scenario",
                                                 "backlash": "--backlash"})
    _file_outputs(args)


def validate_probe(args: argparse.Namespace) -> None:
    """The sphere and the tolerance in range, the seed, the outputs."""
    from ..core.inputs.options import in_range

    in_range("--sphere-radius-mm", args.sphere_radius_mm, low=0, low_open=True, unit="mm")
    for axis, value in zip("XYZ", args.sphere_mm):
        in_range(f"--sphere-mm ({axis})", value, unit="mm")
    in_range("--tolerance-um", args.tolerance_um, low=0, low_open=True, unit="um")
    _validate_seed_and_simulation_options(args, {})
    _file_outputs(args)


#: Options of ``export`` that one controller's tables read (argparse name: flag, controller).
EXPORT_CONTROLLER_OPTIONS = {"unilateral": ("--unilateral", "twincat"),
                             "fanuc_step_limit": ("--fanuc-step-limit", "fanuc")}


def validate_export(args: argparse.Namespace) -> None:
    """The tables' spacing, band and sizes in range; a controller's options only with it;
    the outputs."""
    from ..core.inputs.options import in_range, not_applicable
    from ..io.output_paths import Output, check_outputs

    in_range("--spacing-mm", args.spacing_mm, low=0, low_open=True, unit="mm")
    in_range("--band-um", args.band_um, low=0, low_open=True, unit="um")
    in_range("--max-points", args.max_points, low=2, what="an integer")
    in_range("--detection-unit-um", args.detection_unit_um, low=0, low_open=True, unit="um")
    in_range("--fanuc-step-limit", args.fanuc_step_limit, low=1, what="an integer")
    for name, (flag, controller) in EXPORT_CONTROLLER_OPTIONS.items():
        if getattr(args, name) not in (None, False) and args.controller != controller:
            raise not_applicable(flag, f"--controller {controller}",
                                 f"--controller {args.controller}" if args.controller
                                 else "the generic tables (no --controller)")
    check_outputs([Output("--out", args.out, "directory"), Output("--json", args.json),
                   Output("--report", args.report)])


def add_parser(commands) -> None:
    """``ballbar``, ``probe`` and ``export`` on the subcommands ``commands``."""
    ballbar = commands.add_parser("ballbar", help="rotary-table calibration with a ball bar "
                                  "(two bars, Zhu ch. 5; l2 and l-infinity)")
    ballbar.add_argument("file", help="ball-bar CSV: bar_mm,repetition,angle_deg,change_um")
    ballbar.add_argument("--radius-mm", type=float, default=71.842,
                         help="R_x: the table ball's distance from the table centre [mm]")
    ballbar.add_argument("--socket-height-mm", type=float, default=0.0,
                         help="R_z: the table ball's height above the table centre [mm]")
    ballbar.add_argument("--socket-change-um", type=float, default=1.0,
                         help="how far the table ball may re-seat between the two setups, "
                              "unseen by two setups: carried into U (default 1 um)")
    ballbar.add_argument("--simulate", type=int, metavar="SEED",
                         help="first write FILE from the virtual rotary table")
    ballbar.add_argument("--scenario", help="with --simulate: measure this scenario's "
                         "virtual machine (its rotary_location errors of --axis)")
    ballbar.add_argument("--axis", default="A", help="the rotary axis of --scenario's machine")
    ballbar.add_argument("--backlash", action="store_true",
                         help="with --simulate: the table has a lost motion")
    ballbar.add_argument("--report", help="HTML report with polar plots")
    ballbar.add_argument("--json", help="JSON summary")
    ballbar.set_defaults(handler=ballbar_command, validate=validate_ballbar)
    probe = commands.add_parser("probe", help="rotary-axis location errors from a probed sphere")
    probe.add_argument("file", help="probing CSV: cycle, <axis>_mm|_deg, px_mm, py_mm, pz_mm")
    probe.add_argument("--machine", default="khan_chen_rpppr",
                       help="machine description (bundled name or YAML)")
    probe.add_argument("--scenario", help="the machine of this scenario (and, with "
                       "--simulate, its true rotary_location errors) instead of --machine")
    probe.add_argument("--sphere-radius-mm", type=float, default=12.5)
    probe.add_argument("--sphere-mm", type=float, nargs=3, default=[50.0, 80.0, 60.0],
                       metavar=("X", "Y", "Z"),
                       help="nominal sphere centre in the workpiece-end frame [mm]")
    probe.add_argument("--parameters", help="comma-separated location errors to identify "
                       "(default: every observable offset and tilt of the rotary axes)")
    probe.add_argument("--tolerance-um", type=float, default=50.0,
                       help="largest distance of a touch point from the fitted sphere")
    probe.add_argument("--simulate", type=int, metavar="SEED",
                       help="first write FILE from the virtual machine")
    probe.add_argument("--report", help="HTML report")
    probe.add_argument("--json", help="JSON summary")
    probe.set_defaults(handler=probe_command, validate=validate_probe)
    export = commands.add_parser("export", help="CNC compensation tables of a model "
                                 "(per-axis bilateral CSV, volumetric ISG-CSV style)")
    export.add_argument("model", help="error model: bundled name, YAML path")
    export.add_argument("--spacing-mm", type=float, default=None,
                        help="table spacing (default: the coarsest that keeps the round trip "
                             "within --band-um and samples every period at 8 points)")
    export.add_argument("--band-um", type=float, default=1.0,
                        help="the instrument's band the tables must hold the model within")
    export.add_argument("--unilateral", action="store_true",
                        help="--controller twincat: one table for both directions (default "
                             "bilateral: the reversal error in the table)")
    export.add_argument("--comp-file-type", type=int, choices=[0, 1], default=0,
                        help="--controller linuxcnc: COMP_FILE_TYPE 0 (actual positions, "
                             "default) or 1 (trims)")
    export.add_argument("--controller", choices=["siemens", "fanuc", "twincat", "linuxcnc"],
                        default=None,
                        help="write the positioning tables a control loads: SINUMERIK EEC "
                             "(AX_EEC.INI), FANUC pitch error compensation (parameter tape) "
                             "or the ISG / TwinCAT leadscrew error compensation list "
                             "(achskw<n>.lis, kw.ssfk) or LinuxCNC's joint compensation "
                             "files (<axis>.comp, COMP_FILE)")
    export.add_argument("--max-points", type=int, default=None,
                        help="points per axis the control holds (SINUMERIK MD38000; default "
                             "200 for siemens, 128 for fanuc)")
    export.add_argument("--detection-unit-um", type=float, default=1.0,
                        help="fanuc: the axis' detection unit")
    export.add_argument("--fanuc-step-limit", type=int, default=None,
                        help="fanuc: largest increment per point in detection units x "
                             "magnification (default 7; 32767 on controls that allow it)")
    export.add_argument("--out", required=True, help="directory for the tables")
    export.add_argument("--report", help="HTML report")
    export.add_argument("--json", help="JSON summary")
    export.set_defaults(handler=export_command, validate=validate_export)
