"""Model monitor: the model against reference measurements, live, and what is missing.

Subscribes ``reference/tcp_error`` (``ReferenceMeasurement``), the latest
``temperatures`` and the measured profiles ``systematic/<axis>``; keeps the
last ``window`` readings and every ``check_every`` readings runs the
workbench diagnosis (:func:`mt_accuracy_ros.core.workbench.diagnosis.diagnose`):
residual statistics (offset per component removed - instruments measure from
their own zero), the readings outside the instrument's 2u band, and the
candidate effects ranked by time-blocked cross-validated error reduction.
Publishes ``model_check`` (``ModelCheck``, reliable), ``/diagnostics`` (WARN
while the residual is outside the band, naming the likely missing effect) and
every model version on ``model`` (``ModelVersion``: version, reason, effects,
the model's YAML; reliable + transient local) for the compensation broadcaster,
the recorder and any replay.

Readings of a compensated machine carry the correction the CNC applied; the
model is judged against the machine's own error, ``error - applied_correction``.

Every model version - a user's ``add_effects`` / ``remove_effects`` / ``model``,
the monitor's own ``auto_add`` - passes one gate before it goes live: an
effect whose fit physics refuses is not added, and a model whose corrections
would exceed the controller's limits anywhere in the travel and temperature
range (:mod:`..core.compensation.limits`) is refused; the live version stays
and the refusal is an ERROR on ``/diagnostics``. Once a version is live at the
machine (readings carry ``compensation_model_version``), the next
``judge_readings`` readings of the compensated machine are compared with the
previous version's last ones (:func:`..core.workbench.closed_loop.judge_version`);
if the measured error rose beyond its uncertainty the monitor rolls back: a
new version holding the previous model, reason ``rolled back: measured error
rose from X to Y um``, and an ERROR on ``/diagnostics``.

Model changes at run time: set ``add_effects`` (e.g. ``["structural_thermal_drift"]``);
the monitor fits them to the readings it holds, adds them and publishes the new
model version. ``remove_effects`` takes effects out. ``auto_add`` adds the top
significant candidate by itself. ``mt-accuracy model add|remove EFFECT`` does
the same from a terminal.

A set is validated in the on_set callback only - the model parses and passes the
gate, the effects are known, held or fittable with the readings held - and refused
there with its reason, nothing changed. An accepted set is answered at once; its
change (fit, gate, publish, a new version) is made afterwards on the node's executor,
one change at a time in the order they were set; one that cannot be made (the
physics refuses the fit, the gate refuses the fitted model) leaves the live version
and says why on ``/diagnostics`` (ERROR) and in the log. The service
``~/change_model`` (``mt_accuracy_msgs/srv/ChangeModel``) sets the same parameters
itself and answers once their changes are made: ``accepted``, ``reason`` and the
live ``version`` after.

An effect is fitted on the readings held when it was added. Every check also
refits the model's fitted effects on the readings held now
(:mod:`..core.workbench.refit`: families and settings kept, only the numbers
move) and says on ``/diagnostics`` what that would leave, held out. ``refit_effects``
(names, or ``["all"]``; ``mt-accuracy model refit``) makes the refit live;
``auto_refit`` does so by itself whenever the refit passes its held-out test and
the live version has been judged at the machine. A refit version is judged and,
if it made the machine worse, rolled back like any other.
"""
from __future__ import annotations

import copy
import sys
from collections import deque

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from dataclasses import dataclass

from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.parameter import Parameter

from mt_accuracy_msgs.msg import EffectScore, ModelCheck, ModelVersion, ReferenceMeasurement
from mt_accuracy_msgs.srv import ChangeModel

from ..core.compensation.error_model import model_from_dict, model_to_dict
from ..core.compensation.limits import gate_problem
from ..core.workbench.closed_loop import judge_version
from ..core.workbench.statistics import (DEFAULT_DIRECTION_UNCERTAINTY_RAD,
                                         DEFAULT_POSITION_UNCERTAINTY_M, stated_uncertainty)
from ..core.compensation.five_axis import tool_direction
from ..core.errors import InputDataError, MtAccuracyError
from ..core.workbench.diagnosis import (Candidate, Observations, add_effect,
                                        effect_name_problem, pick_candidate, work_points)
from ..io.fields import target_point
from ._common import (run_node, LATCHED_QOS, RESULT_QOS, accept, float_descriptor, int_descriptor,
                      nanoseconds_to_stamp, plain_descriptor, refuse, stamp_to_nanoseconds)
from ._health import DeliveryHealth
from ._lockstep import ProgressReporter
from ._model_inputs import MODEL_DIR_DESCRIPTION, ModelInputs, network_model
from ._search_worker import search, search_pool, search_serialized

#: The run-time parameters that change the model, in the order ``change_model`` sets them.
MODEL_CHANGES = ("model", "remove_effects", "add_effects", "refit_effects")
#: The reason of a version a ``model`` parameter made.
MODEL_SET_REASON = "model parameter set"
#: Comparable reference readings needed before anything is fitted to them.
MIN_FIT_READINGS = 10


@dataclass
class ModelChange:
    """One accepted model parameter, queued until the node's executor makes it."""

    name: str
    value: object
    #: What validation prepared (the parsed, gated model of a ``model`` parameter).
    plan: object = None
    #: (accepted, reason, live version after) once made; None while queued.
    outcome: tuple[bool, str, int] | None = None


def _names(value) -> list[str]:
    """The non-empty names of a string-array parameter's value."""
    return [n for n in value if n]


