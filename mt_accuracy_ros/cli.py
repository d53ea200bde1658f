"""The ``mt-accuracy`` command line.

Every option is checked before any work, by the command's validator
(``set_defaults(validate=...)``, run by :func:`main` before the handler): a value out of
its range, an option given where nothing reads it, an output path that cannot be
written (:mod:`~mt_accuracy_ros.io.output_paths`) is refused in one line naming the flag,
the value and what was expected. Every refusal is a :class:`MtAccuracyError` that
:func:`main` prints as one line with exit status 2.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from .core.errors import InputDataError, ParameterError
from .core.inputs.options import in_range, not_applicable
from .io.output_paths import Output, check_outputs


#: The main job's scenario on each bundled machine.
DEMO_SCENARIOS = {"kidani_hmc": "demo", "khan_chen_rpppr": "demo_5axis", "vmc": "demo_vmc",
                  "trunnion_ac": "demo_trunnion"}
#: Its default rate [sim s per wall s] (real time, on every machine).
DEMO_RATE = 1.0
#: Niceness a process may be given (Linux).
NICENESS_RANGE = (-20, 19)


def _validate_demo(args: argparse.Namespace) -> None:
    in_range("--rate", args.rate, low=0, low_open=True, unit="sim s per wall s")
    if args.lockstep and args.rate is not None:
        raise not_applicable("--rate", "a demo in real time", "--lockstep (it streams in "
                             "data time, at the pace of the slowest node)")
    in_range("--niceness", args.niceness, low=NICENESS_RANGE[0], high=NICENESS_RANGE[1],
             what="an integer")
    check_outputs([Output("--out", args.out, "directory")])


def _demo(args: argparse.Namespace) -> int:
    from .commands.demo import run_demo

    rate = args.rate if args.rate is not None else DEMO_RATE
    return run_demo(out_dir=args.out, rate_factor=rate,
                    scenario=args.scenario or DEMO_SCENARIOS[args.machine],
                    compensation_mode=args.compensation, path_niceness=args.niceness,
                    lockstep=args.lockstep)


def _info(args: argparse.Namespace) -> int:
    from .io.bag_reader import bag_info

    info = bag_info(args.bag)
    print(f"Files:          {', '.join(info['files'])}")
    print(f"Duration:       {info['duration_s']:.3f} s")
    print(f"Start:          {info['start_ns'] / 1e9:.9f} s")
    print(f"End:            {info['end_ns'] / 1e9:.9f} s")
    print(f"Messages:       {info['message_count']}")
    print("Topic information:")
    for topic, entry in sorted(info["topics"].items()):
        print(f"  Topic: {topic} | Type: {entry['type']} | Count: {entry['count']} | "
              f"Serialization Format: {entry['encoding']}")
    return 0


def _validate_recover(args: argparse.Namespace) -> None:
    from .io.bag_reader import mcap_files

    check_outputs([Output("OUTPUT", args.output, "new directory")], [args.bag])
    # A damaged bag is what recover is for: only a file that is no MCAP at all is refused.
    mcap_files(args.bag, truncated_ok=True)


def _recover(args: argparse.Namespace) -> int:
    """Every message of the closed chunks of a damaged bag, into a new complete bag."""
    from .io.bag_reader import mcap_files, recover
    from .io.bag_writer import BagWriter

    messages = [m for f in mcap_files(args.bag, truncated_ok=True) for m in recover(f)]
    messages.sort(key=lambda m: m.log_time_ns)
    with BagWriter(args.output) as bag:
        for message in messages:
            bag.add_topic(message.topic, message.type)
            bag.write(message.topic, message.data, message.log_time_ns,
                      message.publish_time_ns)
    print(f"recovered {len(messages)} messages on "
          f"{len({m.topic for m in messages})} topics into {args.output}")
    return 0


def _ros_args(parameters: dict, remaps: list[str]) -> list[str]:
    from .commands.processes import ros_arguments

    return ros_arguments(parameters, remappings=_remappings(remaps))


def _remappings(remaps: list[str]) -> dict[str, str]:
    """``--remap OLD:=NEW`` flags as {OLD: NEW}."""
    pairs = {}
    for remap in remaps:
        source, sep, target = remap.partition(":=")
        if not sep or not source or not target:
            raise ParameterError(f"--remap must be OLD:=NEW, got {remap!r}")
        pairs[source] = target
    return pairs


def _validate_record(args: argparse.Namespace) -> None:
    in_range("--max-bag-size", args.max_bag_size, low=0, what="an integer", unit="bytes; 0: "
             "no split")
    in_range("--max-bag-duration", args.max_bag_duration, low=0, unit="s; 0: no split")
    check_outputs([Output("-o/--output", args.output, "new directory")])


def _record(args: argparse.Namespace) -> int:
    from .nodes.recorder import main as recorder_main

    parameters = {"output": args.output or "", "compression": args.compression,
                  "max_bag_size": args.max_bag_size, "max_bag_duration": args.max_bag_duration}
    if args.topics:
        parameters["topics"] = args.topics
    return recorder_main(["mt-accuracy-record", *_ros_args(parameters, [])])


def _validate_play(args: argparse.Namespace) -> None:
    from .io.bag_reader import mcap_files

    in_range("-r/--rate", args.rate, low=0, low_open=True, what="a speed factor")
    in_range("--start-offset", args.start_offset, low=0, unit="s")
    in_range("--wait-for-subscribers", args.wait_for_subscribers, low=0, unit="s")
    _remappings(args.remap)
    mcap_files(args.bag)


def _play(args: argparse.Namespace) -> int:
    from .nodes.player import main as player_main

    parameters = {"bag": args.bag, "rate": args.rate, "start_offset": args.start_offset,
                  "loop": args.loop, "clock": not args.no_clock,
                  "start_paused": args.start_paused,
                  "wait_for_subscribers_s": args.wait_for_subscribers}
    if args.topics:
        parameters["topics"] = args.topics
    return player_main(["mt-accuracy-play", *_ros_args(parameters, args.remap)])


def _validate_simulate(args: argparse.Namespace) -> None:
    in_range("--csv-stride", args.csv_stride, low=1, what="an integer")
    in_range("--reference-period", args.reference_period, low=0, low_open=True, unit="s")
    if args.no_csv and args.csv_stride is not None:
        raise not_applicable("--csv-stride", "the CSV files", "--no-csv (none is written)")
    if args.no_bag and args.reference_period is not None:
        raise not_applicable("--reference-period", "the bag", "--no-bag (none is written)")
    out = Path(args.out)
    check_outputs([Output("--out", out, "directory")])
    if not args.no_bag and (out / "bag").exists():
        raise ParameterError(f"--out {out}: {out / 'bag'} already exists (a bag is never "
                             "overwritten); give another --out or --no-bag")


def _simulate(args: argparse.Namespace) -> int:
    import json
    import time

    from .sim.export import write_bag, write_csv
    from .sim.machine_tool import simulate
    from .sim.scenario import load_scenario

    scenario = load_scenario(args.scenario)
    out = Path(args.out)
    started = time.perf_counter()
    result = simulate(scenario)
    elapsed = time.perf_counter() - started
    out.mkdir(parents=True, exist_ok=True)
    stride = 1 if args.csv_stride is None else args.csv_stride
    files = [] if args.no_csv else write_csv(result, out, stride=stride)
    if not args.no_bag:
        write_bag(result, out / "bag", progress=not args.quiet,
                  reference_period_s=args.reference_period)
        files.append(out / "bag")
    summary = {"scenario": str(args.scenario), "samples": int(result.time_s.size),
               "channels": result.scale_channels, "effects_on": sorted(scenario.enabled),
               "events": [list(e) for e in scenario.events],
               "simulated_s": scenario.duration_s, "generation_s": elapsed,
               "samples_per_s": result.time_s.size / max(elapsed, 1e-9),
               "files": [str(f) for f in files]}
    (out / "simulation.json").write_text(json.dumps(summary, indent=2))
    if not args.quiet:
        print(json.dumps(summary, indent=2))
    return 0


#: "not added" lines a thermal log's check prints (the JSON holds them all).
SHOWN_REFUSALS = 5
#: Whole models of a thermal log shown with their forward and held-out figures.
SHOWN_CONTESTANTS = 5


#: What ``check`` reads: a bag, a thermal log (a CSV with --target) or a survey (a CSV
#: with a column map), as the refusals name them.
CHECK_DATA_KINDS = {"bag": "a bag", "log": "a thermal log (a CSV with --target)",
                    "survey": "a survey (a CSV with a column map: --columns or --col)"}
#: Each data-specific option of ``check`` (its argparse name), as typed, and the kinds of
#: data whose reader takes it; given with any other it would be ignored, so it is refused.
CHECK_OPTION_SCOPES = {
    "model": ("--model", ("bag", "survey")), "namespace": ("--namespace", ("bag",)),
    "machine": ("--machine", ("survey",)), "columns": ("--columns", ("survey",)),
    "col": ("--col", ("survey",)), "uncertainty_um": ("--uncertainty-um", ("log", "survey")),
    "row_period": ("--row-period", ("log", "survey")),
    "time_column": ("--time-column", ("log",)), "target": ("--target", ("log",)),
    "inputs": ("--inputs", ("log",)), "driver": ("--driver", ("log",)),
    "term": ("--term", ("log",)), "component": ("--component", ("log",)),
    "structure_length": ("--structure-length", ("log",)),
    "train_fraction": ("--train-fraction", ("log",)), "run": ("--run", ("log",)),
    "zeroed_runs": ("--zeroed-runs", ("log",))}
#: Suffixes of table files; other text files are tables too, unless they are descriptions.
TABLE_SUFFIXES = (".csv", ".tsv", ".txt", ".dat")
DESCRIPTION_SUFFIXES = (".yaml", ".yml", ".json", ".xml", ".html")
#: Defaults of the thermal log's options (None in the parser: given or not is known).
LOG_TIME_COLUMN, LOG_TRAIN_FRACTION, LOG_COMPONENT = "time_s", 0.5, "z"


def _is_table(path: Path) -> bool:
    """Whether ``check`` reads ``path`` as a CSV table (by its suffix, or a text file that
    is no description) rather than a bag."""
    from .core.inputs.file_kinds import MCAP_MAGIC, looks_like_text, read_head

    suffix = path.suffix.lower()
    if suffix in TABLE_SUFFIXES:
        return True
    if suffix in DESCRIPTION_SUFFIXES or not path.is_file():
        return False
    try:
        head = read_head(path)
    except OSError:
        return False
    return not head.startswith(MCAP_MAGIC) and looks_like_text(head)


def _check_kind(args: argparse.Namespace) -> str:
    """What ``check``'s DATA is: "bag", "log" or "survey" (:data:`CHECK_DATA_KINDS`)."""
    if not _is_table(Path(args.data)):
        return "bag"
    return "survey" if args.columns or args.col else "log"


