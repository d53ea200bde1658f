"""Property-based fuzzing of every input path a user or a graph can feed (issue 17).

Each target takes one generated input and calls a loader or a node's message
handler **unguarded**; the property is that bad input only ever raises this
package's own errors (:class:`~mt_accuracy_ros.core.errors.MtAccuracyError`
and its subclasses) - never a ``TypeError`` from deep inside numpy, a
``ZstdError`` from a corrupt chunk, or anything that would have killed a
node without its guard. Anything else fails the run with the input that
caused it.

Used by ``test/studies/test_fuzz.py`` (a fast, derandomised sample) and by
``bench/fuzz.py`` (10,000 cases per target, recorded in docs/reliability.md).
"""
from __future__ import annotations

import copy
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import yaml
from hypothesis import strategies as st

import mt_accuracy_ros
from mt_accuracy_ros.core.errors import MtAccuracyError

PACKAGE_DIR = Path(mt_accuracy_ros.__file__).resolve().parent

#: Any value a YAML document can hold.
YAML_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-10**6, 10**6)
    | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=12),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner,
                                                                  max_size=4),
    max_leaves=12)
FLOATS = st.floats(allow_nan=True, allow_infinity=True, width=64)


@st.composite
def mutated(draw, base):
    """``base`` (a parsed YAML mapping) with 1-3 values replaced, keys added or removed."""
    data = copy.deepcopy(base)
    for _ in range(draw(st.integers(1, 3))):
        node = data
        # Walk down a random path of mappings and lists.
        while isinstance(node, (dict, list)) and node and draw(st.booleans()):
            keys = list(node) if isinstance(node, dict) else list(range(len(node)))
            key = draw(st.sampled_from(keys))
            if not isinstance(node[key], (dict, list)) or not node[key]:
                break
            node = node[key]
        if isinstance(node, dict):
            action = draw(st.sampled_from(["replace", "add", "remove"]))
            if action == "add" or not node:
                node[draw(st.text(max_size=8))] = draw(YAML_VALUES)
            elif action == "remove":
                del node[draw(st.sampled_from(list(node)))]
            else:
                node[draw(st.sampled_from(list(node)))] = draw(YAML_VALUES)
        elif isinstance(node, list) and node:
            node[draw(st.integers(0, len(node) - 1))] = draw(YAML_VALUES)
    return data


def _only_package_errors(function: Callable, *args) -> None:
    try:
        function(*args)
    except MtAccuracyError:
        pass


# --------------------------------------------------------------------------- loaders
def _machine_base() -> dict:
    return yaml.safe_load((PACKAGE_DIR / "machines" / "kidani_hmc.yaml").read_text())


def _scenario_base() -> dict:
    return yaml.safe_load((PACKAGE_DIR / "scenarios" / "demo.yaml").read_text())


MODEL_BASE = {"machine": "kidani_hmc", "version": 1,
              "effects": {"geometric": {}, "squareness": {"errors_rad": {"EC0Y": 1e-5}},
                          "structural_thermal_drift": {}},
              "reference_temperatures_c": {"column_top": 20.0}}


def machine_dict(data) -> None:
    from mt_accuracy_ros.core.kinematics.machine import machine_from_dict

    _only_package_errors(machine_from_dict, data, "fuzz.yaml")


def scenario_dict(data) -> None:
    from mt_accuracy_ros.sim.scenario import scenario_from_dict

    _only_package_errors(scenario_from_dict, data, "fuzz.yaml")


def scenario_text(text: str) -> None:
    from mt_accuracy_ros.sim.scenario import scenario_from_yaml

    _only_package_errors(scenario_from_yaml, text, "fuzz.yaml")


def model_dict(data) -> None:
    """A model that loads must also evaluate, or refuse, with package errors only."""
    from mt_accuracy_ros.core.compensation.error_model import model_from_dict

    try:
        model = model_from_dict(data, "fuzz.yaml")
    except MtAccuracyError:
        return
    _only_package_errors(model.tcp_error, {"X": [0.1, -0.2], "Y": [0.05, 0.0], "Z": [0.0, 0.1]},
                         {"column_top": 25.0})