class ModelMonitor(Node):
    """ReferenceMeasurement stream -> ModelCheck, diagnostics, model versions."""

    def __init__(self, **kwargs) -> None:
        super().__init__("model_monitor", **kwargs)
        self.declare_parameter("model", "demo", plain_descriptor(
            "Error model: bundled name, path or inline YAML (setting it starts a new version; "
            "at run time: inline YAML, a bundled name or a file in model_dir, never a path)"))
        self.declare_parameter("model_dir", "", plain_descriptor(MODEL_DIR_DESCRIPTION,
                                                                read_only=True))
        self.declare_parameter("window", 200, int_descriptor(
            "Reference readings kept for the comparison", 10, 100000))
        self.declare_parameter("check_every", 10, int_descriptor(
            "Readings between two checks", 1, 100000))
        self.declare_parameter("min_readings", 30, int_descriptor(
            "Readings before the first check", 10, 100000))
        self.declare_parameter("min_reduction", 0.05, float_descriptor(
            "Smallest cross-validated error reduction that counts as an effect", 0.0, 1.0))
        self.declare_parameter("max_effects", 3, int_descriptor(
            "Most missing effects named at one check (forward selection)", 1, 10))
        self.declare_parameter("add_effects", [""], plain_descriptor(
            "Effects to fit and add to the model now (run-time action)"))
        self.declare_parameter("remove_effects", [""], plain_descriptor(
            "Effects to take out of the model now (run-time action)"))
        self.declare_parameter("auto_add", False, plain_descriptor(
            "Add the top significant candidate by itself"))
        self.declare_parameter("refit_effects", [""], plain_descriptor(
            "Fitted effects to refit on the readings held now, or ['all'] (run-time action)"))
        self.declare_parameter("auto_refit", False, plain_descriptor(
            "Make a refit of the fitted effects live by itself when it passes its held-out "
            "test (once the live version has been judged at the machine)"))
        self.declare_parameter("judge_readings", 15, int_descriptor(
            "Readings of a new version's compensated machine judged against the previous "
            "version's last ones (roll back if worse)", 5, 10000))
        self.declare_parameter("settle_readings", 2, int_descriptor(
            "Readings after a version went live that are not judged (the change settling)",
            0, 1000))
        self.declare_parameter("lockstep", False, plain_descriptor(
            "Report on 'lockstep' which readings are handled - a reading that starts a check "
            "once the check is published - and each check and model version (a lockstep run)",
            read_only=True))
        # Validate in on_set, act after the set: the model changes a set accepted are
        # queued by the post-set callback and made one at a time on this node's executor
        # (a guard condition wakes it), never inside the parameter callbacks.
        self._validated: dict[str, object] = {}
        self._changes: deque[ModelChange] = deque()
        self._queued: list[ModelChange] = []
        self._said_refusal = ""
        self._wake = self.create_guard_condition(self._run_next_change)
        self.add_on_set_parameters_callback(self._validate)
        self.add_post_set_parameters_callback(self._after_set)
        self.create_service(ChangeModel, "~/change_model", self._on_change_model)
        self.health = DeliveryHealth(self)
        self._check_sequences: dict[str, int] = {}   # ModelCheck.sequence per quantity
        self._model_sequence = 0
        self._reason = "start"
        self.versions: list[dict] = []   # every version published: version, reason, effects
        self.inputs = ModelInputs(self, str(self.get_parameter("model").value),
                                  follow_topic=False, on_change=self._publish_model,
                                  health=self.health,
                                  model_dir=str(self.get_parameter("model_dir").value))
        self._readings: deque = deque(maxlen=int(self.get_parameter("window").value))
        # The compensated machine's measured error per reading and the version that was
        # live at the machine then: what a new version is judged on.
        self._judge_log: deque = deque(maxlen=4000)
        self._judging: dict | None = None
        self.rolled_back: set[str] = set()   # effects a roll-back took out
        self._last_check: tuple | None = None   # (version, observations, diagnosis)
        self._since_check = 0
        self._default_notes: set[str] = set()   # defaults taken, each said once
        self.last_diagnosis = None
        self.history: list[dict] = []
        self._check = self.create_publisher(ModelCheck, "model_check", RESULT_QOS)
        # Five-axis references that also measure the tool's direction are checked on
        # their own topic: model_check stays the TCP position's story for every consumer.
        self._direction_check = self.create_publisher(ModelCheck, "model_check/tool_direction",
                                                      RESULT_QOS)
        self._model_topic = self.create_publisher(ModelVersion, "model", LATCHED_QOS)
        self._diagnostics = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self._progress = ProgressReporter(self, publishes_models=True) \
            if self.get_parameter("lockstep").value else None
        self._newest_reading_ns = -1
        guarded = self.health.guard("reference/tcp_error", self._on_reading)

        def on_reading(message: ReferenceMeasurement) -> None:
            try:
                guarded(message)
            finally:
                self._newest_reading_ns = max(self._newest_reading_ns,
                                              stamp_to_nanoseconds(message.header.stamp))
                self._report_progress()

        self.create_subscription(ReferenceMeasurement, "reference/tcp_error", on_reading,
                                 RESULT_QOS)
        self._checking = None   # (model, observations, stamp, future) of the check under way
        self._pool = search_pool()
        self._say_fallback()
        self.create_timer(0.02, self._poll_check, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self._publish_model()

    def destroy_node(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)
        super().destroy_node()

    # ---------------------------------------------------------------- parameters
    def _validate(self, parameters: list[Parameter]) -> SetParametersResult:
        """on_set: validate only - nothing is fitted, published or changed here.

        A model parses (inline YAML, a bundled name or a file in ``model_dir``) and
        passes the gate; named effects are known and the readings held can fit them;
        effects to remove are in the model; effects to refit are fitted ones. The
        refusal carries the reason (and is counted on /diagnostics); an accepted change
        is made after the set (:meth:`_after_set`)."""
        validated: dict[str, object] = {}
        try:
            for parameter in parameters:
                problem, plan = self._change_problem(parameter)
                if problem:
                    result = refuse(problem)
                    break
                validated[parameter.name] = plan
            else:
                result = accept()
        except Exception as exc:  # noqa: BLE001 - a parameter must never kill the node
            result = refuse(f"{type(exc).__name__}: {exc}")
        if result.successful:
            self._validated = validated   # taken by _after_set, in the same set call
        else:
            self.health.refused("parameters", result.reason)
        return result

    def _change_problem(self, parameter: Parameter) -> tuple[str, object]:
        """Why ``parameter`` cannot be set ("" if it can) and what its change will use
        (the model a ``model`` parameter names, parsed and gated; else None)."""
        if parameter.name == "model":
            try:
                model = network_model(str(parameter.value), self.inputs.model_dir,
                                      self.inputs.trusted_machines)
            except MtAccuracyError as exc:
                return f"model refused: {exc}", None
            problem = gate_problem(model)
            return (self._refuse_version(MODEL_SET_REASON, problem) if problem else ""), model
        if parameter.name not in MODEL_CHANGES:
            return "", None
        names = _names(parameter.value)
        if parameter.name == "add_effects":
            return self._add_problem(names), None
        if parameter.name == "remove_effects":
            return self._remove_problem(names), None
        return self._refit_problem(names), None

    def _add_problem(self, names: list[str]) -> str:
        problems = [p for p in (effect_name_problem(n, self.inputs.model) for n in names) if p]
        if problems:
            return "; ".join(problems)
        wanted = self._wanted(names)
        last = self._last_check
        if wanted and not (last is not None and last[0] == self.inputs.model.version) and \
                not self._enough_readings():
            return f"cannot fit {', '.join(wanted)}: only {len(self._readings)} reference " \
                "readings yet"
        return ""

    def _remove_problem(self, names: list[str]) -> str:
        absent = [n for n in names if n not in self.inputs.model.effects]
        if absent:
            held = ", ".join(sorted(self.inputs.model.effects)) or "nothing"
            return f"cannot remove {', '.join(absent)}: not in the model (it holds {held})"
        return ""

    def _refit_problem(self, names: list[str]) -> str:
        from ..core.workbench.refit import refittable_effects

        if not names:
            return ""
        if not self._enough_readings():
            return f"cannot refit: only {len(self._readings)} reference readings yet"
        available = refittable_effects(self.inputs.model)
        wrong = [n for n in names if n not in available] if names != ["all"] else []
        if wrong:
            # The same rule as the refit's own request check (core.workbench.refit).
            return (f"cannot refit {', '.join(wrong)}: not a fitted catalogue effect of the "
                    f"model (those are: {', '.join(available) or 'none'})")
        return "" if available else "cannot refit: the model holds no fitted catalogue effect"

    def _enough_readings(self) -> bool:
        """Whether the readings held are enough to fit to (:meth:`_observations`)."""
        return bool(self._readings) and len(self._comparable_readings()) >= MIN_FIT_READINGS

    def _wanted(self, names: list[str]) -> list[str]:
        """``names`` the model does not hold fitted yet (a user expression is fitted)."""
        return [n for n in names if not (n in self.inputs.model.effects and
                                         "expression" not in self.inputs.model.effects[n])]

    def _after_set(self, parameters: list[Parameter]) -> None:
        """post-set: the parameters are set; each model change is queued for the node's
        executor (:meth:`_run_next_change`), in order - never made here."""
        validated, self._validated = self._validated, {}
        queued = []
        for parameter in parameters:
            if parameter.name == "window":
                self._readings = deque(self._readings, maxlen=int(parameter.value))
            elif parameter.name in MODEL_CHANGES and (
                    parameter.name == "model" or _names(parameter.value)):
                queued.append(ModelChange(parameter.name, parameter.value,
                                          validated.get(parameter.name)))
        self._changes.extend(queued)
        self._queued = queued
        if queued:
            self._wake.trigger()

    def _run_next_change(self) -> None:
        """Make the oldest queued change: one at a time, in the order they were set. A
        change that cannot be made leaves the live version, and says why on /diagnostics
        (ERROR) and in the log; the node runs on."""
        if not self._changes:
            return
        change = self._changes.popleft()
        before = int(self.inputs.model.version)
        self._said_refusal = ""
        try:
            problem = self._make_change(change)
        except Exception as exc:  # noqa: BLE001 - a change must never kill the node
            problem = f"{type(exc).__name__}: {exc}"
        version = int(self.inputs.model.version)
        if problem:
            text = f"{change.name} {change.value!r} not applied: {problem}"
            if problem != self._said_refusal:   # the gate has said it already
                self.get_logger().error(text)
                self._status(DiagnosticStatus.ERROR, text,
                             [KeyValue(key="model_version", value=str(version))])
        change.outcome = (not problem, problem or (self._reason if version != before else
                                                   "nothing to change"), version)
        if self._changes:
            self._wake.trigger()

    def _make_change(self, change: ModelChange) -> str | None:
        """The action of one accepted parameter; the reason it could not be made, else None."""
        if change.name == "model":
            # Parsed and gated when the parameter was validated.
            return self._make_live(change.plan, MODEL_SET_REASON, gated="")
        names = _names(change.value)
        if change.name == "add_effects":
            return self._add_many(names, "user")
        if change.name == "refit_effects":
            return self._refit(None if names == ["all"] else names, "user")
        problem = self._remove_problem(names)   # the model may have changed since the set
        if problem:
            return problem
        model = self.inputs.model
        for name in names:
            model = model.without_effect(name)
        problem = self._make_live(model, f"removed {', '.join(names)} (user)")
        if problem is None:
            self._since_check = int(self.get_parameter("check_every").value)
        return problem

    def _on_change_model(self, request, response):
        """The ``change_model`` service: the parameters it names set here (validated
        together: all or none), then their changes made before the answer - accepted,
        reason and the live version after."""
        wanted = [Parameter(name, value=value) for name, value in (
            ("model", str(request.model)), ("remove_effects", list(request.remove_effects)),
            ("add_effects", list(request.add_effects)),
            ("refit_effects", list(request.refit_effects))) if value]
        response.accepted, response.reason = True, "nothing to change"
        if wanted:
            self._queued = []
            result = self.set_parameters_atomically(wanted)
            response.accepted, response.reason = bool(result.successful), str(result.reason)
            changes = self._queued if result.successful else []
            while any(c.outcome is None for c in changes):
                self._run_next_change()   # earlier changes first: they were set first
            if changes:
                # Accepted when every change was made; the reasons of those that were not.
                response.accepted = all(c.outcome[0] for c in changes)
                response.reason = "; ".join(c.outcome[1] for c in changes
                                            if c.outcome[0] == response.accepted)
        response.version = int(self.inputs.model.version)
        return response

    def _make_live(self, model, reason: str, *, rollback: bool = False,
                   gated: str | None = None) -> str | None:
        """The one gate every model version passes: refused (the live one stays, an ERROR on
        /diagnostics) when its corrections exceed the controller's limits; otherwise
        published, and - unless it is a roll-back - judged at the machine next.
        ``gated``: the gate's verdict on this very model, evaluated by the search worker."""
        live = self.inputs.model
        problem = "" if rollback else (gated if gated is not None else gate_problem(model))
        if problem:
            return self._refuse_version(reason, problem)
        previous = {"model": model_to_dict(live), "version": int(live.version)}
        self._reason = reason
        self.inputs.set_model(model)
        self._judging = None if rollback else {
            **previous, "version_new": int(self.inputs.model.version), "reason": reason}
        return None

    def _refuse_version(self, reason: str, problem: str) -> str:
        """A version the gate refused: counted, an ERROR on /diagnostics; the text."""
        live = self.inputs.model
        text = (f"model version refused before going live ({reason}): {problem}; "
                f"version {live.version} stays")
        self.health.refused("model_gate", text)
        self._status(DiagnosticStatus.ERROR, text,
                     [KeyValue(key="model_version", value=str(live.version))])
        self._said_refusal = text
        return text

    def _fitted_candidates(self, names: list[str]) -> tuple[list[Candidate], object] | str:
        """The candidates ``names`` ask for, fitted on the readings of the last check when
        the model has not changed since (what the user saw), else on the readings now."""
        last = self._last_check
        if last is not None and last[0] == self.inputs.model.version:
            obs, diagnosis = last[1], last[2]
        else:
            obs = self._observations()
            if obs is None:
                return f"cannot fit {', '.join(names)}: only {len(self._readings)} reference " \
                    "readings yet"
            try:
                diagnosis = self._diagnose(self.inputs.model, obs)
            except MtAccuracyError as exc:
                return f"cannot fit {', '.join(names)}: {exc}"
        chosen = []
        for name in names:
            candidate = pick_candidate(diagnosis, name)
            if candidate is None:
                return f"cannot fit {name}: it has no regressors in these readings"
            if candidate.refusal:
                return f"cannot add {candidate.name}: physics refuses its fit ({candidate.refusal})"
            chosen.append(candidate)
        return chosen, obs

    def _add_many(self, names: list[str], who: str) -> str | None:
        """Fit and add several effects from one diagnosis (their joint fit where the
        forward selection named them together), through the gate."""
        wanted = self._wanted(names)
        if not wanted:
            return None
        fitted = self._fitted_candidates(wanted)
        if isinstance(fitted, str):
            return fitted
        chosen, obs = fitted
        model = self.inputs.model
        for candidate in chosen:
            model = add_effect(model, candidate, obs)
        model.version = self.inputs.model.version + 1   # one decision, one version
        problem = self._make_live(model, f"added {', '.join(c.name for c in chosen)} ({who})")
        if problem:
            return problem
        for candidate in chosen:
            self.get_logger().info(f"added {candidate.name} {candidate.parameters}")
        self._since_check = int(self.get_parameter("check_every").value)  # check at once
        return None

    def _add(self, name: str, who: str, candidate: Candidate | None = None) -> str | None:
        if candidate is None:
            return self._add_many([name], who)
        model = self.inputs.model
        if name in model.effects and "expression" not in model.effects[name]:
            return None
        if candidate.refusal:
            return f"cannot add {candidate.name}: physics refuses its fit ({candidate.refusal})"
        obs = self._last_check[1] if self._last_check is not None else self._observations()
        problem = self._make_live(add_effect(model, candidate, obs),
                                  f"added {candidate.name} ({who})")
        if problem:
            return problem
        self.get_logger().info(f"added {candidate.name} {candidate.parameters}; model version "
                               f"{self.inputs.model.version}")
        self._since_check = int(self.get_parameter("check_every").value)  # check at once
        return None

    def _refit(self, names: list[str] | None, who: str, refit=None) -> str | None:
        """Make the refit of ``names`` (None: every fitted effect) live through the gate;
        the reason it cannot be, else None. ``refit``: one the last check made."""
        from ..core.workbench.refit import refit_effects

        model = self.inputs.model
        obs = self._last_check[1] if refit is not None else self._observations()
        if refit is None:
            if obs is None:
                return f"cannot refit: only {len(self._readings)} reference readings yet"
            try:
                refit = refit_effects(model, obs, names, min_reduction=float(
                    self.get_parameter("min_reduction").value))
            except MtAccuracyError as exc:
                return f"cannot refit: {exc}"
        if refit.refusal:
            return f"refit refused: physics refuses it ({refit.refusal})"
        if refit.reduction < 0:
            return (f"refit refused: it would predict the readings it did not see worse "
                    f"({refit.cv_rmse_refit * 1e6:.2f} against {refit.cv_rmse_live * 1e6:.2f} "
                    "um held out)")
        moved = sorted(refit.moved, key=lambda c: -c.z)[:2]
        by_name = {c.name: c for c in refit.candidates}
        changes = ", ".join(c.text(by_name[c.effect].effect, by_name[c.effect].variant)
                            for c in moved)
        if refit.datum is not None:
            corrected = ", ".join(f"{v * 1e6:+.2f}" for v in refit.datum.new)
            changes = ", ".join(c for c in (changes, f"the model's error at the datum "
                                                     f"corrected by ({corrected}) um") if c)
        reason = (f"refitted {', '.join(refit.names)} on {refit.readings} readings ({who})"
                  + (f": {changes}" if changes else ""))
        # The worker's verdict holds for the model it refitted: the live version. (Profiles
        # the estimator renewed since move its corrections by their own change; the
        # broadcaster gates every version again with the profiles it holds.)
        gated = refit.gate_problem if refit.gate_problem is not None and \
            self._last_check is not None and self._last_check[0] == model.version else None
        problem = self._make_live(refit.apply(model, obs), reason, gated=gated)
        if problem:
            return problem
        self.get_logger().info(f"{reason}; {refit.sentence()}")
        self._since_check = int(self.get_parameter("check_every").value)  # check at once
        return None

    def _judge_live_version(self) -> None:
        """Roll the model back when the version that went live made the machine worse."""
        judging = self._judging
        if judging is None:
            return
        count = int(self.get_parameter("judge_readings").value)
        settle = int(self.get_parameter("settle_readings").value)
        after = [r for r in self._judge_log if r[0] == judging["version_new"]]
        if len(after) < settle + count:
            return
        self._judging = None
        before = [r for r in self._judge_log if r[0] == judging["version"]][-count:]
        band = self._uncertainty([r[2] for r in after], "the judge's band")
        if len(before) < 5:
            self._status(DiagnosticStatus.OK, f"model version {judging['version_new']} live "
                         f"at the machine; not judged: version {judging['version']} was measured "
                         f"at only {len(before)} readings")
            return
        judgement = judge_version(np.array([r[1] for r in before]),
                                  np.array([r[1] for r in after[settle:settle + count]]), band)
        version = judging["version_new"]
        if judgement.worse is None:
            self._status(DiagnosticStatus.OK, f"model version {version} judged at the machine: "
                         f"{judgement.sentence()}")
            return
        before_um, after_um = (v * 1e6 for v in judgement.rise)
        reason = (f"rolled back: measured error rose from {before_um:.2f} to {after_um:.2f} um "
                  f"(e_{judgement.worse}) with version {version} ({judging['reason']})")
        try:
            previous = model_from_dict(judging["model"], "<previous version>")
        except MtAccuracyError as exc:
            self._status(DiagnosticStatus.ERROR, f"model version {version} made the machine "
                         f"worse ({judgement.sentence()}) but version {judging['version']} "
                         f"cannot be restored: {exc}")
            return
        self.rolled_back.update(set(self.inputs.model.effects) - set(previous.effects))
        previous.version = self.inputs.model.version + 1
        self._make_live(previous, reason, rollback=True)
        self._status(DiagnosticStatus.ERROR, f"model version {version} {reason}; now version "
                     f"{self.inputs.model.version} (the previous model)",
                     [KeyValue(key="rolled_back_version", value=str(version)),
                      KeyValue(key="rmse_before_m", value=f"{judgement.rise[0]:.3e}"),
                      KeyValue(key="rmse_after_m", value=f"{judgement.rise[1]:.3e}")])

    # ---------------------------------------------------------------- data
    def _on_reading(self, message: ReferenceMeasurement) -> None:
        axes = [a.upper() for a in message.command_axes]
        if len(axes) != len(message.command_positions) or not np.all(
                np.isfinite(message.command_positions)):
            raise InputDataError("reference reading with bad command positions skipped")
        # The machine's own error: what the instrument saw minus what the CNC added.
        error = np.array([message.error.x - message.applied_correction.x,
                          message.error.y - message.applied_correction.y,
                          message.error.z - message.applied_correction.z])
        measured = np.array(message.measured, dtype=bool)
        if not np.all(np.isfinite(error[measured])):
            raise InputDataError("reference reading with a NaN/inf error skipped")
        if not (np.isfinite(message.uncertainty) and message.uncertainty >= 0):
            raise InputDataError(f"reference uncertainty {message.uncertainty!r} m: must be "
                                 "finite and non-negative")
        velocities_in = np.asarray(message.command_velocities, dtype=np.float64)
        if not (np.all(np.isfinite(velocities_in)) and np.all(np.abs(velocities_in) <= 100.0)):
            raise InputDataError("reference reading with velocities that are not finite or "
                                 "beyond 100 m/s (rad/s): skipped")
        if np.any(np.abs(np.asarray(message.command_positions)) > 1e3) or \
                np.any(np.abs(error[measured]) > 1.0) or message.uncertainty > 1.0:
            raise InputDataError("reference reading beyond 1 km positions, 1 m error or 1 m "
                                 "uncertainty: a unit mistake? skipped")
        machine_axes = set(self.inputs.model.machine.axis_order)
        if len(set(axes)) != len(axes) or set(axes) != machine_axes:
            raise InputDataError(f"reference reading for axes {axes}: the model's machine has "
                                 f"axes {sorted(machine_axes)}, each once")
        self.health.sequence("reference/tcp_error", message.sequence)
        self.health.processed("reference/tcp_error")
        self.inputs.advance(stamp_to_nanoseconds(message.header.stamp))
        velocities = list(message.command_velocities) if len(message.command_velocities) == \
            len(axes) else [0.0] * len(axes)
        directions = list(message.command_directions) if len(message.command_directions) == \
            len(axes) else []
        direction_error = None
        if message.orientation_measured:
            direction_error = np.array([
                message.orientation_error.x - message.applied_orientation_correction.x,
                message.orientation_error.y - message.applied_orientation_correction.y,
                message.orientation_error.z - message.applied_orientation_correction.z])
            if not (np.all(np.isfinite(direction_error)) and np.all(np.abs(direction_error) < 0.1)
                    and np.isfinite(message.orientation_uncertainty)
                    and 0 <= message.orientation_uncertainty < 0.1):
                raise InputDataError("reference reading with a tool-direction error or "
                                     "uncertainty that is not finite or beyond 0.1 rad "
                                     "(degrees sent as radians?): skipped")
        target = target_point(message)
        self._judge_log.append((int(message.compensation_model_version),
                                np.where(measured, [message.error.x, message.error.y,
                                                    message.error.z], 0.0),
                                float(message.uncertainty)))
        self._readings.append({
            "stamp_ns": stamp_to_nanoseconds(message.header.stamp),
            "direction_error": direction_error,
            "direction_uncertainty": float(message.orientation_uncertainty),
            "target": target,
            "directions": dict(zip(axes, directions)),
            "time": stamp_to_nanoseconds(message.header.stamp) * 1e-9,
            "positions": dict(zip(axes, message.command_positions)),
            "velocities": dict(zip(axes, velocities)), "error": error, "measured": measured,
            "temperatures": dict(self.inputs.temperatures),
            # The measured profiles live at this reading: it is judged against the
            # machine as it was then, not against a later (e.g. deteriorated) profile.
            "profiles": dict(self.inputs.model.profiles),
            "uncertainty": float(message.uncertainty)})
        self._since_check += 1
        self._judge_live_version()
        if len(self._readings) >= int(self.get_parameter("min_readings").value) and \
                self._since_check >= int(self.get_parameter("check_every").value):
            self._run_check()

    def _predict(self, model, readings, obs: Observations) -> None:
        """Model predictions of each reading with the profiles live when it was taken."""
        position = np.zeros((obs.n, 3))
        orientation = np.zeros((obs.n, 3))
        groups: dict[tuple, list[int]] = {}
        for i, reading in enumerate(readings):
            key = tuple(sorted((name, id(f)) for name, f in reading["profiles"].items()))
            groups.setdefault(key, []).append(i)
        state = copy.copy(model)
        state._lag_states = {}   # lagged effects start at the window's first reading
        for rows in groups.values():
            state.profiles = readings[rows[0]]["profiles"]
            sub = obs.subset(np.asarray(rows))
            position[rows], orientation[rows] = state.tcp_error(sub.positions,
                                                                **sub.model_inputs())
        obs.predicted_m, obs.predicted_orientation = position, orientation

    def _comparable_readings(self) -> list[dict]:
        """Readings that have every sensor the latest has (those taken before the first
        temperatures arrived cannot enter a thermal comparison)."""
        sensors = set(self._readings[-1]["temperatures"])
        return [r for r in self._readings if sensors <= set(r["temperatures"])]

    def _observations(self, model=None) -> Observations | None:
        if not self._readings:
            return None
        readings = self._comparable_readings()
        sensors = set(readings[-1]["temperatures"])
        if len(readings) < MIN_FIT_READINGS:
            return None
        axes = list(readings[0]["positions"])
        obs = Observations(
            positions={a: np.array([r["positions"][a] for r in readings]) for a in axes},
            measured_m=np.array([r["error"] for r in readings]),
            measured_mask=np.array([r["measured"] for r in readings]),
            time_s=np.array([r["time"] for r in readings]),
            velocities={a: np.array([r["velocities"][a] for r in readings]) for a in axes},
            temperatures={s: np.array([r["temperatures"][s] for r in readings])
                          for s in sorted(sensors)},
            uncertainty_m=self._uncertainty([r["uncertainty"] for r in readings],
                                            "the check's readings"))
        if all(r["directions"] for r in readings):
            # The CNC's last direction per axis; where unknown (0), the feed's sign.
            obs.directions = {a: np.array([r["directions"][a] or np.sign(r["velocities"][a])
                                           for r in readings], dtype=float) for a in axes}
        # Where the instrument measured the tool's direction too (an R-test): a second
        # measured quantity with its own uncertainty.
        self._say_default(obs.set_directions([r["direction_error"] for r in readings],
                                             [r["direction_uncertainty"] for r in readings]))
        # An instrument with a fixed target on the workpiece side is judged there.
        obs.work_point = work_points((model or self.inputs.model).kinematics, obs.positions,
                                     [r.get("target") for r in readings])
        self._predict(model or self.inputs.model, readings, obs)
        return obs

    def _run_check(self) -> None:
        """Start a check: observations taken here, the diagnosis (seconds of CPU) in the
        worker thread, so that readings keep arriving - none lost to a full queue - and
        the judge keeps judging while it searches. One check at a time: the next starts
        once this one is published and ``check_every`` readings have come."""
        if self._checking is not None:
            return
        model = self.inputs.model
        try:
            # A user effect the readings cannot evaluate (a sensor it names is missing)
            # stops this check, not the node: said on /diagnostics.
            obs = self._observations()
        except MtAccuracyError as exc:
            self._status(DiagnosticStatus.WARN, f"no check: {exc}")
            return
        if obs is None:
            return
        self._since_check = 0
        # The worker gets its own copy: profiles arrive meanwhile on this thread.
        snapshot = copy.copy(model)
        snapshot.profiles = dict(model.profiles)
        snapshot._lag_states = {}   # lagged effects start at the window's first reading
        stamp_ns = self._readings[-1]["stamp_ns"]
        self._checking = (model, obs, stamp_ns, self._submit_search(snapshot, obs))

    def _submit_search(self, model, obs):
        """The search in the worker process; here, said on /diagnostics, when the inputs
        cannot be sent to it (a plug-in effect that does not pickle)."""
        import pickle
        from concurrent.futures import Future
        from concurrent.futures.process import BrokenProcessPool

        settings = self._search_settings()
        try:
            inputs = pickle.dumps((model, obs))
        except Exception as exc:  # noqa: BLE001 - any reason to not pickle: run here
            self._status(DiagnosticStatus.WARN, f"search in the node's own process: its "
                         f"inputs cannot go to the worker ({type(exc).__name__}: {exc})")
            future = Future()
            try:
                future.set_result(search(model, obs, *settings))
            except Exception as error:  # noqa: BLE001 - reported by _poll_check
                future.set_exception(error)
            return future
        try:
            return self._pool.submit(search_serialized, inputs, *settings)
        except BrokenProcessPool:
            # The worker died (killed, out of memory): a new one for this and later checks.
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = search_pool()
            self._say_fallback()
            return self._pool.submit(search_serialized, inputs, *settings)

    def _poll_check(self) -> None:
        if self._checking is None or not self._checking[3].done():
            return
        model, obs, stamp_ns, future = self._checking
        self._checking = None
        try:
            diagnosis = future.result()
        except MtAccuracyError as exc:
            self._status(DiagnosticStatus.WARN, f"no check: {exc}")
            self._report_progress()
            return
        except Exception as exc:  # noqa: BLE001 - a failed search must not end the monitor
            self._status(DiagnosticStatus.ERROR, f"check failed: {type(exc).__name__}: {exc}")
            self._report_progress()
            return
        self._publish_check(model, obs, stamp_ns, diagnosis)
        if self._since_check >= int(self.get_parameter("check_every").value):
            self._run_check()
        self._report_progress(last_check_ns=stamp_ns)

    def _publish_check(self, model, obs: Observations, stamp_ns: int, diagnosis) -> None:
        self.last_diagnosis = diagnosis
        self._last_check = (model.version, obs, diagnosis)
        check = self._new_check(model, obs, "tcp_error", "m", stamp_ns)
        check.rmse = diagnosis.baseline_rmse
        check.max_abs_error = diagnosis.max_abs_error
        check.band = obs.uncertainty_m
        check.fraction_outside_band = diagnosis.fraction_outside_band
        check.ranking = [_score(c) for c in diagnosis.ranking[:20]]
        check.named = [_score(c) for c in diagnosis.selected]
        check.diagnosis = diagnosis.text()
        check.verdict = diagnosis.verdict()
        where = diagnosis.localisation
        if where is not None:
            top = where.shares[:12]
            check.localisation_variables = [s.variable for s in top]
            check.localisation_components = [s.component for s in top]
            check.localisation_shares = [float(s.share) for s in top]
            check.localisation = where.sentence()
            if where.peaks:
                peak = where.peaks[0]
                check.peak_axis, check.peak_component = peak.axis, peak.component
                check.peak_period, check.peak_amplitude = peak.period_m, peak.amplitude
        self._check.publish(check)
        self._check_direction(model, obs, stamp_ns)
        self.history.append({"version": model.version, "rmse": diagnosis.baseline_rmse})
        found = diagnosis.found
        level = DiagnosticStatus.OK if found is None and \
            diagnosis.baseline_rmse <= obs.uncertainty_m else DiagnosticStatus.WARN
        refit = diagnosis.refit
        text = diagnosis.text() + (f"; {refit.sentence()}" if refit is not None and
                                   refit.recommended else "")
        self._status(level, text, [
            KeyValue(key="rmse_m", value=f"{diagnosis.baseline_rmse:.3e}"),
            KeyValue(key="model_version", value=str(model.version)),
            KeyValue(key="missing_effect", value=found.effect if found else ""),
            KeyValue(key="refit", value=refit.sentence() if refit is not None else ""),
            # The check's cost: wall and CPU seconds of the search (the worker's).
            KeyValue(key="search_wall_s", value=f"{diagnosis.search_wall_s:.3f}"),
            KeyValue(key="search_cpu_s", value=f"{diagnosis.search_cpu_s:.3f}"),
            KeyValue(key="readings", value=str(obs.n))])
        if found is not None and self.get_parameter("auto_add").value and \
                found.name not in self.rolled_back:
            problem = self._add(found.name, "auto_add", found)
            if problem:
                self.get_logger().warning(problem)
        elif refit is not None and refit.recommended and \
                self.get_parameter("auto_refit").value and self._judging is None and \
                model.version == self.inputs.model.version:
            # The live version has been judged at the machine: its numbers may be renewed.
            problem = self._refit(refit.names, "monitor", refit)
            if problem:
                self.get_logger().warning(problem)

    def _new_check(self, model, obs: Observations, quantity: str, unit: str,
                   stamp_ns: int) -> ModelCheck:
        """A ModelCheck of ``quantity`` with its header, version and running sequence."""
        check = ModelCheck()
        # Stamped with the data it judged (its newest reading), not the wall clock: a
        # subscriber acting on checks acts on data time, whatever the host's load.
        check.header.stamp = nanoseconds_to_stamp(stamp_ns)
        check.model_version = int(model.version)
        check.sequence = self._check_sequences.get(quantity, 0)
        self._check_sequences[quantity] = check.sequence + 1
        check.quantity = quantity
        check.unit = unit
        check.effects_included = sorted(model.effects)
        check.sample_count = obs.n
        return check

    def _check_direction(self, model, obs: Observations, stamp_ns: int) -> None:
        """The model's tool-direction error against the readings that measured it."""
        readings = [r for r in self._comparable_readings() if r["stamp_ns"] <= stamp_ns]
        readings = readings[-obs.n:]
        if len(readings) != obs.n or any(r["direction_error"] is None for r in readings) or \
                obs.predicted_orientation is None:
            return
        measured = np.array([r["direction_error"] for r in readings])
        axis = tool_direction(model.kinematics, obs.positions)
        predicted = obs.predicted_orientation
        predicted = predicted - axis * np.einsum("ni,ni->n", predicted, axis)[:, None]
        residual = measured - predicted
        norm = np.linalg.norm(residual, axis=1)
        band = self._uncertainty([r["direction_uncertainty"] for r in readings],
                                 "the tool-direction check", direction=True)
        check = self._new_check(model, obs, "tool_direction", "rad", stamp_ns)
        before = float(np.sqrt(np.mean(np.sum(measured ** 2, axis=1))))
        check.rmse = float(np.sqrt(np.mean(norm ** 2)))
        check.max_abs_error = float(np.max(norm))
        check.band = band
        check.fraction_outside_band = float(np.mean(norm > band))
        check.diagnosis = (f"tool-direction residual {check.rmse * 1e6:.1f} urad RMS over "
                           f"{obs.n} readings (the machine's own error {before * 1e6:.1f} urad; "
                           f"instrument band {band * 1e6:.1f} urad)")
        # ISO 14253-1 (core/workbench/conformance.py): within only when RMS + U <= band.
        from ..core.workbench.conformance import judge
        from ..core.workbench.statistics import rms_with_uncertainty

        figure = rms_with_uncertainty(norm, band)
        verdict = judge("tool-direction residual", figure.rms * 1e6, figure.rms_u_k2 * 1e6,
                        band * 1e6, "urad")
        check.verdict = ("the model explains the tool's direction within the instrument's band"
                         if verdict.state.value == "within" else
                         f"an unexplained tool-direction error of {check.rmse * 1e6:.1f} urad "
                         "remains" if verdict.state.value == "outside" else
                         "undecided whether the model explains the tool's direction within "
                         "the instrument's band") + f": {verdict.sentence()}"
        self._direction_check.publish(check)

    def _search_settings(self) -> tuple[float, int, bool]:
        # Gate a recommended refit in the worker when this node would make it live as soon
        # as the check is back: the version live now has been judged, auto_refit is on.
        gate_refit = bool(self.get_parameter("auto_refit").value) and self._judging is None
        return (float(self.get_parameter("min_reduction").value),
                int(self.get_parameter("max_effects").value), gate_refit)

    def _diagnose(self, model, obs):
        return search(model, obs, *self._search_settings()[:2])

    def _report_progress(self, last_check_ns: int | None = None) -> None:
        """Lockstep: every reading before the check under way is handled (all received,
        when none is); the check itself once it is published."""
        if self._progress is None:
            return
        handled = self._checking[2] if self._checking is not None else self._newest_reading_ns + 1
        self._progress.report(handled_ns=handled, last_check_ns=last_check_ns,
                              published=int(self.inputs.model.version))

    def _publish_model(self) -> None:
        model = self.inputs.model
        message = ModelVersion(version=int(model.version), reason=self._reason,
                               effects=sorted(model.effects), model_yaml=self.inputs.model_yaml(),
                               sequence=self._model_sequence)
        message.header.stamp = self.get_clock().now().to_msg()
        self._model_sequence += 1
        self.versions.append({"version": int(model.version), "reason": self._reason,
                              "effects": sorted(model.effects)})
        self.get_logger().info(f"model version {model.version}: {self._reason}")
        self._model_topic.publish(message)
        if getattr(self, "_progress", None) is not None:
            self._progress.report(published=int(model.version))

    def _uncertainty(self, values, what: str, direction: bool = False) -> float:
        """The readings' stated k = 2 uncertainty, or the documented default - said on
        /diagnostics as a WARN (once per kind) when taken (no silent default)."""
        default, unit = ((DEFAULT_DIRECTION_UNCERTAINTY_RAD, "rad") if direction
                         else (DEFAULT_POSITION_UNCERTAINTY_M, "m"))
        value, note = stated_uncertainty(values, default, what, unit)
        self._say_default(note)
        return value

    def _say_fallback(self) -> None:
        """A search pool that could not start its process says so: a WARN on /diagnostics."""
        if getattr(self._pool, "fallback_reason", ""):
            self.health.warn(self._pool.fallback_reason)

    def _say_default(self, note: str) -> None:
        if note and note not in self._default_notes:
            self._default_notes.add(note)
            self._status(DiagnosticStatus.WARN, note)

    def _status(self, level: int, text: str, values=None) -> None:
        status = DiagnosticStatus(level=level, name=f"{self.get_fully_qualified_name()}: model",
                                  hardware_id=self.inputs.model.machine.name, message=text)
        status.values = values or []
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics.publish(array)


def _score(candidate: Candidate) -> EffectScore:
    from ..core.effects import family_named

    try:
        setting = family_named(candidate.effect).describe_setting(candidate.setting) \
            if candidate.setting else ""
    except MtAccuracyError:
        setting = ""
    names = list(candidate.parameters)
    return EffectScore(effect=candidate.effect, cv_rmse_after=candidate.cv_rmse_after,
                       error_reduction=max(0.0, candidate.error_reduction),
                       explanation=candidate.explanation, name=candidate.name,
                       group=candidate.group, setting=setting,
                       significant=bool(candidate.significant),
                       confidence=float(candidate.confidence), parameter_names=names,
                       parameters=[float(candidate.parameters[n]) for n in names],
                       parameter_uncertainties=[float(candidate.parameter_uncertainties.get(
                           n, float("nan"))) for n in names])


#: Scheduling niceness of the monitor's process (environment ``MT_ACCURACY_MONITOR_NICE``;
#: set before rclpy starts, so every thread of the process inherits it). 0 by default,
#: as measured on this 2-core machine (docs/closed_loop.md): idle, a niced monitor
#: changed nothing (0-250 stale corrections of 9,000 either way, once the machine's
#: clock waits for every node); with two CPU burners it made no fewer stale but its
#: checks came too late for the user to act within the run. For a cell where
#: the real-time path must win at any price, set it (e.g. 10).
MONITOR_NICENESS = 0


def lower_priority(default: int = MONITOR_NICENESS) -> int:
    """Lower this process' scheduling priority; returns the niceness increment applied."""
    import os

    try:
        increment = int(os.environ.get("MT_ACCURACY_MONITOR_NICE", default))
    except ValueError:
        increment = default
    if increment > 0:
        try:
            os.nice(increment)
        except OSError:
            return 0
    return max(increment, 0)


def main(args: list[str] | None = None) -> int:
    """Entry point (console_scripts)."""
    lower_priority()
    return run_node(ModelMonitor, args)


if __name__ == "__main__":
    sys.exit(main())