def _validate_check(args: argparse.Namespace) -> None:
    kind = _check_kind(args)
    if kind == "log" and not args.target:
        raise ParameterError("a CSV needs --target COLUMN (a thermal log) or a column map "
                             "(--columns FILE.yaml or --col ROLE=COLUMN[:UNIT]) for a "
                             "reference survey")
    for name, (flag, kinds) in CHECK_OPTION_SCOPES.items():
        if kind not in kinds and getattr(args, name) not in (None, False, "", []):
            raise not_applicable(flag, " or ".join(CHECK_DATA_KINDS[k] for k in kinds),
                                 CHECK_DATA_KINDS[kind])
    if kind == "log":
        from .commands.check_log import validate_log_options

        # The thermal log's own rule (one implementation), before any row is read.
        validate_log_options(args.auto, LOG_TRAIN_FRACTION if args.train_fraction is None
                             else args.train_fraction)
        if args.zeroed_runs and not args.run:
            raise ParameterError("--zeroed-runs needs --run COLUMN (the instrument was zeroed "
                                 "at each run's start)")
    in_range("--auto", args.auto, low=0, what="an integer")
    in_range("--min-reduction", args.min_reduction, low=0, high=1, high_open=True,
             what="a fraction")
    in_range("--uncertainty-um", args.uncertainty_um, low=0, low_open=True, unit="um, k = 2")
    in_range("--row-period", args.row_period, low=0, low_open=True, unit="s")
    in_range("--structure-length", args.structure_length, low=0, low_open=True, unit="m")
    check_outputs([Output("--json", args.json), Output("--report", args.report)],
                  [args.data, args.columns])
    if kind == "bag" and Path(args.data).exists():
        from .io.bag_reader import mcap_files

        mcap_files(args.data)       # a truncated or foreign bag: refused before the model


