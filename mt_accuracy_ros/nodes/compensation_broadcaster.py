"""Volumetric compensation broadcaster: the model's TCP error and correction, live.

From the CNC command positions in ``scales`` (``ScaleBatch``), the latest
``temperatures`` and the measured yaw profiles (``systematic/<axis>``), the
current :class:`~mt_accuracy_ros.core.compensation.error_model.ErrorModel` gives the TCP
error at the command position, published on ``compensation``
(``VolumetricCompensation``, reliable) at ``publish_rate_hz`` of data time
(every n-th sample, whatever the batch boundaries), with correction = -error;
on a machine with rotary axes the correction also turns the rotary axes
(``rotary_corrections``) so that the tool's direction is nominal again, and
the TCP correction includes the shift that turn causes
(:mod:`mt_accuracy_ros.core.compensation.five_axis`).
Whenever the model changes (a new profile, a new effect) the per-axis
component tables go out on ``compensation_table`` (``CompensationTable``,
reliable + transient local, so a node started later still gets them).

The model comes from the ``model`` parameter (bundled name, path or inline
YAML; changeable at run time) and, with ``follow_model_topic``, from the
model monitor's ``model`` topic. Either way a version whose corrections would
exceed the controller's limits (the machine's ``cnc:`` section:
``max_correction_m``, ``max_correction_rate_m_per_s``) anywhere in the travel
and temperature range is refused before it goes live - counted and said on
``/diagnostics`` - and the last good version stays
(:mod:`..core.compensation.limits`).
"""
from __future__ import annotations

import sys

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.node import Node

from mt_accuracy_msgs.msg import CompensationTable, ScaleBatch, VolumetricCompensation

from ..core.compensation.five_axis import five_axis_correction
from ..core.compensation.limits import gate_problem
from ..core.inputs.stream_history import StreamHistory
from ..core.errors import InputDataError, MtAccuracyError
from ..core.validation import sample_period
from ._lockstep import ProgressReporter, report_after
from ._common import (COMPENSATION_QOS, TABLE_QOS, run_node, RESULT_QOS,  # noqa: F401
                      SENSOR_QOS, accept, float_descriptor, int_descriptor,
                      nanoseconds_to_stamp, pack_float64, plain_descriptor, refuse,
                      stamp_to_nanoseconds, unpack_float64)
from ._health import DeliveryHealth
from ._priority import declare_niceness
from ._model_inputs import MODEL_DIR_DESCRIPTION, ModelInputs, network_model

