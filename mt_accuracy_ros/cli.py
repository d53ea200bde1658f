"""The ``mt-accuracy`` command line: the commands of :mod:`.commands`, assembled.

Each command module declares its subcommands (``add_parser(commands)``) with their
handler and validator (``set_defaults(handler=..., validate=...)``). Every option is
checked before any work, by the command's validator, run by :func:`main` before the
handler: a value out of its range, an option given where nothing reads it, an output
path that cannot be written (:mod:`~mt_accuracy_ros.io.output_paths`) is refused in one
line naming the flag, the value and what was expected. Every refusal is raised as a
:class:`~.core.errors.MtAccuracyError` that :func:`main` prints as one line with exit
status 2; no command prints its own errors.
"""
from __future__ import annotations

import argparse
import sys


class _Parser(argparse.ArgumentParser):
    """No abbreviated options anywhere (``--rat 2`` is an error, not ``--rate 2``);
    subcommands' parsers are of this class too (argparse makes them with type(parent))."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)


def build_parser() -> argparse.ArgumentParser:
    """The parser of every command, each declared by its module's ``add_parser``, in the
    order ``--help`` lists them."""
    from .commands import (bags, check, demo, fleet, iso230, model_tools, play, record,
                           rotary_tools, simulate, topic_tools)

    parser = _Parser(
        prog="mt-accuracy",
        description="Live accuracy monitor and volumetric compensation for CNC machine tools.")
    commands = parser.add_subparsers(dest="command", required=True)
    for module in (demo, bags, record, simulate, check, fleet, iso230, play, topic_tools,
                   model_tools, rotary_tools):
        module.add_parser(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run a command; every user error is one line on stderr and exit status 2."""
    from .allocator import keep_freed_arrays
    from .core.errors import MtAccuracyError

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