def _column_map(args: argparse.Namespace):
    """The survey's column map from --columns and --col."""
    import yaml

    from .io.column_map import ColumnMap, column_map_from_dict, parse_col_flags

    column_map = ColumnMap()
    if args.columns:
        try:
            text = Path(args.columns).read_text()
            column_map = column_map_from_dict(yaml.safe_load(text), args.columns)
        except (OSError, yaml.YAMLError) as exc:
            raise InputDataError(f"column map {args.columns}: {exc}") from exc
    column_map = parse_col_flags(args.col or [], column_map)
    if args.uncertainty_um is not None:
        column_map.uncertainty_m = args.uncertainty_um * 1e-6
    if args.row_period is not None:
        column_map.row_period_s = args.row_period
    return column_map


def _check_result(args: argparse.Namespace) -> dict:
    """``check``'s result of its DATA, by kind (the options checked by
    :func:`_validate_check`)."""
    from .commands.check import check_bag, check_mapped_csv
    from .commands.check_log import check_csv

    data = Path(args.data)
    kind = _check_kind(args)
    if kind == "survey":
        return check_mapped_csv(data, _column_map(args), args.model, args.add or [], args.auto,
                                args.min_reduction, machine=args.machine)
    if kind == "log":
        return check_csv(
            data, args.target, args.time_column or LOG_TIME_COLUMN, args.inputs or ["*"],
            args.driver or [], args.add or [], args.auto,
            LOG_TRAIN_FRACTION if args.train_fraction is None else args.train_fraction,
            args.min_reduction, args.term or [], row_period_s=args.row_period,
            component=args.component or LOG_COMPONENT,
            uncertainty_m=None if args.uncertainty_um is None else args.uncertainty_um * 1e-6,
            structure_length_m=args.structure_length, run_column=args.run,
            zeroed_runs=args.zeroed_runs)
    return check_bag(data, args.model or "demo", args.add or [], args.auto,
                     args.namespace or "", args.min_reduction)


