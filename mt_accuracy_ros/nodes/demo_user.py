"""The main job's user: a node that listens to the graph and acts as an engineer would.

It subscribes to what a user sees - the model monitor's checks (``model_check``), the
estimator's profiles and their deterioration alarms (``systematic/<axis>``), the
reference instrument's readings (``reference/tcp_error``), the model versions
(``model``) and every node's status (``/diagnostics``) - and keeps them, in the order
they came, as its attributes. The corrections (``compensation``, 100 a second) it does
not take one by one: the run counts them from the bag afterwards. Its one
decision: once the machine has warmed for ``looks_after_s`` of data, at the first check
that names effects, it asks the monitor to add every one of them (its ``add_effects``
parameter), once.

It asks through the monitor's ``change_model`` service (:mod:`._model_client`), which
answers once the effects are fitted, gated and live - or why they could not be - with
the version made: what the user keeps is the outcome, not merely the request's
validation.

With ``lockstep`` it is a participant of the lockstep gate (``demo_user:checks``): the
machine streams on once the user has looked at each check, and, after adding effects,
once the version they made is settled where it applies (the user reports it published).
The machine waits for the user meanwhile, so however long the fit takes on a loaded
host, it lands at the same data time.

The user runs in the demo's process (``mt-accuracy demo``), which spins it and calls
:meth:`DemoUser.act` after each wake-up.
"""
from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.node import Node
from rclpy.qos import QoSProfile

from mt_accuracy_msgs.msg import ModelCheck, ModelVersion, ReferenceMeasurement, SystematicProfile

from ._common import (LATCHED_QOS, RESULT_QOS, float_descriptor, plain_descriptor,
                      stamp_to_nanoseconds)
from ._health import warnings_of
from ._model_client import ChangeOutcome, ModelClient

#: The statuses on ``/diagnostics`` the user keeps (the latest of each node's delivery
#: counters and the alarms): reliable, 50 deep - one second of every node's statuses.
DIAGNOSTICS_QOS = QoSProfile(depth=50)
#: Data time [s] after which the user acts on the first check naming effects.
LOOKS_AFTER_S = 30.0
#: Wall seconds the user waits for the monitor to answer its request - made, or not -
#: in real time.
ANSWER_S = 30.0
#: Wall seconds a lockstep run's user waits for that answer (a bound for a hung graph
#: only: the machine waits for the user meanwhile).
LOCKSTEP_ANSWER_S = 600.0
#: The TCP error axes the estimator publishes a profile for.
PROFILE_AXES = ("x", "y", "z")

#: What asks the monitor for a change: :meth:`._model_client.ModelClient.change`'s
#: signature, ``ask(*, timeout_s, executor, add_effects) -> ChangeOutcome``.
ChangeClient = Callable[..., ChangeOutcome]


# ------------------------------------------------------------------ the user's rules
def effects_to_add(checks: Sequence[tuple[float, object]], acted: bool,
                   looks_after_s: float = LOOKS_AFTER_S) -> list[str]:
    """The effects the user adds now ([] when it does not act).

    Parameters
    ----------
    checks : sequence of (float, ModelCheck)
        (data time [s], check) in the order they came; only the latest is looked at.
    acted : bool
        Whether the user has already acted (it acts once).
    looks_after_s : float
        [s] of data before which the user does not act (the machine warms first).

    Returns
    -------
    list of str
        Every effect the latest check names, in its order (the monitor's joint fit), when
        it came strictly after ``looks_after_s`` and names any; else [].
    """
    if acted or not checks:
        return []
    time_s, latest = checks[-1]
    if not latest.named or time_s <= looks_after_s:
        return []
    return [score.name for score in latest.named]


def latest_version(models: Sequence[tuple[float, object]]) -> int:
    """The highest model version among (time [s], ModelVersion) pairs (0: none yet)."""
    return max((int(m.version) for _, m in models), default=0)


def is_new_alarm(alarms: Sequence[tuple[float, str]], axis: str, deterioration: bool) -> bool:
    """Whether a profile of ``axis`` raises an alarm not yet heard: each axis' first only."""
    return bool(deterioration) and not any(a[1] == axis for a in alarms)


