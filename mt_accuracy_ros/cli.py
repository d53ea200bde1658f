"""The ``mt-accuracy`` command line."""
from __future__ import annotations

import argparse
import sys


def _demo(args: argparse.Namespace) -> int:
    from .demo import run_demo

    return run_demo(out_dir=args.out, duration_s=args.duration)


def _info(args: argparse.Namespace) -> int:
    from .core.errors import BagError
    from .io.bag_reader import bag_info

    try:
        info = bag_info(args.bag)
    except BagError as exc:
        print(f"mt-accuracy info: {exc}", file=sys.stderr)
        return 2
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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mt-accuracy",
        description="Live accuracy monitor and volumetric compensation for CNC machine tools.")
    commands = parser.add_subparsers(dest="command", required=True)
    demo = commands.add_parser("demo", help="run the main job on the virtual machine tool")
    demo.add_argument("--out", default="demo_output", help="output directory")
    demo.add_argument("--duration", type=float, default=6.0,
                      help="simulated run time [s]")
    demo.set_defaults(handler=_demo)
    info = commands.add_parser("info", help="counts, duration, topics and types of a bag")
    info.add_argument("bag", help="bag directory or .mcap file")
    info.set_defaults(handler=_info)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    return int(args.handler(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