def _check(args: argparse.Namespace) -> int:
    from .commands.check import write_outputs

    result = _check_result(args)
    write_outputs(result, args.json, args.report)
    if result.get("rows_note"):
        print(result["rows_note"])
    for key in ("machine_note", "travel_warning"):
        if result.get(key):
            print(result[key])
    for line in result.get("warnings", []):
        print(line)
    # A thermal log speaks its target's unit, a survey or a bag micrometres (a metrologist's
    # unit); the JSON stays SI.
    log = result["kind"] == "thermal_log"
    unit = result["target_unit"] if log else "um"
    scale = result["target_unit_per_m"] if log else 1e6
    if log:
        lines = result.get("not_added_lines", [])
        for line in lines[:SHOWN_REFUSALS]:
            print(line)
        if len(lines) > SHOWN_REFUSALS:
            print(f"... and {len(lines) - SHOWN_REFUSALS} more not added (the JSON's not_added)")
        for line in result.get("notes", []):
            print(f"note: {line}")
        print(f"held-out RMSE (rows after the first {result['train_rows']}) "
              f"{result['held_out_baseline_rmse'] * scale:.4g} {unit}; a constant's "
              f"{result['constant_held_out_rmse'] * scale:.4g} {unit}; least squares on every "
              f"input {result['all_inputs_least_squares_held_out_rmse'] * scale:.4g} {unit}")
        contest = result.get("model_contest", [])
        if len(contest) > 1:
            print("whole models contested (forward over the training blocks -> held out; "
                  "the held-out figure decided nothing):")
            for entry in contest[:SHOWN_CONTESTANTS]:
                name = entry["name"] if entry["name"] != "step by step" else \
                    f"step by step ({', '.join(entry['terms']) or 'nothing added'})"
                print(f"  {'*' if entry['chosen'] else ' '} {name[:60]:60s} "
                      f"{entry['forward_rmse'] * scale:.4g} -> "
                      f"{entry['held_out_rmse'] * scale:.4g} {unit}")
        for run in result.get("runs") or []:
            print(f"  run {run['run']:>12s} ({run['part']}, {run['rows']} rows): constant "
                  f"{run['constant_rmse'] * scale:.4g}, least squares "
                  f"{run['least_squares_rmse'] * scale:.4g}, model "
                  f"{run['model_rmse'] * scale:.4g} {unit} RMS")
    print(f"baseline RMSE {result['baseline_rmse'] * scale:.4g} {unit}")
    for entry in result["ranking"][:5]:
        flag = "*" if entry["significant"] else " "
        print(f" {flag} {entry.get('name', entry['effect'])[:60]:60s} CV RMSE after "
              f"{entry['cv_rmse_after'] * scale:.4g} {unit} "
              f"({100 * entry['error_reduction']:.1f} %)")
    for entry in result.get("named", []):
        print(f"named: {entry['name']} (confidence {100 * entry['confidence']:.0f} %): "
              f"{entry['explanation']}")
        readings = "; ".join(f"{k} = {v}" for k, v in entry.get("display", {}).items())
        if readings:
            setting = entry.get("setting_display", "")
            print(f"       {readings} (U, k = 2){'; ' + setting if setting else ''}")
    for entry in result.get("dropped", []):
        print(entry["sentence"])
    if result.get("localisation", {}).get("sentence"):
        print(f"where: {result['localisation']['sentence']}")
    if result.get("verdict"):
        print(f"verdict: {result['verdict']}")
    if result.get("sensors_carrying_weight"):
        whose = (result.get("sensors_carrying_weight_of") or {}).get("words",
                                                                      "the sensor model")
        print(f"{whose} leans on: " +
              ", ".join(f"{sensor} {100 * share:.0f} %" for sensor, share in
                        result["sensors_carrying_weight"].items()))
    print(f"added: {', '.join(result['added']) or 'nothing'}; final "
          f"{'held-out ' if log else ''}RMSE {result['final_rmse'] * scale:.4g} {unit}")
    return 0


