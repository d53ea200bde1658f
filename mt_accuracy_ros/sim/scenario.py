"""Scenario files of the virtual machine tool (YAML), validated with line numbers.

Example (all keys but ``machine`` optional)::

    machine: kidani_hmc            # bundled name or path to a machine YAML
    seed: 7                        # the machine (geometry, scales)
    noise_seed: 8                  # the measurement noise (default: seed) - same machine, new run
    duration_s: 600                # simulated time [s]
    sample_rate_hz: 1000           # synchronous scale sampling, 100 ... 20000 Hz
    temperature_rate_hz: 1
    program: {type: back_and_forth, axes: [Y], feed_m_per_min: 30}
    spindle: {speed_rpm: 12000, max_rpm: 15000, intervals_s: [[0, 3600]]}
    noise: {scale_m: 20e-9, thermocouple_k: 0.02, scale_accuracy_fraction: 0.3}
    effects:
      scale_thermal_expansion: true            # defaults of mt_accuracy_ros.sim.effects
      timing_skew: {skew_s: 5e-6}              # on, with a magnitude
      geometric: false                         # switch a default-on effect off
    events:
      - {time_s: 300, enable: guideway_deterioration}
      - {time_s: 500, disable: timing_skew}
    work_offset: {X: 0.3, Y: 0.2, Z: 0.2, A: 0.0, B: 0.0}   # the reference instrument
                                   # is zeroed here at the start [m, rad]; absent: it
                                   # measures the error against the nominal (absolute)

Any mistake - an unknown key, effect or parameter, a negative rate, a
program leaving the stroke - raises :class:`ScenarioError` naming the file
and line.
"""
from __future__ import annotations

import copy
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from ..core.errors import MachineDescriptionError, ScenarioError, reraise_as
from ..core.kinematics.machine import MachineDescription, load_machine
from .effects import DEFAULT_ON, EFFECTS
from .programs import PROGRAMS

#: Rate [Hz] at which the program's motion heats the structure (whole run).
THERMAL_MOTION_RATE_HZ = 10.0
#: Most thermal time steps of one run (duration x rate; ~30 arrays of 8 B each).
MAX_THERMAL_STEPS = 4_000_000
#: Most scale samples simulated at once (a whole-run `simulate`, or one window):
#: ~40 arrays of 8 B each, ~6 GB at the limit.
MAX_WINDOW_SAMPLES = 20_000_000

TOP_KEYS = {"machine", "seed", "noise_seed", "duration_s", "sample_rate_hz", "temperature_rate_hz",
            "program", "spindle", "noise", "effects", "events", "start_time_s", "ambient",
            "description", "work_offset"}
NOISE_KEYS = {"scale_m": 20e-9, "resolution_m": 10e-9, "thermocouple_k": 0.02,
              "thermocouple_resolution_k": 0.01, "scale_accuracy_fraction": 0.3}
SPINDLE_KEYS = {"speed_rpm": 0.0, "max_rpm": 15000.0, "intervals_s": []}
AMBIENT_KEYS = {"amplitude_k": 0.3, "period_s": 86400.0, "mean_c": 20.0}


class _LineLoader(yaml.SafeLoader):
    """SafeLoader whose mappings remember the line of every key."""


class LineDict(dict):
    """A dict with ``lines[key]`` = 1-based line of that key in the file."""

    lines: dict
    line: int = 0


def _construct_mapping(loader, node):
    loader.flatten_mapping(node)
    out = LineDict()
    out.lines = {}
    out.line = node.start_mark.line + 1
    for key_node, value_node in node.value:
        key = loader.construct_object(key_node, deep=True)
        out[key] = loader.construct_object(value_node, deep=True)
        out.lines[key] = key_node.start_mark.line + 1
    return out


_LineLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)
# YAML 1.1 reads "1e-6" (no dot) as a string; scenario authors mean a number.
_LineLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"))


@dataclass
class Scenario:
    """A validated scenario; ``effects[name]`` holds the effective parameters."""

    machine: MachineDescription
    seed: int = 0
    noise_seed: int | None = None
    duration_s: float = 60.0
    sample_rate_hz: float = 1000.0
    temperature_rate_hz: float = 1.0
    start_time_s: float = 1.7e9
    program: dict = field(default_factory=lambda: {"type": "back_and_forth", "axes": ["X"]})
    spindle: dict = field(default_factory=lambda: dict(SPINDLE_KEYS))
    noise: dict = field(default_factory=lambda: dict(NOISE_KEYS))
    ambient: dict = field(default_factory=lambda: dict(AMBIENT_KEYS))
    effects: dict[str, dict] = field(default_factory=dict)
    enabled: set[str] = field(default_factory=lambda: set(DEFAULT_ON))
    events: list[tuple[float, str, bool]] = field(default_factory=list)
    source: str = "<dict>"
    description: str = ""
    #: Axis -> command where the reference instrument was zeroed (and the part touched
    #: off) at the start; empty: the instrument reads the error against the nominal.
    work_offset: dict[str, float] = field(default_factory=dict)

    def parameters(self, effect: str) -> dict:
        """Effective parameters of ``effect`` (defaults overridden by the scenario)."""
        base = {k: copy.deepcopy(v[0]) for k, v in EFFECTS[effect].parameters.items()}
        base.update(self.effects.get(effect, {}))
        return base

    def ever_enabled(self, effect: str) -> bool:
        return effect in self.enabled or any(e == effect and on for _, e, on in self.events)

    @property
    def n_samples(self) -> int:
        return int(round(self.duration_s * self.sample_rate_hz))