def model_text(text: str) -> None:
    from mt_accuracy_ros.core.compensation.error_model import resolve_model

    # Only inline YAML: a short word would be looked up as a file name.
    _only_package_errors(resolve_model, "# fuzz\n" + text)


def file_bytes(loader: str):
    """Random bytes written to a file and given to a file loader."""
    def target(data: bytes) -> None:
        from mt_accuracy_ros.core.compensation.error_model import load_model
        from mt_accuracy_ros.core.kinematics.machine import load_machine
        from mt_accuracy_ros.io.csv_table import read_csv_table
        from mt_accuracy_ros.sim.scenario import load_scenario

        function = {"machine": load_machine, "scenario": load_scenario, "model": load_model,
                    "csv": read_csv_table}[loader]
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / ("data.csv" if loader == "csv" else "data.yaml")
            path.write_bytes(data)
            _only_package_errors(function, path)
    return target


@st.composite
def csv_texts(draw) -> bytes:
    """Mostly well-formed numeric tables with NaN, text, ragged rows and odd headers."""
    columns = draw(st.integers(1, 5))
    header = draw(st.lists(st.sampled_from(["time_s", "t1_C", "e_um", "", "t1_C", "x"]) |
                           st.text(max_size=5), min_size=columns, max_size=columns))
    cell = st.floats(allow_nan=True, allow_infinity=True).map(repr) | st.text(max_size=4) | \
        st.integers(-100, 100).map(str)
    rows = draw(st.lists(st.lists(cell, min_size=max(0, columns - 1), max_size=columns + 1),
                         max_size=12))
    text = "\n".join([",".join(header)] + [",".join(r) for r in rows])
    return text.encode("utf-8", "surrogatepass") if draw(st.booleans()) else \
        text.encode("utf-8", "replace")


# --------------------------------------------------------------------------- MCAP
_BAGS: dict[str, bytes] = {}


def _sample_bag(compression: str | None) -> bytes:
    """A small real bag (std_msgs/String), written once per compression."""
    key = compression or "none"
    if key not in _BAGS:
        from rclpy.serialization import serialize_message
        from std_msgs.msg import String

        from mt_accuracy_ros.io.bag_writer import BagWriter

        with tempfile.TemporaryDirectory() as folder:
            with BagWriter(Path(folder) / "bag", compression=compression, chunk_size=256) as bag:
                bag.add_topic("/chatter", "std_msgs/msg/String")
                for i in range(40):
                    bag.write("/chatter", serialize_message(String(data=f"m{i}")), 10**9 + i)
            _BAGS[key] = (Path(folder) / "bag" / "bag_0.mcap").read_bytes()
    return _BAGS[key]


@st.composite
def damaged_bags(draw) -> bytes:
    """A real bag truncated, with bytes overwritten, or random bytes after the magic."""
    data = bytearray(_sample_bag(draw(st.sampled_from([None, "zstd"]))))
    kind = draw(st.sampled_from(["truncate", "overwrite", "both", "random"]))
    if kind == "random":
        return b"\x89MCAP0\r\n" + draw(st.binary(max_size=400))
    if kind in ("overwrite", "both"):
        for _ in range(draw(st.integers(1, 8))):
            position = draw(st.integers(0, len(data) - 1))
            data[position] = draw(st.integers(0, 255))
    if kind in ("truncate", "both"):
        data = data[:draw(st.integers(0, len(data)))]
    return bytes(data)


def mcap_file(data: bytes) -> None:
    from mt_accuracy_ros.io.bag_reader import bag_info, decode, read_messages, recover, topics

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "bag_0.mcap"
        path.write_bytes(data)
        for function in (bag_info, topics, recover):
            _only_package_errors(function, path)
        try:
            for message in read_messages(path):
                _only_package_errors(decode, message)
        except MtAccuracyError:
            pass