def _validate_fleet(args: argparse.Namespace) -> None:
    if args.scheduler and args.workers is not None:
        raise not_applicable("--workers", "the local cluster", "--scheduler (its workers "
                             "are the scheduler's)")
    in_range("--workers", args.workers, low=1, what="an integer")
    in_range("--auto", args.auto, low=0, what="an integer")
    in_range("--min-reduction", args.min_reduction, low=0, high=1, high_open=True,
             what="a fraction")
    check_outputs([Output("--json", args.json), Output("--report", args.report)],
                  [*args.inputs, args.columns])


def _fleet(args: argparse.Namespace) -> int:
    from .commands.fleet import print_summary, run_fleet, write_fleet_outputs

    # A bad input is one line on stderr and exit 2, by main().
    workers = args.workers if args.workers is not None else os.cpu_count() or 1
    summary = run_fleet(args.inputs, model=args.model, columns=args.columns,
                        scheduler=args.scheduler, workers=workers, auto=args.auto,
                        min_reduction=args.min_reduction, progress=not args.quiet)
    write_fleet_outputs(summary, args.json, args.report)
    print_summary(summary)
    if args.report:
        print(f"report: {args.report}")
    # Refused files are findings of the fleet, not a failure of the command; nothing
    # read at all is.
    return 0 if summary["day_count"] else 1


#: Expansion coefficients a material may have [um/m/K] (Invar ~1, steel 11.5, aluminium
#: 23, polymers up to ~200); below :data:`EXPANSION_PER_K_LIKE` a value is one in 1/K.
EXPANSION_LIMIT_UM_M_K = 300.0
EXPANSION_PER_K_LIKE = 1e-3


def _validate_iso230_2(args: argparse.Namespace) -> None:
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


def _iso230_2(args: argparse.Namespace) -> int:
    from .commands.iso230 import evaluate_run, print_run, write_run_outputs

    # A bad run is one line on stderr and exit 2, by main().
    expansion = None if args.expansion is None else args.expansion * 1e-6
    result = evaluate_run(Path(args.run), args.col or [], args.axis.upper(), expansion)
    print_run(result)
    write_run_outputs(result, args.json, args.report)
    return 0


def _validate_seed_and_simulation_options(args: argparse.Namespace,
                                          simulation_only: dict[str, str]) -> None:
    """--simulate SEED >= 0, and the options only a simulation reads refused without it."""
    in_range("--simulate", args.simulate, low=0, what="an integer seed")
    if args.simulate is None:
        for name, flag in simulation_only.items():
            if getattr(args, name) not in (None, False):
                raise not_applicable(flag, "a simulated measurement (--simulate SEED)",
                                     f"a measured file ({args.file})")


def _file_outputs(args: argparse.Namespace) -> None:
    """--json, --report and, with --simulate, FILE (written first) checked as outputs."""
    outputs = [Output("--json", args.json), Output("--report", args.report)]
    if args.simulate is not None:
        outputs.append(Output("FILE (written by --simulate)", args.file))
    check_outputs(outputs, [] if args.simulate is not None else [args.file])