def readings_judged(delivery: dict[str, dict[str, str]], readings: int) -> bool:
    """Whether the monitor has handled (processed, refused or lost) every one of
    ``readings`` > 0 reference readings, by its latest delivery counters."""
    counts = delivery.get("/model_monitor", {})
    handled = sum(int(counts.get(f"reference/tcp_error.{k}", "0"))
                  for k in ("processed", "refused", "lost"))
    return handled >= readings > 0


def hear_warnings(node_warnings: dict[str, list[str]], status_name: str,
                  values: dict[str, str]) -> None:
    """Keep the warnings a ``<node>: delivery`` status carries (``warning.<n>``, every WARN
    the node said: :class:`._health.DeliveryHealth`), once each, in order."""
    said = node_warnings.setdefault(status_name.split(":")[0], [])
    said += [text for text in warnings_of(values) if text not in said]


def reference_entry(m, start_ns: int) -> tuple[tuple, tuple | None]:
    """A ReferenceMeasurement as the demo holds it.

    Returns
    -------
    reading : tuple
        (data time [s] since ``start_ns``, measured (3,) [m], applied correction (3,) [m],
        compensation model version, uncertainty k = 2 [m]).
    orientation : tuple or None
        (measured (3,), applied (3,), uncertainty) [rad] where the tool's direction was
        measured; None for a reading without one (a gap is told, not hidden).
    """
    reading = ((stamp_to_nanoseconds(m.header.stamp) - start_ns) / 1e9,
               np.array([m.error.x, m.error.y, m.error.z]),
               np.array([m.applied_correction.x, m.applied_correction.y,
                         m.applied_correction.z]),
               int(m.compensation_model_version), float(m.uncertainty))
    if not m.orientation_measured:
        return reading, None
    return reading, (
        np.array([m.orientation_error.x, m.orientation_error.y, m.orientation_error.z]),
        np.array([m.applied_orientation_correction.x, m.applied_orientation_correction.y,
                  m.applied_orientation_correction.z]),
        float(m.orientation_uncertainty))


def action_entry(time_s: float, latest, effects: list[str], accepted: bool,
                 reason: str) -> dict:
    """What the user did, as the summary and the report keep it: when [s of data], the
    effects added (joined and listed), the monitor's answer, and the check it acted on
    (its residual RMSE [m], where the residual lived, the diagnosis)."""
    return {"time_s": time_s, "added": ", ".join(effects), "effects": effects,
            "accepted": accepted, "reason": reason, "rmse_before_m": latest.rmse,
            "where": latest.localisation, "diagnosis": latest.diagnosis}


def action_line(action: dict) -> str:
    """The printed line of an action (see :func:`action_entry`)."""
    effects = action["effects"]
    return (f"  data {action['time_s']:.1f} s: the monitor names {', '.join(effects)}; "
            f"the user adds {'them' if len(effects) > 1 else 'it'} - "
            + ("accepted" if action["accepted"] else f"refused: {action['reason']}"))


def progress_line(wall_s: float, references: Sequence[tuple], models: Sequence[tuple],
                  checks: int, controller: dict[str, str]) -> str:
    """The run's feedback line: wall time [s], the data time of the latest reading, the
    model live at the machine, the checks so far and the controller's correction counts."""
    if references:
        version = references[-1][3]
        reasons = {int(m.version): m.reason for _, m in models}
        phase = f"v{version} live at the machine ({reasons.get(version, 'model')})" \
            if version else "no compensation applied yet"
        when = f"data {references[-1][0]:5.1f} s"
    else:
        phase, when = "waiting for the machine", "data   -  "
    return (f"  [{wall_s:5.0f} s wall] {when} | {phase} | checks {checks} | corrections "
            f"applied {controller.get('applied', 0)}, stale {controller.get('stale', 0)}")