class CompensationBroadcaster(Node):
    """ScaleBatch command positions -> VolumetricCompensation; tables on model change."""

    def __init__(self, **kwargs) -> None:
        super().__init__("compensation_broadcaster", **kwargs)
        self.declare_parameter("model", "demo", plain_descriptor(
            "Error model: bundled name, path to a model YAML, or inline YAML (set at run "
            "time: inline YAML, a bundled name or a file in model_dir - never a path)"))
        self.declare_parameter("model_dir", "", plain_descriptor(MODEL_DIR_DESCRIPTION,
                                                                read_only=True))
        self.declare_parameter("follow_model_topic", True, plain_descriptor(
            "Also take models published on 'model' (by the model monitor)", read_only=True))
        self.declare_parameter("publish_rate_hz", 100.0, float_descriptor(
            "Compensation messages per second of data time", 1.0, 20000.0))
        self.declare_parameter("table_points", 401, int_descriptor(
            "Positions per axis in a compensation table", 2, 10000))
        self.declare_parameter("input_delay_s", 0.5, float_descriptor(
            "Use temperatures/profiles stamped this much before the data (deterministic "
            "replay) [s]", 0.0, 60.0, read_only=True))
        self.declare_parameter("stream_horizon_s", 60.0, float_descriptor(
            "Largest gap a scale batch may open in its stream, and the largest disagreement "
            "of its stamp with the one its sample index predicts [s]; a batch beyond it is "
            "refused (forged or corrupt) until 3 consistent batches confirm a new position",
            0.001, 86400.0, read_only=True))
        self.declare_parameter("input_timeout_s", 10.0, float_descriptor(
            "Data time after which a silent input (temperatures, a systematic profile) is "
            "reported: WARN, and ERROR after 3x; meanwhile its last value is held [s]",
            0.1, 3600.0, read_only=True))
        self.declare_parameter("lockstep", False, plain_descriptor(
            "Report on 'lockstep' how far the scales are compensated and which model version "
            "is settled (a lockstep run)", read_only=True))
        self.add_on_set_parameters_callback(self._validate)
        self.health = DeliveryHealth(self)
        declare_niceness(self, self.health)
        self._silent_level: dict[str, int] = {}   # stream -> 0 ok, 1 warned, 2 error
        self._input_timeout_s = float(self.get_parameter("input_timeout_s").value)
        self._history = StreamHistory(float(self.get_parameter("stream_horizon_s").value))
        self.inputs = ModelInputs(self, str(self.get_parameter("model").value),
                                  follow_topic=bool(self.get_parameter("follow_model_topic").value),
                                  on_change=self._model_changed, health=self.health,
                                  delay_s=float(self.get_parameter("input_delay_s").value),
                                  gate=gate_problem,
                                  model_dir=str(self.get_parameter("model_dir").value))
        self._compensation = self.create_publisher(VolumetricCompensation, "compensation",
                                                   COMPENSATION_QOS)
        self._tables = self.create_publisher(CompensationTable, "compensation_table", TABLE_QOS)
        self._diagnostics = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self._published_version = (-1, -1)
        self._last_direction: dict[str, float] = {}
        self._reported_dead: set[str] = set()
        self._last_stamp = -1
        self._compensation_sequence = 0
        self._table_sequence = 0
        self._progress = ProgressReporter(self, follows_models=True) \
            if self.get_parameter("lockstep").value else None
        if self._progress is not None:
            self.inputs.on_settled = lambda version: self._progress.report(settled=version)
            self._progress.report(settled=self.inputs.settled_version)
        self.create_subscription(ScaleBatch, "scales", report_after(
            self._progress, self.health.guard("scales", self._on_batch)), SENSOR_QOS)
        self._publish_tables()
        self._warm_up()

    def _warm_up(self) -> None:
        """Evaluate a copy of the model once before the first batch: the first call's
        lazy imports and first-use costs would otherwise fall on the first batches, whose
        corrections then reach a running CNC too late (a start-up burst of stale ones on
        a loaded host). A copy, so the live model's lag states stay untouched."""
        import copy

        try:
            model = copy.deepcopy(self.inputs.model)
            machine = model.machine
            positions = {a: np.full(2, 0.5 * sum(machine.axes[a].stroke))
                         for a in machine.axis_order}
            zeros = {a: np.zeros(2) for a in machine.axis_order}
            self._evaluate(model, positions, zeros, zeros, np.array([0.0, 0.01]), zeros)
        except Exception as exc:  # noqa: BLE001 - a warm-up never stops the node
            self.get_logger().debug(f"warm-up skipped: {type(exc).__name__}: {exc}")

    def destroy_node(self) -> None:
        self.inputs.shutdown()
        super().destroy_node()

    def _validate(self, parameters):
        try:
            return self._apply(parameters)
        except Exception as exc:  # noqa: BLE001 - a parameter must never kill the node
            self.health.refused("parameters", f"{type(exc).__name__}: {exc}")
            return refuse(f"{type(exc).__name__}: {exc}")

    def _apply(self, parameters):
        for parameter in parameters:
            if parameter.name == "model":
                try:
                    model = network_model(str(parameter.value), self.inputs.model_dir,
                                          self.inputs.trusted_machines)
                except MtAccuracyError as exc:
                    self.health.refused("parameters", f"model refused: {exc}")
                    return refuse(f"model refused: {exc}")
                problem = gate_problem(model)
                if problem:
                    text = (f"model refused before going live: {problem}; version "
                            f"{self.inputs.model.version} stays")
                    self.health.refused("parameters", text)
                    return refuse(text)
                self.inputs.set_model(model)
            if parameter.name == "publish_rate_hz" and not np.isfinite(parameter.value):
                return refuse("publish_rate_hz must be finite")
        return accept()

    def _model_changed(self) -> None:
        pass  # tables go out with the next batch, stamped in data time

    def _on_batch(self, message: ScaleBatch) -> None:
        axes = [a.upper() for a in message.command_axes]
        commands = unpack_float64(message.command_positions)
        if not axes or commands.size % len(axes):
            raise InputDataError(f"{commands.size} command positions do not fill "
                                 f"{len(axes)} axes")
        period = sample_period(message.sample_period)
        if not np.all(np.isfinite(commands)):
            raise InputDataError("command positions not finite")
        commands = commands.reshape(-1, len(axes))
        stamp = stamp_to_nanoseconds(message.header.stamp)
        if stamp <= self._last_stamp:
            raise InputDataError(f"stamp {stamp} ns not after the last one ({self._last_stamp} ns):"
                                 " out of order or repeated")
        restarts = self._history.restarts
        self._history.check(message.first_sample_index, commands.shape[0], stamp, period)
        self.health.sequence("scales", message.first_sample_index, commands.shape[0],
                             restart=self._history.restarts != restarts)
        self.health.processed("scales", commands.shape[0])
        self._last_stamp = stamp
        self.inputs.advance(stamp)
        self._check_liveness(stamp)
        if self.inputs.dead != self._reported_dead:
            self._reported_dead = set(self.inputs.dead)
            if self._reported_dead:
                self._warn(f"no valid reading from {', '.join(sorted(self._reported_dead))}; "
                           "their last valid value is used")
        rate_hz = float(self.get_parameter("publish_rate_hz").value)
        step = max(1, int(round(1.0 / (period * rate_hz))))
        # Every step-th sample of the run, on a grid fixed in data time (replays give the
        # same rows whatever the batching): samples step-1, 2 step-1, ... - the last of
        # each interval, so that a batch's newest sample, not its oldest, is corrected
        # (a batch period less latency). Reduced first: an index near 2**64 must not
        # overflow int64.
        first = int(message.first_sample_index) % step
        rows = np.flatnonzero((first + np.arange(commands.shape[0]) + 1) % step == 0)
        if rows.size == 0:
            return
        velocity = np.gradient(commands, period, axis=0) if commands.shape[0] > 1 \
            else np.zeros_like(commands)
        positions = {a: commands[rows, j] for j, a in enumerate(axes)}
        velocities = {a: velocity[rows, j] for j, a in enumerate(axes)}
        directions = {a: self._held_directions(a, velocity[:, j])[rows] for j, a in enumerate(axes)}
        model = self.inputs.model
        # Sample times in data time: lagged catalogue effects continue their state.
        times = (stamp + rows * period * 1e9) * 1e-9
        accelerations = {a: np.gradient(velocity[:, j], period)[rows]
                         if velocity.shape[0] > 2 else np.zeros(rows.size)
                         for j, a in enumerate(axes)}
        inputs = (positions, velocities, directions, times, accelerations)
        try:
            error, orientation, correction, rotary_correction = self._evaluate(model, *inputs)
        except InputDataError as exc:   # the batch's fault, not the model's
            self._warn(f"no compensation for this batch: {exc}")
            return
        except Exception as exc:  # noqa: BLE001 - a live model must never stop compensation
            # A model that passed every load-time check and still fails here (an overflow
            # or NaN on inputs outside the checked grid, a variable these data lack): the
            # last version that evaluated takes over.
            reason = f"{type(exc).__name__}: {exc}"[:300]
            if not self.inputs.revert_to_good(f"version {model.version} failed to evaluate "
                                              f"({reason})"):
                self._warn(f"no compensation for this batch: the model failed ({reason})")
                return
            model = self.inputs.model
            try:
                error, orientation, correction, rotary_correction = self._evaluate(model,
                                                                                   *inputs)
            except Exception as again:  # noqa: BLE001
                self._warn(f"no compensation for this batch: {type(again).__name__}: {again}")
                return
        self.inputs.evaluated(model)
        rotary = [a for a in model.machine.axis_order if model.machine.axes[a].is_rotary]
        if self._published_version != (model.version, model.profile_revision):
            self._publish_tables()
        for k, row in enumerate(rows):
            out = VolumetricCompensation()
            out.header.stamp = nanoseconds_to_stamp(stamp + int(round(row * period * 1e9)))
            out.header.frame_id = message.header.frame_id
            linear = [a for a in axes if a in "XYZ"]
            point = {a: float(positions[a][k]) for a in linear}
            out.command_position.x = point.get("X", 0.0)
            out.command_position.y = point.get("Y", 0.0)
            out.command_position.z = point.get("Z", 0.0)
            # The machine's order, the same as rotary_corrections'.
            out.rotary_positions = [float(positions[a][k]) for a in rotary]
            out.error.x, out.error.y, out.error.z = (float(v) for v in error[k])
            (out.orientation_error.x, out.orientation_error.y,
             out.orientation_error.z) = (float(v) for v in orientation[k])
            out.correction.x, out.correction.y, out.correction.z = (float(v) for v in
                                                                    correction[k])
            out.rotary_corrections = [float(v) for v in rotary_correction[k]]
            out.uncertainty = 0.0
            out.model_version = int(model.version)
            out.sequence = self._compensation_sequence
            self._compensation_sequence += 1
            self._compensation.publish(out)

    def _check_liveness(self, stamp: int) -> None:
        """An input that stopped (its node died, its link broke) is said on /diagnostics:
        WARN after ``input_timeout_s`` of data time, ERROR after three times that. The safe
        state meanwhile: its last value is held (the last profile, the last temperature),
        the tables stay, compensation goes on - and the operator is told."""
        horizon = self._input_timeout_s     # read-only: not looked up on the hot path
        silent = self.inputs.silent(stamp, horizon)
        for stream in list(self._silent_level):
            if stream not in silent:
                del self._silent_level[stream]
                self._warn(f"{stream}: receiving again", level=DiagnosticStatus.OK)
        for stream, seconds in silent.items():
            level = 2 if seconds > 3 * horizon else 1
            if self._silent_level.get(stream, 0) >= level:
                continue
            self._silent_level[stream] = level
            source = "the yaw estimator" if stream.startswith("systematic") else \
                "the temperature source"
            text = (f"{stream}: nothing for {seconds:.1f} s of data ({source} stopped?); its "
                    "last value is held and compensation goes on with it")
            if level == 2:
                self.health.alarm(text, topic="inputs")
            else:
                self._warn(text)

    def _evaluate(self, model, positions, velocities, directions, times, accelerations):
        """(error, orientation, linear correction, rotary correction) of ``model`` at the rows;
        a non-finite result is an evaluation failure (FloatingPointError)."""
        with np.errstate(all="ignore"):
            error, orientation = model.tcp_error(positions, self.inputs.temperatures, velocities,
                                                 directions, time_s=times,
                                                 accelerations=accelerations)
            rotary = [a for a in model.machine.axis_order if model.machine.axes[a].is_rotary]
            correction, rotary_correction = -error, np.zeros((error.shape[0], 0))
            if rotary:
                # The tool's direction is put right by the rotary axes, its tip by the
                # linear ones (including the shift the rotary correction causes).
                five = five_axis_correction(model.kinematics, positions, error, orientation)
                correction, rotary_correction = five.position_m, five.rotary_rad
        if not (np.all(np.isfinite(correction)) and np.all(np.isfinite(rotary_correction))
                and np.all(np.isfinite(orientation))):
            raise FloatingPointError("non-finite compensation")
        return error, orientation, correction, rotary_correction

    def _held_directions(self, axis: str, velocity: np.ndarray) -> np.ndarray:
        """Sign of each sample's last motion, carried across batches (backlash at a stop)."""
        moving = np.abs(velocity) > 1e-9
        index = np.where(moving, np.arange(velocity.size), -1)
        np.maximum.accumulate(index, out=index)
        previous = self._last_direction.get(axis, 0.0)
        held = np.where(index >= 0, np.sign(velocity[np.maximum(index, 0)]), previous)
        if held.size:
            self._last_direction[axis] = float(held[-1])
        return held

    def _publish_tables(self) -> None:
        model = self.inputs.model
        points = int(self.get_parameter("table_points").value)
        for axis in model.machine.axis_order:
            spec = model.machine.axes[axis]
            if spec.is_rotary:
                continue
            grid = np.linspace(*spec.stroke, points)
            columns = [f"{axis}_m"]
            values = [grid]
            for name, column in model.component_errors(axis, grid).items():
                columns.append(f"{name}_{'m' if name[1] in 'XYZ' else 'rad'}")
                values.append(column)
            table = CompensationTable()
            table.header.stamp = self.get_clock().now().to_msg()
            table.header.frame_id = model.machine.name
            table.model_version = int(model.version)
            table.sequence = self._table_sequence
            self._table_sequence += 1
            table.axis = axis.lower()
            table.columns = columns
            table.values = pack_float64(np.column_stack(values).ravel())
            squareness = model.location_table()
            table.squareness_names = list(squareness)
            table.squareness = [float(v) for v in squareness.values()]
            self._tables.publish(table)
        self._published_version = (model.version, model.profile_revision)

    def _warn(self, text: str, level=DiagnosticStatus.WARN) -> None:
        status = DiagnosticStatus(level=level,
                                  name=f"{self.get_fully_qualified_name()}: model", message=text)
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics.publish(array)


def main(args: list[str] | None = None) -> int:
    """Entry point (console_scripts)."""
    return run_node(CompensationBroadcaster, args, events=True)


if __name__ == "__main__":
    sys.exit(main())