def _where(source: str, data, key=None) -> str:
    line = None
    if isinstance(data, LineDict):
        line = data.lines.get(key, data.line) if key is not None else data.line
    return f"{source}, line {line}" if line else source


def _number(data, key, source, low=None, high=None, default=None, integer=False):
    if key not in data:
        return default
    value = data[key]
    where = _where(source, data, key)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ScenarioError(f"{where}: {key} must be a number, got {value!r}")
    value = float(value)
    if value != value or value in (float("inf"), float("-inf")):
        raise ScenarioError(f"{where}: {key} must be finite")
    if low is not None and value < low:
        raise ScenarioError(f"{where}: {key} = {value:g} must be >= {low:g}")
    if high is not None and value > high:
        raise ScenarioError(f"{where}: {key} = {value:g} must be <= {high:g}")
    return int(value) if integer else value


def _subsection(data, key, allowed: dict, source: str) -> dict:
    section = data.get(key) or {}
    if not isinstance(section, dict):
        raise ScenarioError(f"{_where(source, data, key)}: {key} must be a mapping")
    for name in section:
        if name not in allowed:
            raise ScenarioError(f"{_where(source, section, name)}: unknown {key} key {name!r}; "
                                f"known: {', '.join(sorted(allowed))}")
    out = dict(allowed)
    out.update(section)
    return out