def _validate_ballbar(args: argparse.Namespace) -> None:
    in_range("--radius-mm", args.radius_mm, low=0, low_open=True, unit="mm")
    in_range("--socket-height-mm", args.socket_height_mm, unit="mm")
    in_range("--socket-change-um", args.socket_change_um, low=0, unit="um")
    _validate_seed_and_simulation_options(args, {"scenario": "--scenario",
                                                 "backlash": "--backlash"})
    _file_outputs(args)


def _validate_probe(args: argparse.Namespace) -> None:
    in_range("--sphere-radius-mm", args.sphere_radius_mm, low=0, low_open=True, unit="mm")
    for axis, value in zip("XYZ", args.sphere_mm):
        in_range(f"--sphere-mm ({axis})", value, unit="mm")
    in_range("--tolerance-um", args.tolerance_um, low=0, low_open=True, unit="um")
    _validate_seed_and_simulation_options(args, {})
    _file_outputs(args)


#: Options of ``export`` that one controller's tables read (argparse name: flag, controller).
EXPORT_CONTROLLER_OPTIONS = {"unilateral": ("--unilateral", "twincat"),
                             "fanuc_step_limit": ("--fanuc-step-limit", "fanuc")}


def _validate_export(args: argparse.Namespace) -> None:
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


class _Parser(argparse.ArgumentParser):
    """No abbreviated options anywhere (``--rat 2`` is an error, not ``--rate 2``);
    subcommands' parsers are of this class too (argparse makes them with type(parent))."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="mt-accuracy",
        description="Live accuracy monitor and volumetric compensation for CNC machine tools.")
    commands = parser.add_subparsers(dest="command", required=True)
    demo = commands.add_parser("demo", help="run the main job on the virtual machine tool")
    demo.add_argument("--out", default="demo_output", help="output directory")
    demo.add_argument("--rate", type=float, default=None,
                      help="sim seconds per wall second (the 90 s scenario takes 90/rate s; "
                           "default 1: real time, 10 ms scale batches and a 20 ms controller "
                           "delay; at rate r both are r times longer in data time)")
    demo.add_argument("--scenario", default=None,
                      help="bundled scenario or path (default: the machine's demo scenario)")
    demo.add_argument("--machine", default="kidani_hmc", choices=sorted(DEMO_SCENARIOS),
                      help="the virtual machine: the 3-axis HMC (scenario 'demo'), a 3-axis "
                           "VMC with the work on X and Y tables (scenario 'demo_vmc'), Khan "
                           "& Chen's 5-axis RPPPR grinder (scenario 'demo_5axis') or a 5-axis "
                           "trunnion VMC (scenario 'demo_trunnion')")
    demo.add_argument("--compensation", default="hybrid",
                      choices=["hybrid", "realtime", "table", "off"],
                      help="how the virtual CNC takes the compensation: tables + real-time "
                           "offset (hybrid, default), real-time offset only, tables only, or off")
    demo.add_argument("--niceness", type=int, default=-15,
                      help="niceness of the compensation path's nodes (CNC, estimator, "
                           "broadcaster; default -15: the CPU first when the host is loaded; "
                           "0 = as started). Without the right to it they warn and run as is")
    demo.add_argument("--lockstep", action="store_true",
                      help="stream in data time: the machine sends each batch once every node "
                           "of the loop has caught up, so the outcome is the same on any host "
                           "(the tests run so); not with --rate")
    demo.set_defaults(handler=_demo, validate=_validate_demo)
    info = commands.add_parser("info", help="counts, duration, topics and types of a bag")
    info.add_argument("bag", help="bag directory or .mcap file")
    info.set_defaults(handler=_info)
    salvage = commands.add_parser("recover", help="save the closed chunks of a damaged bag "
                                  "(a killed recorder) into a new complete bag")
    salvage.add_argument("bag", help="damaged bag directory or .mcap file")
    salvage.add_argument("output", help="new bag directory (must not exist)")
    salvage.set_defaults(handler=_recover,
                         validate=_validate_recover)
    record = commands.add_parser("record", help="record topics to a rosbag2-compatible MCAP bag")
    record.add_argument("topics", nargs="*", help="topics to record (none: all)")
    record.add_argument("-o", "--output", help="bag directory (default rosbag2_<date>)")
    record.add_argument("--compression", choices=["zstd", "none"], default="zstd")
    record.add_argument("--max-bag-size", type=int, default=0, help="split after N bytes")
    record.add_argument("--max-bag-duration", type=float, default=0.0,
                        help="split after S seconds")
    record.set_defaults(handler=_record, validate=_validate_record)
    sim = commands.add_parser("simulate", help="run a scenario on the virtual machine tool")
    sim.add_argument("scenario", help="scenario YAML (see mt_accuracy_ros.sim.scenario)")
    sim.add_argument("--out", required=True, help="output directory (bag/ and CSV files)")
    sim.add_argument("--no-bag", action="store_true")
    sim.add_argument("--no-csv", action="store_true")
    sim.add_argument("--csv-stride", type=int, default=None,
                     help="write every N-th sample (default 1: every one)")
    sim.add_argument("--reference-period", type=float, default=None, metavar="S",
                     help="bag: a reference probe's TCP error every S seconds of data time "
                          "(the uncompensated machine; what mt-accuracy check and fleet read)")
    sim.add_argument("-q", "--quiet", action="store_true")
    sim.set_defaults(handler=_simulate,
                     validate=_validate_simulate)
    check = commands.add_parser("check", help="model vs measurement: rank missing effects, add them")
    check.add_argument("data", help="bag (this package's topics) or CSV file")
    check.add_argument("--model", default=None,
                       help="model: bundled name, path or inline YAML (default: 'demo' for a "
                            "bag; for a survey, none - see --machine)")
    check.add_argument("--machine", default=None,
                       help="survey CSV: the machine it was taken on, a bundled name or a "
                            "machine YAML (default: a generic Cartesian machine over the "
                            "surveyed travel); readings outside its travel are warned about")
    check.add_argument("--add", action="append", metavar="EFFECT", help="add this effect (repeat)")
    check.add_argument("--auto", type=int, default=0, metavar="N",
                       help="add up to N top significant candidates by themselves")
    check.add_argument("--report", help="HTML report path")
    check.add_argument("--json", help="JSON summary path")
    check.add_argument("--namespace", default=None, help="bag: machine namespace in the bag "
                       "(/mt1)")
    check.add_argument("--min-reduction", type=float, default=0.05,
                       help="smallest CV error reduction that counts")
    check.add_argument("--columns", metavar="FILE.yaml",
                       help="CSV survey: column map (which column is which axis, error, "
                            "temperature, and its unit)")
    check.add_argument("--col", action="append", metavar="ROLE=COLUMN[:UNIT]",
                       help="CSV survey: one column of the map, e.g. pos.X=x_mm:mm, err.x=dev:um, "
                            "temp.column=T3:degC, time=t:min, vel.X=f:mm/min, spindle=S:rpm")
    check.add_argument("--uncertainty-um", type=float, default=None,
                       help="CSV survey: the instrument's k = 2 uncertainty [um]")
    check.add_argument("--row-period", type=float, default=None,
                       help="CSV survey without a time column: seconds between rows")
    check.add_argument("--time-column", default=None,
                       help=f"CSV log: time column [s] (default {LOG_TIME_COLUMN})")
    check.add_argument("--target", metavar="COLUMN[:UNIT]",
                       help="CSV log: the measured displacement column (unit from the flag or "
                            "the name's suffix, e.g. ch5_um)")
    check.add_argument("--inputs", nargs="+", help="CSV log: temperature columns [degC] "
                       "(names or patterns)")
    check.add_argument("--driver", nargs="+", metavar="COLUMN[:UNIT]",
                       help="CSV log: the spindle speed (rpm, rad/s, Hz), a heat source")
    check.add_argument("--term", action="append",
                       help="CSV log: effects the starting model holds (fitted first)")
    check.add_argument("--component", default=None, choices=["x", "y", "z"],
                       help="CSV log: the direction the target displacement is measured in "
                            f"(default {LOG_COMPONENT})")
    check.add_argument("--structure-length", type=float, default=None, metavar="METRES",
                       help="CSV log: structure between the sensors and the tool (bounds a "
                            "physical thermal gain; default 1 m)")
    check.add_argument("--train-fraction", type=float, default=None,
                       help="CSV log: fit on this leading fraction, judge on the rest (with "
                            f"--run: at the run boundary nearest it; default "
                            f"{LOG_TRAIN_FRACTION})")
    check.add_argument("--run", metavar="COLUMN",
                       help="CSV log of many runs: rows of one run share this column's value "
                            "(time restarts or jumps between runs; lags restart each run; "
                            "whole runs judge one another)")
    check.add_argument("--zeroed-runs", action="store_true",
                       help="CSV log with --run: the instrument was zeroed at each run's "
                            "start (each run has its own zero; default: absolute readings)")
    check.set_defaults(handler=_check, validate=_validate_check)
    fleet = commands.add_parser("fleet", help="diagnose many machines' bags and surveys on "
                                "Dask: error over time, shared effects, drift ranked")
    fleet.add_argument("inputs", nargs="+", metavar="INPUT",
                       help="a directory (a folder per machine), a glob (the folder holding "
                            "each match names its machine) or a manifest YAML (machines: "
                            "{NAME: {data: [globs], model:, machine:, columns:}})")
    fleet.add_argument("--scheduler", metavar="ADDRESS",
                       help="an existing Dask scheduler (tcp://host:8786) whose workers have "
                            "this package; default: a local cluster of --workers processes")
    fleet.add_argument("--workers", type=int, default=None,
                       help="worker processes of the local cluster (default: one per core; "
                            "not with --scheduler)")
    fleet.add_argument("--model", default=None,
                       help="model of the machines that have none of their own (bags: "
                            "default 'demo'; a folder's model.yaml or the manifest's model: "
                            "wins)")
    fleet.add_argument("--columns", metavar="FILE.yaml",
                       help="column map of the surveys whose machine has none of its own")
    fleet.add_argument("--auto", type=int, default=3, metavar="N",
                       help="name up to N effects per machine-day (default 3)")
    fleet.add_argument("--min-reduction", type=float, default=0.05,
                       help="smallest CV error reduction that counts")
    fleet.add_argument("--json", help="JSON summary path (every machine-day's result)")
    fleet.add_argument("--report", help="HTML fleet report path")
    fleet.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    fleet.set_defaults(handler=_fleet, validate=_validate_fleet)
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
    iso.set_defaults(handler=_iso230_2,
                     validate=_validate_iso230_2)
    play = commands.add_parser("play", help="publish a bag's messages in recorded time, with /clock")
    play.add_argument("bag", help="bag directory or .mcap file")
    play.add_argument("--topics", nargs="+", help="topics to play (default all)")
    play.add_argument("-r", "--rate", type=float, default=1.0, help="speed factor")
    play.add_argument("--start-offset", type=float, default=0.0, help="skip S seconds")
    play.add_argument("-l", "--loop", action="store_true")
    play.add_argument("--remap", action="append", default=[], metavar="OLD:=NEW")
    play.add_argument("--no-clock", action="store_true", help="do not publish /clock")
    play.add_argument("--start-paused", action="store_true")
    play.add_argument("--wait-for-subscribers", type=float, default=0.0, metavar="S",
                      help="wait up to S seconds for subscribers before playing")
    play.set_defaults(handler=_play, validate=_validate_play)
    from .commands.model_tools import add_parser as add_model_parser
    from .commands.rotary_tools import add_parser as add_rotary_parser
    from .commands.topic_tools import add_parser as add_topic_parser

    add_topic_parser(commands)
    add_model_parser(commands)
    add_rotary_parser(commands)
    # The rotary tools' options, checked here before their handlers run.
    for name, validate in (("ballbar", _validate_ballbar), ("probe", _validate_probe),
                           ("export", _validate_export)):
        commands.choices[name].set_defaults(validate=validate)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run a command; every user error is one line on stderr and exit status 2."""
    from .core.errors import MtAccuracyError

    from .allocator import keep_freed_arrays

    parser = build_parser()
    args = parser.parse_args(argv)
    # The commands' numerics allocate and free arrays of megabytes: from the heap.
    keep_freed_arrays()
    try:
        # Every option and output path before any work: a refusal writes nothing.
        validate = getattr(args, "validate", None)
        if validate is not None:
            validate(args)
        return int(args.handler(args) or 0)
    except (MtAccuracyError, OSError, ValueError, KeyError) as exc:
        text = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
        message = " ".join(str(text).split())
        print(f"mt-accuracy {args.command}: {message}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
