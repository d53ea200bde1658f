"""``mt-accuracy simulate``: a scenario on the virtual machine tool, written as a bag and
CSV files with a summary (``simulation.json``)."""
from __future__ import annotations

import argparse
from pathlib import Path

from ..core.errors import ParameterError
from ..core.inputs.options import in_range, not_applicable
from ..io.output_paths import Output, check_outputs


def validate_simulate(args: argparse.Namespace) -> None:
    """A stride of 1 or more and a positive reference period, each only where it is read;
    an output directory whose bag does not exist yet."""
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


def simulate_command(args: argparse.Namespace) -> int:
    """Simulate the scenario, write its files and its summary (printed unless quiet)."""
    import json
    import time

    from ..sim.export import write_bag, write_csv
    from ..sim.machine_tool import simulate
    from ..sim.scenario import load_scenario

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


def add_parser(commands) -> None:
    """``simulate`` on the subcommands ``commands``."""
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
    sim.set_defaults(handler=simulate_command, validate=validate_simulate)