# --------------------------------------------------------------------------- messages
STAMPS = st.integers(0, 2**62)
NAMES = st.sampled_from(["x1", "x2", "y1", "y2", "z1", "z2", "column_top", "x1_s0"]) | \
    st.text(max_size=4)
AXES = st.sampled_from(["x", "y", "z", "a", "b", "c", "w", "X"]) | st.text(max_size=3)


def _stamp(nanoseconds: int):
    from mt_accuracy_ros.io.fields import nanoseconds_to_stamp

    return nanoseconds_to_stamp(nanoseconds)


@st.composite
def scale_batches(draw):
    from mt_accuracy_msgs.msg import ScaleBatch

    message = ScaleBatch()
    message.header.stamp = _stamp(draw(STAMPS))
    message.first_sample_index = draw(st.integers(0, 2**64 - 1))
    message.sample_period = draw(FLOATS | st.sampled_from([0.001, 0.0005]))
    message.channel_names = draw(st.lists(NAMES, max_size=6))
    message.positions = draw(st.lists(FLOATS | st.floats(-0.5, 0.5), max_size=60))
    message.command_axes = draw(st.lists(AXES, max_size=4))
    message.command_positions = draw(st.lists(FLOATS | st.floats(-0.5, 0.5), max_size=60))
    return message


@st.composite
def temperature_arrays(draw):
    from mt_accuracy_msgs.msg import TemperatureArray

    message = TemperatureArray()
    message.header.stamp = _stamp(draw(STAMPS))
    message.sequence = draw(st.integers(0, 2**64 - 1))
    message.sensor_names = draw(st.lists(NAMES, max_size=6))
    message.temperatures = draw(st.lists(FLOATS | st.floats(15, 40), max_size=6))
    return message


@st.composite
def profiles(draw):
    from mt_accuracy_msgs.msg import SystematicProfile

    message = SystematicProfile()
    message.header.stamp = _stamp(draw(STAMPS))
    message.sequence = draw(st.integers(0, 2**64 - 1))
    message.axis = draw(AXES)
    message.error_name = draw(st.sampled_from(["ECX", "ECY", "EBZ", "EXX", "", "ECQ"]) |
                              st.text(max_size=4))
    message.unit = draw(st.sampled_from(["rad", "m", ""]))
    message.positions = draw(st.lists(FLOATS | st.floats(-0.5, 0.5), max_size=20))
    message.systematic = draw(st.lists(FLOATS | st.floats(-1e-4, 1e-4), max_size=20))
    return message


@st.composite
def references(draw):
    from mt_accuracy_msgs.msg import ReferenceMeasurement

    message = ReferenceMeasurement()
    message.header.stamp = _stamp(draw(STAMPS))
    message.sequence = draw(st.integers(0, 2**64 - 1))
    # Mostly plausible readings of the HMC's three axes, so that checks run on them.
    message.command_axes = draw(st.just(["x", "y", "z"]) | st.lists(AXES, max_size=4))
    message.command_positions = draw(st.lists(st.floats(-0.5, 0.5), min_size=3, max_size=3)
                                     | st.lists(FLOATS, max_size=4))
    message.command_velocities = draw(st.lists(FLOATS, max_size=4))
    message.command_directions = draw(st.lists(st.integers(-128, 127), max_size=4))
    values = st.floats(-1e-4, 1e-4) | FLOATS
    message.error.x, message.error.y, message.error.z = (draw(values) for _ in range(3))
    message.measured = draw(st.lists(st.booleans(), min_size=3, max_size=3))
    message.uncertainty = draw(st.floats(0, 1e-5) | FLOATS)
    return message


#: The DDS domain the fuzzing nodes run in (not 0, the default of every cell).
FUZZ_DOMAIN_ID = 167


