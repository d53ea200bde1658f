"""Inputs every model-running node keeps: latest temperatures, measured profiles, the model."""
from __future__ import annotations

import numpy as np
import yaml

from mt_accuracy_msgs.msg import ModelVersion, SystematicProfile, TemperatureArray

from ..core.compensation.error_model import ErrorModel, model_to_dict, resolve_model
from ..core.errors import InputDataError, MtAccuracyError
from ._health import LiveSensorWatch
from ._common import (LATCHED_QOS, RESULT_QOS, SENSOR_QOS, TABLE_QOS,  # noqa: F401
                      stamp_to_nanoseconds, unpack_float64)



MODEL_DIR_DESCRIPTION = (
    "The one directory a model or machine named by the network (model topic, a model "
    "parameter set at run time) may be read from; empty: none (inline YAML and bundled "
    "names only)")


def network_model(text: str, model_dir: str | None, trusted_machines: tuple[str, ...] = ()
                  ) -> ErrorModel:
    """A model a DDS peer sent (topic or run-time parameter): never a path (its machine:
    a bundled one, one in ``model_dir`` or the node's start-up machine)."""
    return resolve_model(text, from_network=True, model_dir=model_dir or None,
                         trusted_machines=trusted_machines)


def gate_model_text(text: str, gate, model_dir: str | None = None,
                    trusted_machines: tuple[str, ...] = ()) -> tuple[str, str]:
    """(parse error, gate problem) of a model's YAML: run in the gate's worker process."""
    try:
        model = network_model(text, model_dir, trusted_machines)
    except MtAccuracyError as exc:
        return str(exc), ""
    try:
        return "", (gate(model) if gate is not None else "")
    except Exception as exc:  # noqa: BLE001 - a model must never kill the node
        return "", f"its corrections cannot be evaluated ({type(exc).__name__}: {exc})"


def _warm_worker() -> None:
    from ._priority import leave_path_priority

    # A node on the compensation path may run at a negative niceness (its ``niceness``
    # parameter); its gate has no deadline and must not take the path's CPU.
    leave_path_priority()
    from ..core.compensation import limits  # noqa: F401 - imported once, at start