@reraise_as(ScenarioError, "scenario")
def scenario_from_dict(data: dict, source: str = "<dict>") -> Scenario:
    """Validate a parsed scenario mapping (see the module docstring)."""
    if not isinstance(data, dict):
        raise ScenarioError(f"{source}: a scenario must be a mapping")
    for key in data:
        if key not in TOP_KEYS:
            raise ScenarioError(f"{_where(source, data, key)}: unknown key {key!r}; "
                                f"known: {', '.join(sorted(TOP_KEYS))}")
    if "machine" not in data:
        raise ScenarioError(f"{source}: 'machine' is required (e.g. machine: kidani_hmc)")
    try:
        machine = load_machine(str(data["machine"]))
    except (MachineDescriptionError, OSError) as exc:
        raise ScenarioError(f"{_where(source, data, 'machine')}: {exc}") from exc
    scenario = Scenario(machine=machine, source=source,
                        description=str(data.get("description", "")))
    scenario.seed = _number(data, "seed", source, 0, 2**32 - 1, 0, integer=True)
    scenario.noise_seed = _number(data, "noise_seed", source, 0, 2**32 - 1, None, integer=True)
    scenario.duration_s = _number(data, "duration_s", source, 1e-3, 1e7, 60.0)
    scenario.sample_rate_hz = _number(data, "sample_rate_hz", source, 100.0, 20000.0, 1000.0)
    scenario.temperature_rate_hz = _number(data, "temperature_rate_hz", source, 1e-3, 100.0, 1.0)
    # The thermal state is computed over the whole run (temperatures at their rate, the
    # heat of motion on a 10 Hz grid): a run the simulator can hold, or a refusal now.
    steps = scenario.duration_s * max(scenario.temperature_rate_hz, THERMAL_MOTION_RATE_HZ)
    if steps > MAX_THERMAL_STEPS:
        raise ScenarioError(
            f"{_where(source, data, 'duration_s')}: duration_s {scenario.duration_s:g} s at "
            f"temperature_rate_hz {scenario.temperature_rate_hz:g} (and the "
            f"{THERMAL_MOTION_RATE_HZ:g} Hz motion-heat grid) is {steps:.3g} thermal steps; the "
            f"simulator holds at most {MAX_THERMAL_STEPS:.0e} for a run (e.g. "
            f"{MAX_THERMAL_STEPS / THERMAL_MOTION_RATE_HZ / 3600:.0f} h at up to "
            f"{THERMAL_MOTION_RATE_HZ:g} Hz): shorten the run or lower temperature_rate_hz")
    scenario.start_time_s = _number(data, "start_time_s", source, 0.0, 4e9, 1.7e9)
    scenario.noise = _subsection(data, "noise", NOISE_KEYS, source)
    for key in NOISE_KEYS:
        _number(scenario.noise, key, source, 0.0)
    scenario.spindle = _subsection(data, "spindle", SPINDLE_KEYS, source)
    scenario.ambient = _subsection(data, "ambient", AMBIENT_KEYS, source)

    if data.get("work_offset"):
        from ..core.kinematics.machine import checked_datum
        from ..core.errors import ParameterError

        try:
            scenario.work_offset = checked_datum(data["work_offset"], machine)
        except ParameterError as exc:
            raise ScenarioError(f"{_where(source, data, 'work_offset')}: {exc}") from exc

    program = data.get("program") or {"type": "back_and_forth", "axes": ["X"]}
    if not isinstance(program, dict) or "type" not in program:
        raise ScenarioError(f"{_where(source, data, 'program')}: program needs a 'type' "
                            f"({', '.join(PROGRAMS)})")
    if program["type"] not in PROGRAMS:
        raise ScenarioError(f"{_where(source, program, 'type')}: unknown program "
                            f"{program['type']!r}; known: {', '.join(PROGRAMS)}")
    try:
        PROGRAMS[program["type"]](machine, **{k: v for k, v in program.items() if k != "type"})
    except TypeError as exc:
        raise ScenarioError(f"{_where(source, program)}: bad program parameters: {exc}") from exc
    except ScenarioError as exc:
        named = [k for k in program if str(exc).startswith(str(k))]
        where = _where(source, program, named[0]) if named else _where(source, data, "program")
        raise ScenarioError(f"{where}: {exc}") from exc
    scenario.program = dict(program)

    effects = data.get("effects") or {}
    if not isinstance(effects, dict):
        raise ScenarioError(f"{_where(source, data, 'effects')}: effects must be a mapping")
    for name, value in effects.items():
        where = _where(source, effects, name)
        if name not in EFFECTS:
            raise ScenarioError(f"{where}: unknown effect {name!r}; known: "
                                f"{', '.join(EFFECTS)}")
        if value is False:
            scenario.enabled.discard(name)
            continue
        scenario.enabled.add(name)
        if value is True or value is None:
            continue
        if not isinstance(value, dict):
            raise ScenarioError(f"{where}: effect {name} takes true/false or a mapping of "
                                f"parameters, got {value!r}")
        params = dict(value)
        if params.pop("enabled", True) is False:
            scenario.enabled.discard(name)
        for key in params:
            if key not in EFFECTS[name].parameters:
                raise ScenarioError(
                    f"{_where(source, value, key)}: effect {name} has no parameter {key!r}; "
                    f"known: {', '.join(EFFECTS[name].parameters)}")
            default = EFFECTS[name].parameters[key][0]
            if isinstance(default, (int, float)) and not isinstance(default, bool):
                _number(value, key, source)
        scenario.effects[name] = params

    events = data.get("events") or []
    if not isinstance(events, list):
        raise ScenarioError(f"{_where(source, data, 'events')}: events must be a list")
    for event in events:
        if not isinstance(event, dict):
            raise ScenarioError(f"{_where(source, data, 'events')}: each event is a mapping "
                                "{time_s, enable|disable}")
        time_s = _number(event, "time_s", source, 0.0, None)
        if time_s is None:
            raise ScenarioError(f"{_where(source, event)}: event needs time_s")
        kinds = [k for k in ("enable", "disable") if k in event]
        extra = set(event) - {"time_s", "enable", "disable"}
        if len(kinds) != 1 or extra:
            raise ScenarioError(f"{_where(source, event)}: an event has time_s and exactly one "
                                "of enable / disable")
        name = event[kinds[0]]
        if name not in EFFECTS:
            raise ScenarioError(f"{_where(source, event, kinds[0])}: unknown effect {name!r}")
        if time_s > scenario.duration_s:
            raise ScenarioError(f"{_where(source, event, 'time_s')}: event at {time_s:g} s is "
                                f"after the end ({scenario.duration_s:g} s)")
        scenario.events.append((time_s, name, kinds[0] == "enable"))
    scenario.events.sort()
    _check_effect_axes(scenario)
    return scenario