class NodeHarness:
    """The model nodes, in this process, whose raw handlers the message targets call."""

    def __init__(self) -> None:
        import rclpy

        from mt_accuracy_ros.nodes.compensation_broadcaster import CompensationBroadcaster
        from mt_accuracy_ros.nodes.model_monitor import ModelMonitor
        from mt_accuracy_ros.nodes.yaw_estimator import YawEstimator

        self.context = rclpy.Context()
        # Its own DDS domain and namespace: a fuzzing run must never talk to a real cell's
        # graph (or a test's) on the default domain, nor be mistaken for its nodes.
        rclpy.init(context=self.context, domain_id=FUZZ_DOMAIN_ID)
        kwargs = {"context": self.context, "namespace": "fuzz"}
        self.estimator = YawEstimator(**kwargs)
        self.broadcaster = CompensationBroadcaster(**kwargs)
        self.monitor = ModelMonitor(**kwargs)

    def close(self) -> None:
        import rclpy

        for node in (self.estimator, self.broadcaster, self.monitor):
            node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def message_targets(harness: NodeHarness) -> dict[str, tuple]:
    """(strategy, target) per node handler."""
    def advance(message):
        harness.broadcaster.inputs._on_profile(message)
        harness.broadcaster.inputs.advance(2**63 - 1)

    def model_string(text):
        from mt_accuracy_msgs.msg import ModelVersion

        harness.broadcaster.inputs._on_model(ModelVersion(version=2**31, model_yaml="# fuzz\n"
                                                          + text))

    def model_parameter(text):
        from rclpy.parameter import Parameter

        result = harness.monitor._validate([Parameter("model", value="# fuzz\n" + text)])
        assert result.successful or result.reason

    def wrap(handler):
        return lambda message: _only_package_errors(handler, message)

    model_yaml = mutated(MODEL_BASE).map(lambda d: yaml.safe_dump(d)) | st.text(max_size=60)
    return {
        "estimator.scales": (scale_batches(), wrap(harness.estimator._on_batch)),
        "estimator.temperatures": (temperature_arrays(), wrap(harness.estimator._on_temperatures)),
        "broadcaster.scales": (scale_batches(), wrap(harness.broadcaster._on_batch)),
        "broadcaster.temperatures": (temperature_arrays(),
                                     wrap(harness.broadcaster.inputs._on_temperatures)),
        "broadcaster.profiles": (profiles(), wrap(advance)),
        "broadcaster.model": (model_yaml, wrap(model_string)),
        "monitor.references": (references(), wrap(harness.monitor._on_reading)),
        "monitor.model_parameter": (model_yaml, model_parameter),
    }


#: What a hostile peer names as a model: paths of every kind, traversal, specials.
NETWORK_PATHS = st.sampled_from([
    "/etc/passwd", "/proc/self/environ", "/dev/zero", "/dev/stdin", "../models/demo.yaml",
    "demo.yaml", "/tmp", "~/.ssh/id_rsa", "C:\\Windows\\win.ini", "file:///etc/passwd",
    "kidani_hmc/../../etc/passwd", "models/../../x.yml", "\x00", " /etc/hosts ",
    # Valid files by path: a network model must not reach them either.
    str(Path(mt_accuracy_ros.__file__).parent / "machines" / "kidani_hmc.yaml"),
    str(Path(mt_accuracy_ros.__file__).parent / "models" / "demo.yaml")])


@st.composite
def network_models(draw):
    """A model string from the network: a path, or inline YAML whose machine is one."""
    path = draw(NETWORK_PATHS | st.text(max_size=40))
    kind = draw(st.sampled_from(["bare", "inline", "block"]))
    if kind == "bare":
        return path
    machine = yaml.safe_dump(path).strip().removesuffix("...").strip()
    return f"{{machine: {machine}}}" if kind == "inline" else f"machine: {machine}\n"


def network_model(text: str) -> None:
    """A network model opens no file outside the bundled directories: it is refused
    (ParameterError) or it is inline YAML / a bundled name on a bundled machine."""
    from mt_accuracy_ros.core.compensation.error_model import resolve_model
    from mt_accuracy_ros.core.kinematics.machine import bundled_machine_names

    try:
        model = resolve_model(text, from_network=True)
    except MtAccuracyError:
        return
    except Exception as exc:  # noqa: BLE001 - the property
        raise AssertionError(f"{type(exc).__name__} escaped for {text!r}: {exc}") from exc
    source = model.machine_source or model.machine.name
    assert source in bundled_machine_names(), f"{text!r} reached machine {source!r}"


