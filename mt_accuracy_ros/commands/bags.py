"""``mt-accuracy info`` and ``mt-accuracy recover``: what a bag holds, and the closed
chunks of a damaged one saved into a new complete bag."""
from __future__ import annotations

import argparse

from ..io.output_paths import Output, check_outputs


def info_command(args: argparse.Namespace) -> int:
    """Print the files, duration, span, message count and topics of ``args.bag``."""
    from ..io.bag_reader import bag_info

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


def validate_recover(args: argparse.Namespace) -> None:
    """The output a new directory; the bag at least an MCAP file, truncated or not."""
    from ..io.bag_reader import mcap_files

    check_outputs([Output("OUTPUT", args.output, "new directory")], [args.bag])
    # A damaged bag is what recover is for: only a file that is no MCAP at all is refused.
    mcap_files(args.bag, truncated_ok=True)


def recover_command(args: argparse.Namespace) -> int:
    """Every message of the closed chunks of a damaged bag, into a new complete bag."""
    from ..io.bag_reader import mcap_files, recover
    from ..io.bag_writer import BagWriter

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


def add_parser(commands) -> None:
    """``info`` and ``recover`` on the subcommands ``commands``."""
    info = commands.add_parser("info", help="counts, duration, topics and types of a bag")
    info.add_argument("bag", help="bag directory or .mcap file")
    info.set_defaults(handler=info_command)
    salvage = commands.add_parser("recover", help="save the closed chunks of a damaged bag "
                                  "(a killed recorder) into a new complete bag")
    salvage.add_argument("bag", help="damaged bag directory or .mcap file")
    salvage.add_argument("output", help="new bag directory (must not exist)")
    salvage.set_defaults(handler=recover_command, validate=validate_recover)