# ------------------------------------------------------------------ the node
class DemoUser(Node):
    """The scripted user of the main job: what it heard, and the one decision it makes.

    Each list holds what came in the order it came.

    Parameters
    ----------
    ask : callable, optional
        What asks the monitor for a change (:data:`ChangeClient`); None: a
        :class:`._model_client.ModelClient` of ``/model_monitor``, made with the node.
    **kwargs
        Passed to :class:`rclpy.node.Node` (``parameter_overrides``, ``context``).

    Attributes
    ----------
    checks : list of (float, ModelCheck)
        Data time [s] and each check of the monitor.
    check_arrivals : list of float
        When each check came [s], wall clock x ``rate_factor`` since the start.
    alarms : list of (float, str)
        Data time [s] and axis of each axis' first deterioration alarm.
    references : list of tuple
        The reference readings (:func:`reference_entry`); ``orientations`` beside them.
    models : list of (float, ModelVersion)
        Each model version, at its arrival (wall x rate [s]).
    actions : list of dict
        What the user did (:func:`action_entry`).
    delivery : dict
        Node (or ``<node>:compensation``) -> its latest delivery counters.
    node_warnings : dict
        Node -> every WARN it said (:func:`hear_warnings`).
    model_alarms : list of (float, str)
        The monitor's ERROR statuses (model alarms, a dead input), at arrival.
    searches : list of (float, float)
        Each check's search, (wall, CPU) [s].
    """

    def __init__(self, ask: ChangeClient | None = None, **kwargs) -> None:
        super().__init__("demo_user", **kwargs)
        self.declare_parameter("rate_factor", 1.0, float_descriptor(
            "Sim seconds per wall second of the run (1 in lockstep)", 0.01, 1000.0,
            read_only=True))
        self.declare_parameter("lockstep", False, plain_descriptor(
            "Take part in the lockstep gate as 'demo_user:checks'", read_only=True))
        self.declare_parameter("looks_after_s", LOOKS_AFTER_S, float_descriptor(
            "Data time [s] after which the user acts on a check naming effects", 0.0, 1e6,
            read_only=True))
        self.rate_factor = float(self.get_parameter("rate_factor").value)
        self.lockstep = bool(self.get_parameter("lockstep").value)
        self.looks_after_s = float(self.get_parameter("looks_after_s").value)
        # The client is made with the node, so it has matched the monitor long before
        # the user first asks (a request is sent once: a change is not idempotent).
        self._ask = ask if ask is not None else ModelClient(self).change
        #: The run's time base [ns]: far ahead until the graph is ready (:meth:`start`).
        self.start_ns = time.time_ns() + 3600_000_000_000
        self.checks: list[tuple[float, ModelCheck]] = []
        self.check_arrivals: list[float] = []
        self.alarms: list[tuple[float, str]] = []
        self.references: list[tuple] = []
        self.orientations: list[tuple | None] = []
        self.models: list[tuple[float, ModelVersion]] = []
        self.actions: list[dict] = []
        self.delivery: dict[str, dict[str, str]] = {}
        self.node_warnings: dict[str, list[str]] = {}
        self.model_alarms: list[tuple[float, str]] = []
        self.searches: list[tuple[float, float]] = []
        self.progress = None
        if self.lockstep:
            from ._lockstep import ProgressReporter

            # The user is a participant: the machine waits until it has looked at each check.
            self.progress = ProgressReporter(self, "demo_user", publishes_models=True)
        self._subscribe()

    def _subscribe(self) -> None:
        self.create_subscription(ModelCheck, "model_check", self._on_check, RESULT_QOS)
        for axis in PROFILE_AXES:
            self.create_subscription(SystematicProfile, f"systematic/{axis}", self._on_profile,
                                     RESULT_QOS)
        self.create_subscription(DiagnosticArray, "/diagnostics", self._on_diagnostics,
                                 DIAGNOSTICS_QOS)
        self.create_subscription(ReferenceMeasurement, "reference/tcp_error",
                                 self._on_reference, RESULT_QOS)
        self.create_subscription(ModelVersion, "model", self._on_model, LATCHED_QOS)

    # ------------------------------------------------------------------ time
    def start(self, start_ns: int) -> None:
        """Take ``start_ns`` [ns] as the run's time base (the machine's sample 0)."""
        self.start_ns = int(start_ns)

    def now_s(self) -> float:
        """Wall time since the start x the rate [s]: the data time a message arriving now
        would have, were the graph keeping up."""
        return (time.time_ns() - self.start_ns) / 1e9 * self.rate_factor

    def data_s(self, stamp) -> float:
        """Data time [s] of a message stamped in the run's time base: what the user acts
        on, so that host load cannot change which effect is named or when."""
        return (stamp_to_nanoseconds(stamp) - self.start_ns) / 1e9

    # ------------------------------------------------------------------ callbacks
    def _on_check(self, message: ModelCheck) -> None:
        self.checks.append((self.data_s(message.header.stamp), message))
        self.check_arrivals.append(self.now_s())

    def _on_profile(self, message: SystematicProfile) -> None:
        if is_new_alarm(self.alarms, message.axis, message.deterioration):
            self.alarms.append((self.data_s(message.header.stamp), message.axis))

    def _on_reference(self, message: ReferenceMeasurement) -> None:
        reading, orientation = reference_entry(message, self.start_ns)
        self.references.append(reading)
        self.orientations.append(orientation)

    def _on_model(self, message: ModelVersion) -> None:
        self.models.append((self.now_s(), message))

    def _on_diagnostics(self, message: DiagnosticArray) -> None:
        for status in message.status:
            values = {v.key: v.value for v in status.values}
            self._hear_delivery(status.name, values)
            self._hear_model(status, values)

    def _hear_delivery(self, name: str, values: dict[str, str]) -> None:
        if name.endswith(": delivery"):
            hear_warnings(self.node_warnings, name, values)
            self.delivery[name.split(":")[0]] = values
        elif name.endswith(": compensation"):
            self.delivery[name.split(":")[0] + ":compensation"] = values

    def _hear_model(self, status: DiagnosticStatus, values: dict[str, str]) -> None:
        if status.name.endswith(": model") and "search_cpu_s" in values:
            self.searches.append((float(values["search_wall_s"]),
                                  float(values["search_cpu_s"])))
        # The model's alarms, and an input that stopped (its node died): ERRORs.
        if status.name.endswith((": model", ": inputs")) and \
                status.level == DiagnosticStatus.ERROR:
            self.model_alarms.append((self.now_s(), status.message))

    # ------------------------------------------------------------------ what it sees
    def sees_graph_ready(self, scales_consumers: int, temperature_consumers: int,
                         compensation_consumers: int = 2) -> bool:
        """Every consumer subscribed, the broadcaster's compensation matched by its
        ``compensation_consumers`` (the CNC that takes it in real time, and the recorder:
        the run counts the corrections from the bag), the monitor constructed (its latched
        version 1)."""
        return (self.count_subscribers("/scales") >= scales_consumers and
                self.count_subscribers("/temperatures") >= temperature_consumers and
                self.count_publishers("/compensation") >= 1 and
                self.count_subscribers("/compensation") >= compensation_consumers and
                bool(self.models))

    def monitor_done(self) -> bool:
        """Every reference reading the machine made has been judged by the monitor."""
        return readings_judged(self.delivery, len(self.references))

    # ------------------------------------------------------------------ what it does
    def act(self) -> dict | None:
        """Look at the latest check; add what it names when it is time (once). Returns
        the action taken now (:func:`action_entry`), else None. In lockstep, then say
        the check was looked at."""
        latest = self.checks[-1][1] if self.checks else None
        effects = effects_to_add(self.checks, bool(self.actions), self.looks_after_s)
        action = self._add(effects, latest) if effects else None
        if latest is not None and self.progress is not None:
            self.progress.report(check_handled_ns=stamp_to_nanoseconds(latest.header.stamp))
        return action

    def _add(self, effects: list[str], latest: ModelCheck) -> dict:
        """Ask the monitor to add ``effects`` (all in one decision: its joint fit)."""
        # The monitor answers once it has fitted, gated and published them (seconds of
        # CPU on five axes): a lockstep run has no pace to keep, so the user waits as
        # long as a slow host needs - the outcome must not depend on it.
        outcome = self._ask(add_effects=effects, executor=self.executor,
                            timeout_s=LOCKSTEP_ANSWER_S if self.lockstep else ANSWER_S)
        action = action_entry(self.checks[-1][0], latest, effects, outcome.accepted,
                              outcome.reason)
        self.actions.append(action)
        if outcome.accepted and self.progress is not None:
            # The machine goes on once the version the request made is settled where it
            # applies: the answer names it, made before the answer.
            self.progress.report(published=outcome.version)
        return action
