"""``mt-accuracy record``: topics to a rosbag2-compatible MCAP bag, by the recorder node."""
from __future__ import annotations

import argparse

from ..core.inputs.options import in_range
from ..io.output_paths import Output, check_outputs


def validate_record(args: argparse.Namespace) -> None:
    """Split sizes and durations of 0 or more; the bag a new directory."""
    in_range("--max-bag-size", args.max_bag_size, low=0, what="an integer", unit="bytes; 0: "
             "no split")
    in_range("--max-bag-duration", args.max_bag_duration, low=0, unit="s; 0: no split")
    if args.output is None:
        # Named here, so that the working directory is checked before anything starts.
        from ..io.bag_writer import default_bag_name

        args.output = default_bag_name()
        print(f"mt-accuracy record: no -o/--output: recording to ./{args.output}")
    check_outputs([Output("-o/--output", args.output, "new directory")])


def record_command(args: argparse.Namespace) -> int:
    """Run the recorder node with the options as its parameters."""
    from ..nodes.recorder import main as recorder_main
    from .processes import ros_arguments

    parameters = {"output": args.output or "", "compression": args.compression,
                  "max_bag_size": args.max_bag_size, "max_bag_duration": args.max_bag_duration}
    if args.topics:
        parameters["topics"] = args.topics
    return recorder_main(["mt-accuracy-record", *ros_arguments(parameters, remappings={})])


def add_parser(commands) -> None:
    """``record`` on the subcommands ``commands``."""
    record = commands.add_parser("record", help="record topics to a rosbag2-compatible MCAP bag")
    record.add_argument("topics", nargs="*", help="topics to record (none: all)")
    record.add_argument("-o", "--output", help="bag directory (default rosbag2_<date>)")
    record.add_argument("--compression", choices=["zstd", "none"], default="zstd")
    record.add_argument("--max-bag-size", type=int, default=0, help="split after N bytes")
    record.add_argument("--max-bag-duration", type=float, default=0.0,
                        help="split after S seconds")
    record.set_defaults(handler=record_command, validate=validate_record)