def _check_effect_axes(scenario: Scenario) -> None:
    machine = scenario.machine
    for name in ("guideway_deterioration", "position_dependent_thermal", "ballscrew_pitch"):
        if scenario.ever_enabled(name):
            params = scenario.parameters(name)
            axis = params["axis"]
            if axis not in machine.axes or machine.axes[axis].is_rotary:
                raise ScenarioError(f"{scenario.source}: effect {name}: axis {axis!r} is not a "
                                    f"linear axis of {machine.name}")
    _check_rotary_effects(scenario)
    _check_table_tilt(scenario)
    if scenario.ever_enabled("guideway_deterioration"):
        params = scenario.parameters("guideway_deterioration")
        low, high = machine.axes[params["axis"]].stroke
        for key in ("start_m", "end_m"):
            if not low - 1e-9 <= float(params[key]) <= high + 1e-9:
                raise ScenarioError(f"{scenario.source}: guideway_deterioration {key} = "
                                    f"{params[key]} m is outside the {params['axis']} stroke "
                                    f"[{low}, {high}] m")


def _check_table_tilt(scenario: Scenario) -> None:
    if not scenario.ever_enabled("table_tilt"):
        return
    machine = scenario.machine
    params = scenario.parameters("table_tilt")
    errors = params["errors_rad"]
    bow = params.get("bow", 0.0)
    if isinstance(bow, bool) or not isinstance(bow, (int, float)) or not 0.0 <= bow <= 1.0:
        raise ScenarioError(f"{scenario.source}: table_tilt bow = {bow!r}: expected a number "
                            "in [0, 1] (the cubic share of the pitch)")
    work = [a for a in machine.workpiece_branch if not machine.axes[a].is_rotary]
    if not isinstance(errors, dict):
        raise ScenarioError(f"{scenario.source}: table_tilt errors_rad must be a mapping such "
                            "as {EAY: 1.2e-5}")
    _check_error_values(scenario, "table_tilt", errors, r"E[ABC]([XYZ])", work,
                        f"an angular error motion of a linear axis that carries the workpiece "
                        f"on {machine.name} ({', '.join(work) or 'none'}), e.g. "
                        f"EA{work[0] if work else 'X'}", 1e-3, "rad")


def _check_error_values(scenario: Scenario, effect: str, errors: dict, pattern: str,
                        axes: list[str], what: str, largest: float, unit: str) -> None:
    """Each ``errors`` key matches ``pattern`` with its axis among ``axes`` (else: it is
    not ``what``), each value a finite number below ``largest``."""
    for key, value in errors.items():
        match = re.fullmatch(pattern, str(key))
        if not match or match.group(1) not in axes:
            raise ScenarioError(f"{scenario.source}: {effect} {key!r} is not {what}")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                not math.isfinite(value) or abs(value) > largest:
            raise ScenarioError(f"{scenario.source}: {effect} {key} = {value!r}: expected a "
                                f"finite number below {largest:g} ({unit})")


def _check_rotary_effects(scenario: Scenario) -> None:
    machine = scenario.machine
    rotary = [a for a in machine.axis_order if machine.axes[a].is_rotary]
    for name in ("rotary_location", "rotary_runout"):
        if scenario.ever_enabled(name) and not rotary:
            raise ScenarioError(f"{scenario.source}: effect {name}: {machine.name} has no "
                                "rotary axis")
    if scenario.ever_enabled("rotary_location"):
        errors = scenario.parameters("rotary_location")["errors"]
        if not isinstance(errors, dict):
            raise ScenarioError(f"{scenario.source}: rotary_location errors must be a mapping "
                                "such as {EY0A: 2.0e-5, EB0A: 3.0e-5}")
        _check_error_values(scenario, "rotary_location error", errors, r"E[XYZABC]0([A-Z])",
                            rotary, f"a location error of a rotary axis of {machine.name} "
                            f"({', '.join(rotary)}), e.g. EY0{rotary[0]}", 0.01, "m or rad")
    if scenario.ever_enabled("rotary_runout"):
        axis = scenario.parameters("rotary_runout")["axis"]
        if axis not in rotary:
            raise ScenarioError(f"{scenario.source}: effect rotary_runout: axis {axis!r} is not "
                                f"a rotary axis of {machine.name} ({', '.join(rotary)})")


@reraise_as(ScenarioError, "scenario")
def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario YAML file."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot read scenario ({exc.strerror})") from exc
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"{path}: not a text file ({exc.reason})") from exc
    try:
        data = yaml.load(text, Loader=_LineLoader)  # noqa: S506 - SafeLoader subclass
    except yaml.YAMLError as exc:
        raise ScenarioError(f"{path}: not valid YAML: {exc}") from exc
    return scenario_from_dict(data, str(path))


@reraise_as(ScenarioError, "scenario")
def scenario_from_yaml(text: str, source: str = "<string>") -> Scenario:
    """Parse scenario YAML text (line numbers refer to ``text``)."""
    try:
        data = yaml.load(text, Loader=_LineLoader)  # noqa: S506 - SafeLoader subclass
    except yaml.YAMLError as exc:
        raise ScenarioError(f"{source}: not valid YAML: {exc}") from exc
    return scenario_from_dict(data, source)