def stream_batches(draw_list):
    from mt_accuracy_ros.core.errors import InputDataError
    from mt_accuracy_ros.core.inputs.stream_history import StreamHistory

    history = StreamHistory(60.0)
    for index, count, stamp, period in draw_list:
        try:
            lost = history.check(index, count, stamp, period)
        except InputDataError:
            continue
        # Whatever came before, a loss is never more than the horizon's worth of samples.
        assert -1 <= lost <= 60.0 / period + 1, (index, count, stamp, period, lost)


BATCH_HISTORIES = st.lists(st.tuples(
    st.integers(0, 2**64 - 1) | st.integers(0, 10**6), st.integers(1, 2000),
    st.integers(0, 2**63 - 1) | st.integers(10**9, 10**9 + 10**11),
    st.sampled_from([1e-3, 5e-5, 0.01, 1.0])), max_size=30)

#: Terms that overflow, are not finite or not defined somewhere in a machine's travel.
HOSTILE_TERMS = st.sampled_from([
    "9**9**9", "1" + "0" * 400, "1" + "0" * 1500, "exp(1000 * x)", "exp(40 * T_bed)",
    "log(x)", "1 / (y - y)", "sqrt(-1 - x)", "x ** -2", "10 ** 400", "cosh(1e4 * z)",
    "arcsin(2 + x)", "x", "x * y", "sin(x / 0.01)", "T_bed", "lag(T_bed, 600)"])


@st.composite
def hostile_expressions(draw):
    terms = draw(st.lists(HOSTILE_TERMS, min_size=1, max_size=3))
    value = draw(st.sampled_from(["1.0e-3", "1.0e+300", "1.0e-300", "-2.5e-6"]))
    return ("{machine: kidani_hmc, effects: {mine: {expression: 'k * " + " * ".join(terms) +
            "', parameters: [k], values: {k: " + value + "}}}}")


def expression_model(text: str) -> None:
    """A model with a user expression either is refused when it loads, or evaluates to
    finite values over the machine's travel and temperature range."""
    import numpy as np

    from mt_accuracy_ros.core.compensation.error_model import (representative_variables,
                                                               resolve_model)

    try:
        model = resolve_model(text)
    except MtAccuracyError:
        return
    variables = representative_variables(model.machine, {"T_bed"})
    model.reference_temperatures_c["bed"] = 20.0    # the load-time check's reference
    position, _ = model.tcp_error(variables.positions, {"bed": variables.temperatures["bed"]},
                                  time_s=variables.time_s)
    assert np.all(np.isfinite(position)), f"{text!r} loaded and evaluates to NaN/inf"


@dataclass(frozen=True)
class Target:
    name: str
    strategy: object
    check: Callable


def loader_targets() -> list[Target]:
    """The file and YAML loaders (no ROS graph needed)."""
    return [
        Target("machine.dict", mutated(_machine_base()), machine_dict),
        Target("machine.file", st.binary(max_size=300), file_bytes("machine")),
        Target("scenario.dict", mutated(_scenario_base()), scenario_dict),
        Target("scenario.text", st.text(max_size=200), scenario_text),
        Target("scenario.file", st.binary(max_size=300), file_bytes("scenario")),
        Target("model.dict", mutated(MODEL_BASE), model_dict),
        Target("model.text", st.text(max_size=200), model_text),
        Target("model.file", st.binary(max_size=300), file_bytes("model")),
        Target("csv.table", csv_texts(), file_bytes("csv")),
        Target("csv.bytes", st.binary(max_size=300), file_bytes("csv")),
        Target("mcap.damaged", damaged_bags(), mcap_file),
        Target("model.network", network_models(), network_model),
        Target("stream.history", BATCH_HISTORIES, stream_batches),
        Target("model.expression", hostile_expressions(), expression_model),
    ]