def _gate_pool():
    """One worker *process* for the gate. Evaluating a model over the whole travel takes
    ~0.7 s of pure Python and numpy; in a thread of the broadcaster it held the GIL
    against the executor and made corrections late while a new version was gated.
    Not niced: with two CPU burners a niced gate took so long that the user's model
    reached the machine after the run (docs/closed_loop.md)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    try:
        pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"),
                                   initializer=_warm_worker)
        pool.submit(int)   # start the worker (and its imports) now, not at the first model
        return pool
    except (OSError, ValueError, NotImplementedError) as exc:
        from ._search_worker import thread_fallback

        return thread_fallback("model_gate", "the model gate", "gating a new version now "
                               "competes with the compensation callbacks", exc)


class ModelInputs:
    """Subscribes temperatures and systematic/<axis>; holds the current ErrorModel.

    Inputs are applied by **data time**, not arrival: for data stamped t the
    model uses the temperatures and profiles stamped at or before
    t - ``delay_s``. Live and replayed runs then compute the same thing
    whatever the order in which messages of different topics arrived.

    ``follow_topic``: also take the model versions published on ``model``
    (``ModelVersion``) by the model monitor, with their version numbers; a
    version below the live one is refused (counted, on /diagnostics) and the
    live model stays. With ``gate`` (model -> reason or ""), a version the gate
    refuses is refused the same way: the last good version stays live. A version
    from the topic is parsed and gated in a worker process (the gate evaluates the
    model over the whole travel, a few hundred ms) and made live when it passes,
    so that a model change never holds up the real-time path: until then the live
    version keeps compensating.
    """

    def __init__(self, node, model_text: str, *, follow_topic: bool, on_change, health,
                 delay_s: float = 0.5, on_profiles=None, gate=None,
                 model_dir: str | None = None) -> None:
        self.model_dir = model_dir or None
        self.on_profiles = on_profiles
        self.gate = gate
        self.node = node
        self.health = health
        # The start-up model comes from the node's own command line or parameter file.
        self.model: ErrorModel = resolve_model(model_text, model_dir=self.model_dir)
        #: Newest data stamp [ns] received per input stream (liveness: :meth:`silent`).
        self.last_stamp: dict[str, int] = {}
        # The last versions that evaluated at the machine, newest last (a version that
        # fails there is taken out: never a fallback).
        self._evaluated: list[ErrorModel] = []
        #: The start-up machine, as models name it: network models may name it too.
        self.trusted_machines = (self.model.machine_source or self.model.machine.name,)
        #: The newest version from the topic that is settled - live or refused - and a
        #: hook told of it (a lockstep run's progress report).
        self.settled_version = int(self.model.version)
        self.on_settled = None
        self.temperatures: dict[str, float] = {}
        #: Sensors whose latest reading is left out (dead, frozen, implausible) -> kind.
        self.dead_kinds: dict[str, str] = {}
        self._watch = LiveSensorWatch()
        self.on_change = on_change
        self.delay_ns = int(delay_s * 1e9)
        self._applied_until = -1  # data time [ns] up to which inputs have been applied
        self._pending_temperatures: list[tuple[int, dict, set]] = []
        self._pending_profiles: list[tuple[int, str, np.ndarray, np.ndarray]] = []
        node.create_subscription(TemperatureArray, "temperatures",
                                 health.guard("temperatures", self._on_temperatures), SENSOR_QOS)
        for axis in ("x", "y", "z"):
            node.create_subscription(SystematicProfile, f"systematic/{axis}",
                                     health.guard(f"systematic/{axis}", self._on_profile),
                                     RESULT_QOS)
        self._pending_model = None   # (message, future of (parse error, gate problem))
        self._queued_model = None    # a newer message while one is being gated
        self._pool = None
        if follow_topic:
            from rclpy.clock import Clock, ClockType

            self._pool = _gate_pool()
            if getattr(self._pool, "fallback_reason", ""):
                health.warn(self._pool.fallback_reason)
            node.create_subscription(ModelVersion, "model", health.guard("model", self._on_model),
                                     LATCHED_QOS)
            node.create_timer(0.02, self._poll_model, clock=Clock(clock_type=ClockType.STEADY_TIME))

    def set_model(self, model: ErrorModel, *, keep_version: bool = False) -> None:
        """Make ``model`` live. Its version becomes the live one + 1 unless ``keep_version``
        (a version numbered by the monitor, already checked to be >= the live one)."""
        # Profiles and temperature references live on across model versions.
        model.profiles.update({k: v for k, v in self.model.profiles.items()
                               if k not in model.profiles})
        for sensor, value in self.model.reference_temperatures_c.items():
            model.reference_temperatures_c.setdefault(sensor, value)
        for name, value in self.model.profile_offsets.items():
            model.profile_offsets.setdefault(name, value)
        if not keep_version:
            model.version = max(model.version, self.model.version + 1)
        self.model = model
        self.on_change()

    def evaluated(self, model: ErrorModel) -> None:
        """``model`` gave corrections at the machine: a version to fall back to."""
        if not self._evaluated or self._evaluated[-1] is not model:
            self._evaluated = [m for m in self._evaluated[-2:] if m is not model] + [model]

    def revert_to_good(self, reason: str) -> bool:
        """Make the newest other version that evaluated live again after the live one
        failed (counted, ERROR on /diagnostics); False when there is none."""
        failing = self.model
        self._evaluated = [m for m in self._evaluated if m is not failing]
        if not self._evaluated:
            return False
        good = self._evaluated[-1]
        self.health.refused("model", f"{reason}; version {good.version}, the last that "
                            "evaluated, is live again")
        self.health.alarm(f"model version {failing.version} failed at the machine: "
                          f"{reason}; version {good.version} is live again")
        self.model = good
        self.on_change()
        return True

    def _on_model(self, message: ModelVersion) -> None:
        self.health.sequence("model", message.sequence)
        if self._pending_model is not None:
            self._queued_model = message   # gated once the one in hand is settled
            return
        self._submit(message)

    def _settled(self, version: int) -> None:
        if version > self.settled_version:
            self.settled_version = int(version)
            if self.on_settled is not None:
                self.on_settled(self.settled_version)

    def _older_than_live(self, message: ModelVersion) -> bool:
        if message.version >= self.model.version:
            return False
        self._settled(message.version)
        # Counted and on /diagnostics; the live model stays.
        self.health.refused("model", f"model version {message.version} is older than the "
                            f"live version {self.model.version}: refused, the live one stays")
        return True

    def _submit(self, message: ModelVersion) -> None:
        if not self._older_than_live(message):
            self._pending_model = (message, self._pool.submit(gate_model_text, message.model_yaml,
                                                          self.gate, self.model_dir,
                                                          self.trusted_machines))

    def _poll_model(self) -> None:
        """Settle a gated version (live or refused) once its worker is done, then gate
        the version that arrived meanwhile, if any."""
        if self._pending_model is None or not self._pending_model[1].done():
            return
        message, future = self._pending_model
        self._pending_model = None
        try:
            parse_error, problem = future.result()
            model = None if parse_error or problem else network_model(
                message.model_yaml, self.model_dir, self.trusted_machines)
        except Exception as exc:  # noqa: BLE001 - a dead worker must not kill the node
            parse_error, problem = "", f"its gate failed ({type(exc).__name__}: {exc})"
        if parse_error:
            self.health.refused("model", f"model refused, version {self.model.version} kept: "
                                f"{parse_error}")
        elif problem:
            self.health.refused("model", f"model version {message.version} refused before going "
                                f"live: {problem}; version {self.model.version} stays")
        elif not self._older_than_live(message):   # the live one may have moved on meanwhile
            self._make_live(message, model)
        self._settled(message.version)
        if self._queued_model is not None:
            queued, self._queued_model = self._queued_model, None
            self._submit(queued)

    def _make_live(self, message: ModelVersion, model: ErrorModel) -> None:
        self.health.processed("model")
        model.version = int(message.version)
        if model.version > self.model.version or \
                model_to_dict(model)["effects"] != model_to_dict(self.model)["effects"] or \
                model.reference_temperatures_c != self.model.reference_temperatures_c:
            self.set_model(model, keep_version=True)

    def shutdown(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)

    def _on_temperatures(self, message: TemperatureArray) -> None:
        values = unpack_float64(message.temperatures)
        if len(values) != len(message.sensor_names):
            raise InputDataError(f"{len(message.sensor_names)} sensor names but {len(values)} "
                                 "temperatures")
        self.health.sequence("temperatures", message.sequence)
        self.health.processed("temperatures")
        readings = {name: float(v) for name, v in zip(message.sensor_names, values)}
        stamp = stamp_to_nanoseconds(message.header.stamp)
        self.last_stamp["temperatures"] = max(self.last_stamp.get("temperatures", stamp), stamp)
        if stamp <= self._applied_until:
            self.health.late("temperatures")
        self._pending_temperatures.append((stamp, readings))
        self._pending_temperatures.sort(key=lambda item: item[0])

    def _on_profile(self, message: SystematicProfile) -> None:
        if message.unit != "rad" or not message.error_name:
            raise InputDataError(f"profile {message.error_name!r} in {message.unit!r}: only "
                                 "angular profiles [rad] feed the model")
        positions = unpack_float64(message.positions)
        if positions.size != len(message.systematic) or not np.all(np.isfinite(positions)):
            raise InputDataError(f"profile {message.error_name}: positions and values differ "
                                 "in length or are not finite")
        stream = f"systematic/{message.axis or '?'}"
        self.health.sequence(stream, message.sequence)
        self.health.processed(stream)
        stamp = stamp_to_nanoseconds(message.header.stamp)
        self.last_stamp[stream] = max(self.last_stamp.get(stream, stamp), stamp)
        if stamp <= self._applied_until:
            self.health.late(stream)
        difference = unpack_float64(message.baseline_difference).copy()
        self._pending_profiles.append((stamp_to_nanoseconds(message.header.stamp),
                                       message.error_name,
                                       unpack_float64(message.positions).copy(),
                                       unpack_float64(message.systematic).copy(),
                                       difference if difference.size else None))
        self._pending_profiles.sort(key=lambda item: item[0])

    def advance(self, stamp_ns: int) -> None:
        """Apply every input stamped at or before ``stamp_ns - delay``, in stamp order."""
        limit = stamp_ns - self.delay_ns
        self._applied_until = max(self._applied_until, limit)
        while self._pending_temperatures and self._pending_temperatures[0][0] <= limit:
            _, readings = self._pending_temperatures.pop(0)
            # Judged in data-time order (a frozen sensor is a run of readings): what the
            # judge leaves out never reaches the model, which holds the sensor's last
            # valid value.
            good, dead = self._watch.judge(readings)
            self._say_dead(dead)
            self.temperatures.update(good)
            # Rises count from the first reading of each sensor in data time - the
            # cold state the model and the work zero refer to - not from whenever the
            # model happens to be evaluated first (a late reference is a constant
            # error of beta x the rise missed; every node gets the same one).
            for sensor, value in good.items():
                self.model.reference_temperatures_c.setdefault(sensor, value)
        changed = False
        while self._pending_profiles and self._pending_profiles[0][0] <= limit:
            _, name, positions, values, difference = self._pending_profiles.pop(0)
            try:
                changed = self.model.apply_profile(name, positions, values, difference) or changed
            except MtAccuracyError as exc:
                self.health.refused(f"systematic/{name}", f"profile ignored: {exc}")
        if changed and self.on_profiles is not None:
            self.on_profiles()

    @property
    def dead(self) -> set[str]:
        """The sensors whose latest reading was left out."""
        return set(self.dead_kinds)

    def _say_dead(self, dead: dict[str, tuple[str, str]]) -> None:
        """A WARN on /diagnostics naming each sensor that goes bad, once per kind of
        trouble (a log line when it reads valid again): never silently dropped, never
        silently used."""
        for name, (kind, why) in dead.items():
            if self.dead_kinds.get(name) != kind:
                held = self.temperatures.get(name)
                self.health.warn(
                    f"temperature sensor {name}: {why} - left out of the model's inputs"
                    + (f"; its last valid value {held:.2f} degC is held" if held is not None
                       else "; no valid value yet, the model goes without it"))
        for name in set(self.dead_kinds) - set(dead):
            self.node.get_logger().info(f"temperature sensor {name} reads valid values again")
        self.dead_kinds = {name: kind for name, (kind, _) in dead.items()}

    def silent(self, stamp_ns: int, horizon_s: float) -> dict[str, float]:
        """Input streams seen before that sent nothing for more than ``horizon_s`` of data
        time before ``stamp_ns``: stream -> seconds of silence."""
        return {stream: (stamp_ns - last) * 1e-9 for stream, last in self.last_stamp.items()
                if stamp_ns - last > horizon_s * 1e9}

    def model_yaml(self) -> str:
        return yaml.safe_dump(model_to_dict(self.model), sort_keys=False)
