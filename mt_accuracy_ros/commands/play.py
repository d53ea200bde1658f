"""``mt-accuracy play``: a bag's messages published in recorded time, with /clock, by the
player node."""
from __future__ import annotations

import argparse

from ..core.errors import ParameterError
from ..core.inputs.options import in_range


def remappings(remaps: list[str]) -> dict[str, str]:
    """``--remap OLD:=NEW`` flags as {OLD: NEW}.

    Raises
    ------
    ParameterError
        A flag that is not OLD:=NEW.
    """
    pairs = {}
    for remap in remaps:
        source, sep, target = remap.partition(":=")
        if not sep or not source or not target:
            raise ParameterError(f"--remap must be OLD:=NEW, got {remap!r}")
        pairs[source] = target
    return pairs


def validate_play(args: argparse.Namespace) -> None:
    """A positive rate, offsets of 0 or more, remaps OLD:=NEW, and an MCAP bag."""
    from ..io.bag_reader import mcap_files

    in_range("-r/--rate", args.rate, low=0, low_open=True, what="a speed factor")
    in_range("--start-offset", args.start_offset, low=0, unit="s")
    in_range("--wait-for-subscribers", args.wait_for_subscribers, low=0, unit="s")
    remappings(args.remap)
    mcap_files(args.bag)


def play_command(args: argparse.Namespace) -> int:
    """Run the player node with the options as its parameters."""
    from ..nodes.player import main as player_main
    from .processes import ros_arguments

    parameters = {"bag": args.bag, "rate": args.rate, "start_offset": args.start_offset,
                  "loop": args.loop, "clock": not args.no_clock,
                  "start_paused": args.start_paused,
                  "wait_for_subscribers_s": args.wait_for_subscribers}
    if args.topics:
        parameters["topics"] = args.topics
    return player_main(["mt-accuracy-play",
                        *ros_arguments(parameters, remappings=remappings(args.remap))])


def add_parser(commands) -> None:
    """``play`` on the subcommands ``commands``."""
    play = commands.add_parser("play", help="publish a bag's messages in recorded time, "
                               "with /clock")
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
    play.set_defaults(handler=play_command, validate=validate_play)
