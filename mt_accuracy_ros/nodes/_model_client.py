"""The model monitor's ``change_model`` service, called from another node.

The one implementation of that call, for ``mt-accuracy model add|remove|refit`` and the
demo's user. The monitor answers once the change is made (fitted, gated, published) or
refused - with ``accepted``, ``reason`` and the live ``version`` after - so the caller
hears the outcome, not merely that the request passed validation (its ``add_effects``
parameter's answer comes before the fit).

A request is sent once, never again while unanswered: a change is not idempotent (a
second ``refit`` refits again, a second ``remove`` is refused). So that the first
request is not lost in discovery, the client waits for the service and then, while it
is younger than :data:`._common.MATCH_SETTLE_S`, lets the server match it too; a node
that asks more than once keeps one :class:`ModelClient` from its start.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

from ._common import MATCH_SETTLE_S

#: The monitor's node name, as the demo and ``mt-accuracy model`` default to it.
MONITOR = "/model_monitor"
#: The longest wall time [s] the client waits for the service to be discovered.
DISCOVERY_S = 10.0


@dataclass(frozen=True)
class ChangeOutcome:
    """The monitor's answer to a change.

    Attributes
    ----------
    accepted : bool
        Validated and made (a new version live, or nothing needed to change).
    reason : str
        The refusal - validation's, or why the change could not be made - else the
        reason of the version made; the client's own words when no answer came.
    version : int or None
        The live model version after the change: the one made, or the one that stays;
        None when the monitor did not answer.
    """

    accepted: bool
    reason: str
    version: int | None


class ModelClient:
    """A client of ``<monitor>/change_model`` held by ``node``.

    Parameters
    ----------
    node : rclpy.node.Node
        The node that holds the client (and is spun while an answer is awaited).
    monitor : str
        The model monitor's node name (``/model_monitor``).
    """

    def __init__(self, node, monitor: str = MONITOR) -> None:
        from mt_accuracy_msgs.srv import ChangeModel

        self.node = node
        self.monitor = monitor
        self._type = ChangeModel
        self._client = node.create_client(ChangeModel, f"{monitor}/change_model")
        self._created = time.monotonic()

    def change(self, *, timeout_s: float, executor=None, model: str = "",
               remove_effects=(), add_effects=(), refit_effects=()) -> ChangeOutcome:
        """Ask the monitor for one change and wait for its outcome.

        Parameters
        ----------
        timeout_s : float
            Longest wall time [s] to wait for the answer (the fit included): a bound
            for a monitor that hangs or died, never a pace.
        executor : rclpy.executors.Executor, optional
            The executor that holds the node (a node kept by its own executor must be
            spun by it); None: rclpy's global one.
        model, remove_effects, add_effects, refit_effects : str, sequence of str
            The request's fields (``mt_accuracy_msgs/srv/ChangeModel``); empty ones
            change nothing.

        Returns
        -------
        ChangeOutcome
            The monitor's answer; refused, with the client's reason and no version, when
            the service is missing or silent for ``timeout_s``.
        """
        if not self._client.wait_for_service(timeout_sec=min(DISCOVERY_S, timeout_s)):
            return ChangeOutcome(False, f"{self.monitor}/change_model not available (is the "
                                 "node running?)", None)
        self._spin_until(lambda: time.monotonic() >= self._created + MATCH_SETTLE_S,
                         self._created + MATCH_SETTLE_S, executor)
        request = self._type.Request(model=str(model), remove_effects=list(remove_effects),
                                     add_effects=list(add_effects),
                                     refit_effects=list(refit_effects))
        future = self._client.call_async(request)
        if not self._spin_until(future.done, time.monotonic() + timeout_s, executor):
            self._client.remove_pending_request(future)
            return ChangeOutcome(False, f"{self.monitor} did not answer within {timeout_s:.0f} s "
                                 "(a change it accepted may still be made: mt-accuracy model "
                                 "show)", None)
        response = future.result()
        return ChangeOutcome(bool(response.accepted), str(response.reason), int(response.version))

    def _spin_until(self, condition, deadline: float, executor) -> bool:
        """Spin the node until ``condition()`` or the monotonic ``deadline`` [s]."""
        import rclpy

        while not condition() and time.monotonic() < deadline:
            if executor is None:
                rclpy.spin_once(self.node, timeout_sec=0.05)
            else:
                executor.spin_once(timeout_sec=0.05)
        return bool(condition())

    def destroy(self) -> None:
        """Destroy the client (the node stays)."""
        self.node.destroy_client(self._client)


def change_model(node, monitor: str = MONITOR, *, timeout_s: float, executor=None,
                 **request) -> ChangeOutcome:
    """One change through a client made for it and destroyed after (:class:`ModelClient`:
    ``request`` holds its fields)."""
    client = ModelClient(node, monitor)
    try:
        return client.change(timeout_s=timeout_s, executor=executor, **request)
    finally:
        client.destroy()
