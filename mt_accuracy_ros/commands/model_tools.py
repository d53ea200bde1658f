"""``mt-accuracy model``: change the live model from a terminal (add, remove, refit, show).

``add``, ``remove`` and ``refit`` ask the model monitor through its ``change_model``
service (:mod:`..nodes._model_client`) with the effects to add, remove or refit; the
monitor fits what is added (or refits what it holds) to the readings it holds,
gates it and publishes the new version on ``model``, which the compensation
broadcaster follows, and answers once that is done. The command prints the version
made; a refusal - at validation (an unknown effect, one not in the model, too few
readings) or when the change could not be made (physics refuses the fit, the gate
the fitted model) - is the command's one-line error, exit status 2. ``show`` prints
the live version from ``model``.
"""
from __future__ import annotations

import argparse
import math
import time

from ..core.errors import ParameterError

#: Default wall seconds ``add``/``remove``/``refit`` wait for the monitor's answer: it
#: comes once the change is made, a five-axis fit taking seconds of CPU on a busy host.
CHANGE_TIMEOUT_S = 120.0


def set_remote_parameter(node, target: str, name: str, value, timeout_s: float = 30.0,
                         *, resend_after_s: float | None = None,
                         executor=None) -> tuple[bool, str]:
    """Set parameter ``name`` of node ``target`` through its set_parameters service.

    Returns (accepted, reason); (False, why) when the service is missing or silent.
    With ``resend_after_s``, a request still unanswered after that long is sent again
    (the first answer counts): a request sent before the server's reader matched this
    client is lost without a trace, which a node that has just started makes likely.
    Only for settings whose repetition changes nothing. ``executor``: the one that holds
    ``node`` (a node kept by its own executor must be spun by it), else rclpy's global.
    """
    import rclpy
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter

    client = node.create_client(SetParameters, f"{target}/set_parameters")
    try:
        if not client.wait_for_service(timeout_sec=min(10.0, timeout_s)):
            return False, f"{target}/set_parameters not available (is the node running?)"
        request = SetParameters.Request(
            parameters=[Parameter(name, value=value).to_parameter_msg()])
        futures = [client.call_async(request)]
        deadline = time.monotonic() + timeout_s
        resend_at = math.inf if resend_after_s is None else time.monotonic() + resend_after_s
        while not any(f.done() for f in futures) and time.monotonic() < deadline:
            if executor is None:
                rclpy.spin_once(node, timeout_sec=0.05)
            else:
                executor.spin_once(timeout_sec=0.05)
            if time.monotonic() >= resend_at:
                futures.append(client.call_async(request))
                resend_at = time.monotonic() + resend_after_s
        answered = [f for f in futures if f.done()]
        for future in futures:
            if not future.done():
                client.remove_pending_request(future)
        if not answered:
            return False, f"{target} did not answer within {timeout_s:.0f} s"
        result = answered[0].result().results[0]
        return bool(result.successful), str(result.reason)
    finally:
        node.destroy_client(client)


def _change(args: argparse.Namespace) -> int:
    import rclpy

    from ..nodes._model_client import change_model

    effects = list(args.effects) or ["all"]   # refit with no names: every fitted effect
    rclpy.init()
    node = rclpy.create_node("mt_accuracy_model_tool")
    try:
        outcome = change_model(node, args.monitor, timeout_s=args.timeout,
                               **{f"{args.verb}_effects": effects})
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    if not outcome.accepted:
        raise ParameterError(f"{args.verb} {' '.join(effects)} refused: {outcome.reason}")
    print(f"{args.verb} {' '.join(effects)}: accepted by {args.monitor} - version "
          f"{outcome.version} live ({outcome.reason})")
    return 0


def _show(args: argparse.Namespace) -> int:
    import rclpy

    from mt_accuracy_msgs.msg import ModelVersion

    from ..nodes._common import LATCHED_QOS

    rclpy.init()
    node = rclpy.create_node("mt_accuracy_model_tool")
    seen: list = []
    try:
        node.create_subscription(ModelVersion, "model", seen.append, LATCHED_QOS)
        deadline = time.monotonic() + args.timeout
        while not seen and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.05)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    if not seen:
        raise ParameterError(f"no model on 'model' within {args.timeout:.0f} s "
                             "(is the model monitor running?)")
    live = seen[-1]
    print(f"version {live.version}: {live.reason}\neffects: {', '.join(live.effects)}\n")
    print(live.model_yaml.rstrip())
    return 0


def validate_args(args: argparse.Namespace) -> None:
    """Refuse, in one line, a --timeout that is not a finite number of seconds > 0 or a
    --monitor that is no node name."""
    from ..core.inputs.options import in_range

    in_range("--timeout", args.timeout, low=0, low_open=True, unit="s")
    monitor = getattr(args, "monitor", "/model_monitor")
    if not monitor.strip() or any(c.isspace() for c in monitor):
        raise ParameterError(f"--monitor must be a node name (/model_monitor), got {monitor!r}")


def add_parser(commands) -> None:
    """The ``model`` sub-command and its verbs."""
    model = commands.add_parser("model", help="change or show the live model (add / remove "
                                "effects at run time)")
    verbs = model.add_subparsers(dest="verb", required=True)
    for verb, text in (("add", "fit effects to the monitor's readings and add them"),
                       ("remove", "take effects out of the live model"),
                       ("refit", "refit the live model's fitted effects on the readings the "
                        "monitor holds now (none named: all of them)")):
        parser = verbs.add_parser(verb, help=text)
        parser.add_argument("effects", nargs="*" if verb == "refit" else "+", metavar="EFFECT")
        parser.add_argument("--monitor", default="/model_monitor",
                            help="the model monitor node (default /model_monitor)")
        parser.add_argument("--timeout", type=float, default=CHANGE_TIMEOUT_S, metavar="S")
        parser.set_defaults(handler=_change, validate=validate_args)
    show = verbs.add_parser("show", help="print the live model version")
    show.add_argument("--timeout", type=float, default=10.0, metavar="S")
    show.set_defaults(handler=_show, validate=validate_args)
