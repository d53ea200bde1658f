"""An independent generator of machine-tool thermal-error logs that change operating regime.

The generator writes a CSV log as an outside laboratory would record it, and a truth JSON
(``<name>.truth.json``) beside it that says everything a reader should recover: which column is
what and in which unit, where each regime (heating, dwell, cooling) starts and ends, which
sensors are dead, stuck or logged in another unit for one run, and which sensors lie on the
thermal path of the displacement. It carries its own conventions and imports nothing from
``mt_accuracy_ros``; numpy only.

Physics
-------
A lumped thermal model (Zhu 2008 ch. 3): two to four heat sources drive the structure, each
structural temperature and each structural elongation responding to a mix of the sources as a
first-order lag, the single-mode form of the decoupled modal equations.

- Sources, as steady temperature rises in K: the spindle bearings (friction heat growing with
  the spindle speed as ``(n / n_max) ** a``, a in 1.3 ... 2.0, an assumption of this
  generator), the spindle motor (a standing loss plus a share proportional to the speed), an
  optional feed drive (off the displacement's thermal path) and the ambient air with a daily
  cycle. Every structural point follows the ambient with weight 1, so a machine left alone
  settles to the air temperature.
- Sensors: ``T_j = T_air_mean + offset_j + lag(sum_i m_ji s_i, tau_j) + noise``; tau_j in
  5 min ... 3 h. On-path sensors are mostly driven by the spindle sources; off-path sensors
  by the ambient (and the feed drive) and do not follow the displacement.
- Displacement: the sum of 1-3 structural elongations ``alpha L_k * lag(sum_i c_ki s_i,
  tau_k)``, each with its own time constant, so the target leads (short tau_k) or lags
  (long tau_k) the on-path sensors. Scaled to a drawn amplitude of 5 ... 200 um, zeroed at
  the start of the log or of each run, plus 0.2 ... 1 um noise.

The lag is integrated exactly for an input held constant between grid points (the step
response of a first-order mode), on a grid that holds every sample time, every speed step
and a 10 min fill through unlogged gaps (nights, weekends, a warm-up before the log).

Conventions (drawn per log from the seed; each may be forced through ``make_log``'s
``choices``): time in s, min, h or date-times, 1 s ... 5 min sampling, jitter, a units row
or units in names, target in um / mm / nm with either sign, one sensor in K or degF with its
unit in its name, a run column or runs separated only by a clock jump, ``,`` or ``;``,
comment lines, faults (dead thermocouple at -180, stuck, zero, missing cells), a spindle
speed column, a coolant flag, a hotter run, a true unit slip for one run.

Rows in the truth are 0-based data rows (the header, units row and comment lines not
counted), ranges half-open ``[row_start, row_end)``; data row ``r`` is file line
``format.first_data_line + r`` (1-based). Times in the truth (``*_s``) are true elapsed
seconds since the first row.

Truth JSON
----------
``schema``, ``name``, ``file``, ``csv_path``, ``truth_path``, ``seed``, ``choices`` (every
drawn choice), ``format`` (separator, comment lines, header/units/first-data line, rows),
``columns`` (index, name, role in time/run/target/temperature/speed/other, unit, units-row
token, sensor), ``time``, ``target`` (unit, per_um, sign, zeroing, amplitude, noise,
elements), ``sources``, ``sensors`` (tau, weights, offset, on_path, target_vs_sensor,
corr_with_target, faults), ``runs``, ``regimes`` (kind, program, run, rows, times, speed
steps), ``split``, ``faults``, ``missing_cells``, ``unit_slips``, ``hot_runs``, ``noise``,
``ambient``, ``prehistory``, ``regime_kinds``, ``row_convention``.

Usage
-----
``python -m studies.regime_logs --seed 3 --out /tmp/x [--choice key=value ...]``
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import datetime
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

SCHEMA = "regime_logs/1"
SCENARIOS = ("hdc", "train_split", "programs", "multi_run")
PROGRAMS = ("constant", "steps_up", "steps_down", "up_down", "random_steps", "intermittent")
SAMPLING_S = (1, 2, 5, 10, 15, 30, 60, 120, 300)
FAULT_KINDS = ("dead", "stuck", "zero", "missing")
OPTIONAL_SOURCES = ("spindle_motor", "feed_drive")
DATETIME_FORMAT = "%Y-%m-%d %H:%M:%S"
MIN_MAX_ROWS = 500
GAP_FILL_S = 600.0
HOUR = 3600.0
DAY = 86400.0
DEAD_READING_C = -180.0

TIME_NAMES = {
    "s": ("t_s", "time_s", "Time [s]", "t (s)", "elapsed_s"),
    "min": ("time_min", "t [min]", "Time (min)", "t_min"),
    "h": ("Time [h]", "t_h", "time_h", "Time (h)"),
    "datetime": ("timestamp", "Date Time", "datetime", "time"),
}
TIME_NAMES_BARE = ("time", "t", "Time", "elapsed")
TIME_TOKENS = {"s": "s", "min": "min", "h": "h", "datetime": "yyyy-mm-dd hh:mm:ss"}
TIME_TO_S = {"s": 1.0, "min": 60.0, "h": HOUR}
TIME_DECIMALS = {"s": 2, "min": 5, "h": 7}
TARGET_BASES = ("dz", "Z-displacement", "disp", "delta_Z", "ch1")
TARGET_SPELLINGS = {"um": ("um", "µm"), "mm": ("mm",), "nm": ("nm",)}
TARGET_SUFFIXES = ("_{u}", " [{u}]", " ({u})")
TARGET_PER_UM = {"um": 1.0, "mm": 1e-3, "nm": 1e3}
TARGET_DECIMALS = {"um": 3, "mm": 6, "nm": 1}
# (name without unit, name with the degC unit); a units row uses the first
TEMP_STYLES = (
    ("T{i}", "T{i}_C"),
    ("t{i}", "t{i}_C"),
    ("temp{i:02d}", "temp{i:02d} [°C]"),
    ("TC{i}", "TC{i} [degC]"),
    ("T{i}", "T{i} (C)"),
    ("T{i}", "T{i}"),
)
TEMP_TOKENS = ("°C", "degC", "C")
ODD_UNIT_NAMES = {"K": ("{b}_K", "{b} [K]"), "degF": ("{b}_degF", "{b} [°F]")}
ODD_UNIT_TOKENS = {"K": "K", "degF": "°F"}
# degC -> unit: value = scale * T_C + offset
UNIT_MAPS = {"K": (1.0, 273.15), "degF": (1.8, 32.0)}
SPEED_NAMES = ("spindle_rpm", "S [rpm]", "n_spindle [1/min]", "speed_rpm")
SPEED_NAMES_BARE = ("spindle", "S", "n_spindle", "speed")
RUN_NAMES = ("run", "day", "experiment")
COMMENTS = (
    "# thermal drift test, machine VMC-{m}, probe: capacitive on spindle nose",
    "# exported by DAQ logger v{m}.2",
    "# operator: lab B, room not air-conditioned",
    "# values as recorded, no filtering",
)
SOURCE_NOTES = {
    "spindle_bearings": "friction heat, steady rise gain_K * (n / n_max) ** exponent",
    "spindle_motor": "motor loss, steady rise gain_K * (0.3 + 0.7 n / n_max) while running",
    "feed_drive": "feed-axis drive, steady rise gain_K * duty, own on/off cycles in the runs",
    "ambient": "air, mean_C + amplitude_K * cos(2 pi (clock_h - peak_h) / 24)",
}
REGIME_NOTES = {
    "heating": "spindle program running (speed steps; short 0 rpm pauses in 'intermittent')",
    "dwell": "spindle held at one speed after a program: heat input constant, near steady",
    "cooling": "spindle stopped (0 rpm), the machine cools toward the air",
}


@dataclass(frozen=True)
class Choices:
    """Every convention and scenario drawn for one log (all may be forced by name).

    Attributes
    ----------
    scenario : str
        ``hdc`` (heating, dwell, cooling in one run), ``train_split`` (the first
        ``train_fraction`` of the rows hold one regime, the rest another), ``programs``
        (several spindle programs in one run) or ``multi_run`` (several days).
    n_runs : int
        Runs (days) in the log; 1 unless ``multi_run``.
    n_sensors : int
        Temperature sensors, 3 ... 20.
    sources : tuple of str
        Heat sources; always ``spindle_bearings`` and ``ambient``.
    sampling_s : int
        Sampling period drawn, s; the log uses the smallest of ``SAMPLING_S`` at or above it
        that keeps the rows within ``max_rows``.
    units_row : bool
        Units on a second header row instead of in the names.
    sign : int
        +1: the written target is the elongation of the tool-to-work loop; -1: its negative.
    target_zero : str
        ``log_start`` or ``run_start``: where the displacement probe was zeroed.
    target_lead : str
        ``leads`` or ``lags``: the elongations' time constants below or above the on-path
        sensors'.
    odd_unit : str or None
        ``K`` or ``degF``: one sensor (``odd_sensor``, 0-based) logged in that unit for the
        whole log, the unit in its name.
    run_marking : str
        ``none`` (one run), ``column`` (a run column) or ``clock_jump`` (no run column).
    faults : tuple of str
        Subset of ``dead``, ``stuck``, ``zero``, ``missing``.
    unit_slip : str or None
        ``K`` or ``degF``: one run where one degC sensor was logged in that unit.
    train_fraction : float
        Share of the rows in the training part (``train_split`` only).

    The other fields are the drawn spellings (``*_name``, ``temp_style``, ``temp_token``),
    number formats, the machine (``spindle_max_rpm``, ``bearing_exponent``), the air
    (``ambient_*``), the target's amplitude and the noise levels (SI units in the names).
    """

    scenario: str
    n_runs: int
    n_sensors: int
    sources: tuple[str, ...]
    n_elements: int
    spindle_max_rpm: int
    bearing_exponent: float
    sampling_s: int
    jitter: bool
    max_rows: int
    time_unit: str
    time_name: str
    time_resets_per_run: bool
    start_datetime: str
    units_row: bool
    target_unit: str
    target_name: str
    sign: int
    target_zero: str
    target_lead: str
    target_first: bool
    amplitude_um: float
    noise_temp_K: float
    noise_target_um: float
    temp_style: int
    temp_token: str
    temp_decimals: int
    odd_unit: str | None
    odd_sensor: int | None
    run_marking: str
    run_name: str
    run_first_label: int
    gap_kind: str
    separator: str
    comment_lines: int
    faults: tuple[str, ...]
    speed_column: bool
    speed_name: str
    other_column: bool
    hot_run: bool
    unit_slip: str | None
    train_kind: str
    rest_kind: str
    train_fraction: float
    ambient_mean_C: float
    ambient_amplitude_K: float
    ambient_peak_h: float


@dataclass
class ColumnTruth:
    """One CSV column: position, name as written, role and canonical unit."""

    index: int
    name: str
    role: str
    unit: str | None
    unit_token: str | None
    sensor: int | None = None


@dataclass
class FormatTruth:
    """How the file is laid out (line numbers are 1-based file lines)."""

    separator: str
    decimal: str
    encoding: str
    comment_prefix: str
    comment_lines: int
    header_line: int
    units_line: int | None
    first_data_line: int
    n_rows: int
    missing_markers: list[str]


@dataclass
class TimeTruth:
    """The time column: unit, sampling and how runs show in it.

    ``jitter_s`` is the half-width of the uniform jitter on each sample time (0: none);
    ``resolution_s`` the rounding of the true sample times (1 s for date-times).
    """

    column: str
    unit: str
    datetime_format: str | None
    sampling_s: float
    jitter_s: float
    resets_per_run: bool
    start_datetime: str
    resolution_s: float


@dataclass
class ElementTruth:
    """One structural elongation: ``alpha_L_um_per_K * lag(sum_i weights[i] s_i, tau_s)``."""

    name: str
    tau_s: float
    alpha_L_um_per_K: float
    weights: dict[str, float]


@dataclass
class TargetTruth:
    """The displacement column and how its values relate to the elongation."""

    column: str
    unit: str
    per_um: float
    sign: int
    sign_convention: str
    zeroed: str
    amplitude_um: float
    noise_um: float
    tau_eff_s: float
    elements: list[ElementTruth]


@dataclass
class SourceTruth:
    """One heat source: its steady temperature rise at full load, K."""

    name: str
    gain_K: float
    on_path: bool
    note: str
    schedule: list[tuple[float, float]] | None = None  # feed drive: (t_start_s, duty)


@dataclass
class SensorTruth:
    """One temperature sensor: its lag, mix of sources and relation to the target."""

    column: str
    sensor: int
    unit_written: str
    tau_s: float
    weights: dict[str, float]
    offset_K: float
    on_path: bool
    target_vs_sensor: str
    corr_with_target: float
    faults: list[str]


@dataclass
class RunTruth:
    """One run (day): rows, true times and how it is marked."""

    run: int
    label: int | None
    row_start: int
    row_end: int
    t_start_s: float
    t_end_s: float
    clock_jump_before_s: float | None
    start_datetime: str


@dataclass
class RegimeTruth:
    """One regime: kind, spindle program and where it sits in rows and time."""

    index: int
    kind: str
    program: str
    run: int
    row_start: int
    row_end: int
    t_start_s: float
    t_end_s: float
    time_first_written: str
    time_last_written: str
    speeds_rpm: list[float]
    steps: list[tuple[float, float]]  # (t_start_s, rpm) of each constant-speed step


@dataclass
class UnloggedBlock:
    """Spindle activity before the first row (a warm-up the log did not record)."""

    kind: str
    program: str
    t_start_s: float
    t_end_s: float
    steps: list[tuple[float, float]]  # (t_start_s, rpm)


@dataclass
class SplitTruth:
    """A training part holding one regime and the rest holding others."""

    train_end_row: int
    train_fraction: float
    train_regimes: list[int]
    test_regimes: list[int]


@dataclass
class FaultTruth:
    """A sensor fault over rows ``[row_start, row_end)``; ``value`` the reading, degC."""

    kind: str
    column: str
    row_start: int
    row_end: int
    value: float | None


@dataclass
class MissingCell:
    """A cell left empty or written as a NaN marker."""

    row: int
    column: str
    written: str


@dataclass
class UnitSlipTruth:
    """One run where a degC sensor was logged in another unit: ``written = scale T + offset``."""

    run: int
    column: str
    unit_written: str
    scale: float
    offset: float
    row_start: int
    row_end: int


@dataclass
class HotRunTruth:
    """A run where the spindle ran a larger share of the run: real heat, not a unit slip."""

    run: int
    source: str
    heating_share: float
    typical_heating_share: float
    sensor: str
    sensor_mean_shift_K: dict[str, float]
    target_mean_shift_um: float


@dataclass
class LogTruth:
    """Everything written into ``<name>.truth.json`` (see the module docstring)."""

    schema: str
    name: str
    file: str
    csv_path: str
    truth_path: str
    seed: int
    choices: Choices
    format: FormatTruth
    columns: list[ColumnTruth]
    time: TimeTruth
    target: TargetTruth
    sources: list[SourceTruth]
    sensors: list[SensorTruth]
    runs: list[RunTruth]
    regimes: list[RegimeTruth]
    split: SplitTruth | None
    faults: list[FaultTruth]
    missing_cells: list[MissingCell]
    unit_slips: list[UnitSlipTruth]
    hot_runs: list[HotRunTruth]
    noise: dict[str, float]
    ambient: dict[str, float]
    prehistory: list[UnloggedBlock]
    regime_kinds: dict[str, str] = field(default_factory=lambda: dict(REGIME_NOTES))
    row_convention: str = "0-based data rows, half-open [row_start, row_end)"

    def to_dict(self) -> dict:
        """Return the truth as plain JSON types."""
        return dataclasses.asdict(self)


# ---------------------------------------------------------------- choices


class _Picker:
    """Draw each choice in a fixed order; a forced value replaces the draw, not the stream."""

    def __init__(self, rng: np.random.Generator, forced: dict):
        self.rng = rng
        self.forced = forced
        self.values: dict = {}

    def __call__(self, name: str, draw):
        drawn = draw()
        value = self.forced[name] if name in self.forced else drawn
        self.values[name] = value
        return value


def _choose(rng: np.random.Generator, options):
    return options[int(rng.integers(len(options)))]


def _draw_scenario(p: _Picker) -> None:
    rng = p.rng
    scenario = p("scenario", lambda: _choose(rng, SCENARIOS))
    multi = scenario == "multi_run"
    p("n_runs", lambda: int(rng.integers(2, 5)) if multi else 1)
    p("hot_run", lambda: bool(multi and rng.random() < 0.5))
    p("unit_slip", lambda: _choose(rng, ("K", "degF")) if multi and rng.random() < 0.5 else None)
    p("train_kind", lambda: "heating" if rng.random() < 0.7 else "cooling")
    rest = ("cooling", "other_program", "dwell_cooling")
    p("rest_kind", lambda: _choose(rng, rest) if p.values["train_kind"] == "heating"
      else "heating")
    p("train_fraction", lambda: round(float(rng.uniform(0.5, 0.7)), 3))
    optional = tuple(s for s in OPTIONAL_SOURCES if rng.random() < 0.5)
    p("sources", lambda: ("spindle_bearings",) + optional + ("ambient",))
    p("n_elements", lambda: int(rng.integers(1, 4)))
    p("spindle_max_rpm", lambda: int(rng.integers(6, 25)) * 1000)
    p("bearing_exponent", lambda: round(float(rng.uniform(1.3, 2.0)), 3))
    p("ambient_mean_C", lambda: round(float(rng.uniform(18.0, 24.0)), 2))
    p("ambient_amplitude_K", lambda: round(float(rng.uniform(0.3, 2.5)), 2))
    p("ambient_peak_h", lambda: round(float(rng.uniform(14.0, 17.0)), 2))
    p("gap_kind", lambda: "overnight" if rng.random() < 0.5 else "days")


def _draw_format(p: _Picker) -> None:
    rng = p.rng
    multi = p.values["n_runs"] > 1
    p("sampling_s", lambda: _choose(rng, SAMPLING_S))
    p("jitter", lambda: bool(rng.random() < 0.4))
    p("max_rows", lambda: 20000)
    unit = p("time_unit", lambda: _choose(rng, ("s", "min", "h", "datetime")))
    p("units_row", lambda: bool(rng.random() < 0.3))
    bare = p.values["units_row"] and unit != "datetime"
    p("time_name", lambda: _choose(rng, TIME_NAMES_BARE if bare else TIME_NAMES[unit]))
    marking = p("run_marking", lambda: ("column" if rng.random() < 0.6 else "clock_jump")
                if multi else "none")
    p("time_resets_per_run", lambda: bool(marking == "column" and unit != "datetime"
                                          and rng.random() < 0.5))
    p("run_name", lambda: _choose(rng, RUN_NAMES))
    p("run_first_label", lambda: int(rng.integers(0, 2)))
    start = datetime.datetime(2023, 1, 2) + datetime.timedelta(
        days=int(rng.integers(0, 900)), minutes=int(rng.integers(6 * 60, 9 * 60)))
    p("start_datetime", lambda: start.strftime(DATETIME_FORMAT))
    tu = p("target_unit", lambda: _choose(rng, ("um", "um", "mm", "nm")))
    p("target_name", lambda: _target_name(rng, tu, p.values["units_row"]))
    p("sign", lambda: int(_choose(rng, (1, -1))))
    p("target_zero", lambda: "run_start" if multi and rng.random() < 0.5 else "log_start")
    p("target_lead", lambda: _choose(rng, ("leads", "lags")))
    p("target_first", lambda: bool(rng.random() < 0.6))
    p("amplitude_um", lambda: round(float(math.exp(rng.uniform(math.log(5), math.log(200)))), 2))
    p("noise_temp_K", lambda: round(float(rng.uniform(0.02, 0.1)), 3))
    p("noise_target_um", lambda: round(float(rng.uniform(0.2, 1.0)), 3))
    p("temp_style", lambda: int(rng.integers(len(TEMP_STYLES))))
    p("temp_token", lambda: _choose(rng, TEMP_TOKENS))
    p("temp_decimals", lambda: int(_choose(rng, (2, 3))))
    p("separator", lambda: _choose(rng, (",", ";")))
    p("comment_lines", lambda: int(rng.integers(1, 5)) if rng.random() < 0.5 else 0)
    p("speed_column", lambda: bool(rng.random() < 0.5))
    p("speed_name", lambda: _choose(rng, SPEED_NAMES_BARE if p.values["units_row"]
                                    else SPEED_NAMES))
    p("other_column", lambda: bool(rng.random() < 0.3))


def _target_name(rng: np.random.Generator, unit: str, units_row: bool) -> str:
    base = _choose(rng, TARGET_BASES)
    suffix = _choose(rng, TARGET_SUFFIXES).format(u=_choose(rng, TARGET_SPELLINGS[unit]))
    return base if units_row else base + suffix


def _draw_sensors_and_faults(p: _Picker) -> None:
    rng = p.rng
    faults = tuple(k for k in FAULT_KINDS if rng.random() < 0.3)
    p("faults", lambda: faults)
    p("odd_unit", lambda: _choose(rng, ("K", "degF")) if rng.random() < 0.3 else None)
    need = _sensors_needed(p.values)
    p("n_sensors", lambda: int(rng.integers(max(3, need), 21)))
    p("odd_sensor", lambda: int(rng.integers(p.values["n_sensors"]))
      if p.values["odd_unit"] else None)


def _sensors_needed(values: dict) -> int:
    """Sensors needed so that every special role gets its own degC sensor, plus one clean."""
    special = [k for k in values["faults"] if k != "missing"]
    return len(special) + bool(values["odd_unit"]) + bool(values["unit_slip"]) + 2


def draw_choices(seed: int, **forced) -> Choices:
    """Draw every choice of a log from ``seed``; names in ``forced`` replace their draw.

    Parameters
    ----------
    seed : int
        The log's seed.
    **forced
        Values for fields of :class:`Choices`.

    Returns
    -------
    Choices

    Raises
    ------
    ValueError
        An unknown name, or forced values that contradict each other.
    """
    known = {f.name for f in dataclasses.fields(Choices)}
    unknown = sorted(set(forced) - known)
    if unknown:
        raise ValueError(f"unknown choices {unknown}; known: {sorted(known)}")
    for name in ("sources", "faults"):
        if name in forced:
            forced[name] = tuple(forced[name])
    p = _Picker(np.random.default_rng([seed, 0]), forced)
    _draw_scenario(p)
    _draw_format(p)
    _draw_sensors_and_faults(p)
    choices = Choices(**p.values)
    _validate(choices)
    return choices


def _validate(c: Choices) -> None:
    checks = [
        (c.scenario in SCENARIOS, f"scenario must be one of {SCENARIOS}"),
        ((c.n_runs > 1) == (c.scenario == "multi_run"), "n_runs > 1 exactly for multi_run"),
        (c.n_runs <= 6, "at most 6 runs"),
        (not (c.hot_run or c.unit_slip) or c.n_runs > 1, "hot_run/unit_slip need several runs"),
        ((c.run_marking == "none") == (c.n_runs == 1), "run_marking 'none' exactly for 1 run"),
        (c.run_marking in ("none", "column", "clock_jump"), "unknown run_marking"),
        (not c.time_resets_per_run or c.run_marking == "column",
         "a time that resets per run needs a run column"),
        (not c.time_resets_per_run or c.time_unit != "datetime", "date-times do not reset"),
        (c.time_unit in TIME_NAMES, f"time_unit must be one of {tuple(TIME_NAMES)}"),
        (c.target_unit in TARGET_PER_UM, "target_unit must be um, mm or nm"),
        (c.sign in (1, -1), "sign must be +1 or -1"),
        (c.sampling_s in SAMPLING_S, f"sampling_s must be one of {SAMPLING_S}"),
        (c.max_rows >= MIN_MAX_ROWS, f"max_rows must be >= {MIN_MAX_ROWS}"),
        (3 <= c.n_sensors <= 20, "n_sensors must be 3 ... 20"),
        (c.n_sensors >= _sensors_needed(dataclasses.asdict(c)), "too few sensors for faults"),
        (set(c.faults) <= set(FAULT_KINDS), f"faults must be within {FAULT_KINDS}"),
        ({"spindle_bearings", "ambient"} <= set(c.sources), "bearings and ambient required"),
        (set(c.sources) <= {"spindle_bearings", "ambient", *OPTIONAL_SOURCES}, "bad source"),
        (c.odd_sensor is None or 0 <= c.odd_sensor < c.n_sensors, "odd_sensor out of range"),
        ((c.odd_unit is None) == (c.odd_sensor is None), "odd_unit and odd_sensor go together"),
        (c.separator in (",", ";"), "separator must be ',' or ';'"),
        (0.5 <= c.train_fraction <= 0.7, "train_fraction must be 0.5 ... 0.7"),
    ]
    failed = [message for ok, message in checks if not ok]
    if failed:
        raise ValueError("inconsistent choices: " + "; ".join(failed))


# ---------------------------------------------------------------- regime plan


@dataclass
class _Block:
    kind: str
    program: str
    steps: list[tuple[float, float]]  # (duration s, rpm)

    @property
    def duration(self) -> float:
        return sum(d for d, _ in self.steps)


@dataclass
class _Plan:
    pre: list[_Block]
    runs: list[list[_Block]]
    hot_run: int | None = None
    heating_shares: list[float] = field(default_factory=list)


def _program_steps(program: str, duration: float, max_rpm: int,
                   rng: np.random.Generator) -> list[tuple[float, float]]:
    """Speed steps of a spindle program lasting ``duration`` s; rpm rounded to 100."""
    if program == "constant":
        levels = [rng.uniform(0.4, 0.9)]
    elif program in ("steps_up", "steps_down"):
        levels = list(np.linspace(0.25, 1.0, int(rng.integers(3, 6))))
        levels = levels if program == "steps_up" else levels[::-1]
    elif program == "up_down":
        up = list(np.linspace(0.3, 1.0, int(rng.integers(2, 4))))
        levels = up + up[-2::-1]
    elif program == "random_steps":
        levels = list(rng.uniform(0.2, 1.0, int(rng.integers(3, 7))))
    elif program == "intermittent":
        on = rng.uniform(0.5, 1.0)
        cycles = int(rng.integers(3, 6))
        pause = min(600.0, 0.2 * duration / cycles)
        run = (duration - pause * (cycles - 1)) / cycles
        steps = []
        for k in range(cycles):
            steps.append((run, round(on * max_rpm, -2)))
            if k < cycles - 1:
                steps.append((pause, 0.0))
        return steps
    else:
        raise ValueError(f"unknown program {program!r}")
    return [(duration / len(levels), round(float(v) * max_rpm, -2)) for v in levels]


def _heating(program: str, duration: float, c: Choices, rng) -> _Block:
    return _Block("heating", program, _program_steps(program, duration, c.spindle_max_rpm, rng))


def _dwell(rpm: float, duration: float) -> _Block:
    return _Block("dwell", "hold", [(duration, rpm)])


def _cooling(duration: float) -> _Block:
    return _Block("cooling", "stop", [(duration, 0.0)])


def _last_rpm(block: _Block) -> float:
    return next(r for _, r in reversed(block.steps) if r > 0)


def _hours(rng, low: float, high: float) -> float:
    return float(rng.uniform(low, high)) * HOUR


def _plan_hdc(c: Choices, rng) -> _Plan:
    blocks = []
    for _ in range(int(rng.integers(1, 3))):
        heat = _heating(_choose(rng, PROGRAMS), _hours(rng, 1.5, 4.0), c, rng)
        blocks += [heat, _dwell(_last_rpm(heat), _hours(rng, 0.5, 1.5)),
                   _cooling(_hours(rng, 1.5, 4.0))]
    return _Plan(pre=[], runs=[blocks])


def _plan_programs(c: Choices, rng) -> _Plan:
    names = rng.permutation(PROGRAMS)[: int(rng.integers(2, 4))]
    blocks = []
    for name in names:
        blocks.append(_heating(str(name), _hours(rng, 1.0, 3.0), c, rng))
        if rng.random() < 0.5:
            blocks.append(_cooling(_hours(rng, 1.0, 2.5)))
    if blocks[-1].kind != "cooling":
        blocks.append(_cooling(_hours(rng, 1.5, 3.0)))
    return _Plan(pre=[], runs=[blocks])


def _plan_train_split(c: Choices, rng) -> _Plan:
    """The first ``train_fraction`` of the log is one regime; the rest is another."""
    train_s = _hours(rng, 3.0, 6.0)
    rest_s = train_s * (1.0 - c.train_fraction) / c.train_fraction
    first, other = rng.permutation(PROGRAMS)[:2]
    pre: list[_Block] = []
    if c.train_kind == "cooling":
        pre = [_heating("constant", _hours(rng, 3.0, 5.0), c, rng)]
        train = _cooling(train_s)
    else:
        train = _heating(str(first), train_s, c, rng)
    if c.rest_kind == "cooling":
        rest = [_cooling(rest_s)]
    elif c.rest_kind == "dwell_cooling":
        rest = [_dwell(_last_rpm(train), 0.4 * rest_s), _cooling(0.6 * rest_s)]
    elif c.rest_kind == "other_program":
        rest = [_heating(str(other), 0.6 * rest_s, c, rng), _cooling(0.4 * rest_s)]
    else:
        rest = [_heating(str(other), rest_s, c, rng)]
    return _Plan(pre=pre, runs=[[train] + rest])


def _plan_multi_run(c: Choices, rng) -> _Plan:
    typical = float(rng.uniform(0.25, 0.4))
    hot = int(rng.integers(c.n_runs)) if c.hot_run else None
    runs, shares = [], []
    for r in range(c.n_runs):
        length = _hours(rng, 5.0, 10.0)
        share = float(rng.uniform(0.75, 0.9)) if r == hot else typical
        program = "constant" if r == hot else _choose(rng, PROGRAMS)
        heat = _heating(program, share * length, c, rng)
        if r == hot:  # the hot run holds the spindle near its top speed
            heat.steps = [(share * length, round(float(rng.uniform(0.85, 1.0))
                                                 * c.spindle_max_rpm, -2))]
        dwell_s = 0.0 if r == hot or rng.random() < 0.3 else 0.12 * length
        blocks = [heat] + ([_dwell(_last_rpm(heat), dwell_s)] if dwell_s else [])
        blocks.append(_cooling(length - share * length - dwell_s))
        runs.append(blocks)
        shares.append(share)
    return _Plan(pre=[], runs=runs, hot_run=hot, heating_shares=shares)


PLANNERS = {"hdc": _plan_hdc, "programs": _plan_programs, "train_split": _plan_train_split,
            "multi_run": _plan_multi_run}


@dataclass
class _Layout:
    """The plan on the true time axis (s since the first row)."""

    step_t0: np.ndarray  # (n_steps,) start of each constant-speed step, contiguous
    step_rpm: np.ndarray
    feed_t0: np.ndarray  # (n_feed,) start of each constant feed-drive duty, contiguous
    feed_duty: np.ndarray
    t_sim_start: float
    run_spans: list[tuple[float, float]]
    regime_spans: list[tuple[_Block, int, float, float]]
    clock0_h: float


def _feed_schedule(run_spans, t_sim_start: float, rng) -> tuple[np.ndarray, np.ndarray]:
    """Feed-drive duty: its own on/off cycles within the runs, unrelated to the spindle."""
    t0s, duties = [t_sim_start], [0.0]
    for begin, end in run_spans:
        t, on = begin, bool(rng.random() < 0.5)
        while t < end:
            t0s.append(t)
            duties.append(float(rng.uniform(0.3, 1.0)) if on else 0.0)
            t += float(rng.uniform(0.25, 1.5)) * HOUR
            on = not on
        t0s.append(end)
        duties.append(0.0)
    return np.array(t0s), np.array(duties)


def _layout(plan: _Plan, c: Choices, rng) -> _Layout:
    """Place runs on days (mornings, next day or after a weekend) and steps on the time axis."""
    start = datetime.datetime.strptime(c.start_datetime, DATETIME_FORMAT)
    clock0_h = start.hour + start.minute / 60.0 + start.second / HOUR
    pre_s = sum(b.duration for b in plan.pre)
    t0s, rpms = [], []
    t = -pre_s
    for block in plan.pre:
        for d, rpm in block.steps:
            t0s.append(t)
            rpms.append(rpm)
            t += d
    run_spans, regime_spans, day = [], [], 0
    for r, blocks in enumerate(plan.runs):
        if r > 0:
            day += 1 if c.gap_kind == "overnight" or r > 1 else int(rng.integers(2, 5))
            t0s.append(run_spans[-1][1])  # idle through the gap
            rpms.append(0.0)
            t = day * DAY + (float(rng.uniform(6.0, 9.0)) - clock0_h) * HOUR
        begin = t
        for block in blocks:
            regime_spans.append((block, r, t, t + block.duration))
            for d, rpm in block.steps:
                t0s.append(t)
                rpms.append(rpm)
                t += d
        run_spans.append((begin, t))
    t0s.append(t)
    rpms.append(0.0)
    feed_t0, feed_duty = _feed_schedule(run_spans, -pre_s, rng)
    return _Layout(np.array(t0s), np.array(rpms), feed_t0, feed_duty, -pre_s, run_spans,
                   regime_spans, clock0_h)


# ---------------------------------------------------------------- physics


def first_order_lag(t: np.ndarray, u: np.ndarray, tau: np.ndarray,
                    y0: np.ndarray | None = None) -> np.ndarray:
    """Integrate ``dy/dt = (u - y) / tau`` exactly for ``u`` held on each interval.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Increasing times, s.
    u : ndarray, shape (n, m)
        Inputs; row ``k`` holds on ``[t[k], t[k+1])`` (the last row is not used).
    tau : ndarray, shape (m,)
        Time constants, s (> 0).
    y0 : ndarray, shape (m,), optional
        Initial state; by default ``u[0]`` (steady at the start).

    Returns
    -------
    ndarray, shape (n, m)
        The state at each time.
    """
    decay = np.exp(-np.diff(t)[:, None] / np.asarray(tau, float)[None, :])  # Zhu 2008 eq. 3.10
    y = np.empty_like(u, dtype=float)
    y[0] = u[0] if y0 is None else y0
    for k in range(len(t) - 1):
        y[k + 1] = u[k] + (y[k] - u[k]) * decay[k]  # Zhu 2008 eq. 3.9, exact over one hold
    return y


def _sample_times(lay: _Layout, c: Choices, rng) -> tuple[np.ndarray, np.ndarray, float]:
    """Sample times (s) and each row's run; the sampling period actually used."""
    length = sum(t1 - t0 for t0, t1 in lay.run_spans)
    usable = [s for s in SAMPLING_S if s >= c.sampling_s and length / s <= c.max_rows]
    if not usable:
        raise ValueError(f"max_rows={c.max_rows} too small for {length / HOUR:.1f} h of log")
    dt = float(usable[0])
    times, runs = [], []
    for r, (t0, t1) in enumerate(lay.run_spans):
        k = np.arange(int(np.floor((t1 - t0) / dt)))
        tr = t0 + k * dt
        if c.jitter and dt >= 2:
            jit = rng.uniform(-0.25, 0.25, len(k)) * dt
            jit[0] = 0.0
            tr = tr + jit
        times.append(tr)
        runs.append(np.full(len(k), r))
    t = np.concatenate(times)
    resolution = 1.0 if c.time_unit == "datetime" else 0.01
    t = np.floor(t / resolution + 0.5) * resolution
    return t, np.concatenate(runs), dt


@dataclass
class _Physics:
    weights_s: np.ndarray  # (n_sensors, n_src)
    tau_s: np.ndarray
    offset_K: np.ndarray
    on_path: np.ndarray
    weights_e: np.ndarray  # (n_el, n_src)
    tau_e: np.ndarray
    alpha_L: np.ndarray  # um/K, scaled to the amplitude after simulation
    gains: dict[str, float]


def _draw_physics(c: Choices, rng) -> _Physics:
    """Sources, sensors and elongations; the target leads or lags the on-path sensors."""
    src = list(c.sources)
    gains = {"spindle_bearings": rng.uniform(6, 20), "spindle_motor": rng.uniform(3, 10),
             "feed_drive": rng.uniform(2, 8), "ambient": 1.0}
    gains = {k: round(float(gains[k]), 3) for k in src}
    n = c.n_sensors
    n_off = max(1, int(round(n * rng.uniform(0.15, 0.35))))
    on_path = np.ones(n, bool)
    on_path[rng.permutation(n)[:n_off]] = False
    ranges_on = {"spindle_bearings": (0.2, 1.0), "spindle_motor": (0.0, 0.6),
                 "feed_drive": (0.0, 0.1), "ambient": (1.0, 1.0)}
    ranges_off = {"spindle_bearings": (0.0, 0.0), "spindle_motor": (0.0, 0.0),
                  "feed_drive": (0.3, 1.0), "ambient": (1.0, 1.0)}
    ws = np.array([[rng.uniform(*(ranges_on if on else ranges_off)[s]) for s in src]
                   for on in on_path])
    tau_s = np.exp(rng.uniform(np.log(300.0), np.log(3 * HOUR), n))
    base = float(np.median(tau_s[on_path]))
    low, high = (0.25, 0.6) if c.target_lead == "leads" else (1.6, 3.0)
    tau_e = np.clip(base * rng.uniform(low, high, c.n_elements), 300.0, 4 * HOUR)
    ranges_e = {"spindle_bearings": (0.5, 1.0), "spindle_motor": (0.0, 0.6),
                "feed_drive": (0.0, 0.0), "ambient": (0.0, 0.4)}
    we = np.array([[rng.uniform(*ranges_e[s]) for s in src] for _ in range(c.n_elements)])
    return _Physics(np.round(ws, 4), np.round(tau_s, 1), np.round(rng.normal(0, 0.3, n), 3),
                    on_path, np.round(we, 4), np.round(tau_e, 1),
                    rng.uniform(0.5, 1.5, c.n_elements), gains)


def _source_inputs(grid: np.ndarray, lay: _Layout, c: Choices, ph: _Physics) -> np.ndarray:
    """Source temperature rises, K, shape (n_grid, n_src), held on ``[grid[k], grid[k+1])``."""
    idx = np.searchsorted(lay.step_t0, grid, side="right") - 1
    rpm = lay.step_rpm[np.clip(idx, 0, None)]
    feed = lay.feed_duty[np.clip(np.searchsorted(lay.feed_t0, grid, side="right") - 1, 0, None)]
    x = rpm / c.spindle_max_rpm
    mid = np.append(0.5 * (grid[1:] + grid[:-1]), grid[-1])  # the air is held at mid-interval
    clock_h = lay.clock0_h + mid / HOUR
    cols = {
        "spindle_bearings": ph.gains.get("spindle_bearings", 0) * x ** c.bearing_exponent,
        "spindle_motor": ph.gains.get("spindle_motor", 0) * (0.3 + 0.7 * x) * (x > 0),
        "feed_drive": ph.gains.get("feed_drive", 0) * feed,
        "ambient": c.ambient_amplitude_K * np.cos(2 * np.pi * (clock_h - c.ambient_peak_h) / 24),
    }
    return np.column_stack([cols[s] for s in c.sources])


@dataclass
class _Clean:
    temps_C: np.ndarray  # (N, n_sensors) noise-free
    elong_um: np.ndarray  # (N,) noise-free elongation, not zeroed
    rpm: np.ndarray  # (N,)


def _simulate(t: np.ndarray, lay: _Layout, c: Choices, ph: _Physics) -> _Clean:
    """Noise-free sensor temperatures and elongation at the sample times ``t``."""
    fill = np.arange(lay.t_sim_start, t[-1], GAP_FILL_S)
    events = np.concatenate([lay.step_t0, lay.feed_t0])
    grid = np.unique(np.concatenate([t, fill, events[events <= t[-1]]]))
    grid = grid[grid >= lay.t_sim_start]
    s = _source_inputs(grid, lay, c, ph)
    weights = np.vstack([ph.weights_s, ph.weights_e])
    tau = np.concatenate([ph.tau_s, ph.tau_e])
    cold = np.where(np.array(c.sources) == "ambient", s[0], 0.0)  # at rest with the air
    y = first_order_lag(grid, s @ weights.T, tau, y0=weights @ cold)  # Zhu 2008 eq. 3.1
    rows = np.searchsorted(grid, t)
    n = c.n_sensors
    temps = c.ambient_mean_C + ph.offset_K + y[rows, :n]
    elong = y[rows, n:] @ ph.alpha_L  # Kidani 2020 eq. 3.17: dL = C L0 (T - T0) per element
    scale = c.amplitude_um / max(np.max(np.abs(elong - elong[0])), 1e-12)
    ph.alpha_L = np.round(ph.alpha_L * scale, 4)
    elong = y[rows, n:] @ ph.alpha_L  # Krulewich 1996 eq. 1: elongations add along the loop
    idx = np.searchsorted(lay.step_t0, t, side="right") - 1
    return _Clean(temps, elong, lay.step_rpm[idx])


# ---------------------------------------------------------------- readings and faults


@dataclass
class _Readings:
    """What the logger recorded, before formatting: degC except the converted cells."""

    temps: np.ndarray  # (N, n_sensors), written unit per cell
    noisy_C: np.ndarray  # (N, n_sensors) what sound sensors would have read, degC
    measured_um: np.ndarray  # (N,) zeroed elongation with its noise, um
    units: list[str]  # written unit per sensor for the log ("degC", "K", "degF")
    target: np.ndarray  # (N,) written value in the target unit
    faults: list[FaultTruth]
    slips: list[UnitSlipTruth]
    roles: dict[int, list[str]]  # sensor -> faults / slip on it


def _special_sensors(c: Choices, ph: _Physics, rng) -> dict[str, int]:
    """Give each fault and the unit slip its own degC sensor; one on-path sensor stays clean."""
    free = [j for j in range(c.n_sensors) if j != c.odd_sensor]
    order = [int(j) for j in rng.permutation(free)]
    order.remove(next((j for j in order if ph.on_path[j]), order[0]))  # one stays clean
    chosen: dict[str, int] = {}
    if c.unit_slip:
        on = [j for j in order if ph.on_path[j]] or order
        chosen["slip"] = on[0]
        order.remove(on[0])
    for kind in (k for k in c.faults if k != "missing"):
        chosen[kind] = order.pop(0)
    return chosen


def _fault_rows(kind: str, n: int, rng) -> int:
    if kind == "dead":
        return 0 if rng.random() < 0.5 else int(rng.integers(n // 10, 8 * n // 10))
    if kind == "stuck":
        return 0 if rng.random() < 0.2 else int(rng.integers(n // 5, 8 * n // 10))
    return int(rng.integers(3 * n // 10, 9 * n // 10))


def _apply_faults(temps: np.ndarray, chosen: dict[str, int], names: list[str],
                  rng) -> list[FaultTruth]:
    """Dead (-180 +/- noise), stuck (last reading held) and zero sensors, in place, degC."""
    n = len(temps)
    out = []
    for kind, j in chosen.items():
        if kind == "slip":
            continue
        r0 = _fault_rows(kind, n, rng)
        value: float | None
        if kind == "dead":
            temps[r0:, j] = DEAD_READING_C + rng.normal(0.0, 0.5, n - r0)
            value = DEAD_READING_C
        elif kind == "stuck":
            value = float(round(temps[r0 - 1, j] if r0 else np.mean(temps[:, j]), 2))
            temps[r0:, j] = value
        else:
            value = 0.0
            temps[r0:, j] = 0.0
        out.append(FaultTruth(kind, names[j], r0, n, value))
    return out


def _readings(c: Choices, ph: _Physics, clean: _Clean, run_rows: list[tuple[int, int]],
              names: list[str], hot_run: int | None, rng) -> _Readings:
    """Add noise, faults and unit conversions (a slip never in the hot run); sign the target."""
    n = len(clean.elong_um)
    noisy = clean.temps_C + rng.normal(0.0, c.noise_temp_K, clean.temps_C.shape)
    temps = noisy.copy()
    chosen = _special_sensors(c, ph, rng)
    faults = _apply_faults(temps, chosen, names, rng)
    units = ["degC"] * c.n_sensors
    if c.odd_unit:
        scale, offset = UNIT_MAPS[c.odd_unit]
        temps[:, c.odd_sensor] = scale * temps[:, c.odd_sensor] + offset
        units[c.odd_sensor] = c.odd_unit
    slips = []
    if c.unit_slip:
        j, run = chosen["slip"], int(_choose(rng, [r for r in range(c.n_runs) if r != hot_run]))
        r0, r1 = run_rows[run]
        scale, offset = UNIT_MAPS[c.unit_slip]
        temps[r0:r1, j] = scale * temps[r0:r1, j] + offset
        slips.append(UnitSlipTruth(run, names[j], c.unit_slip, scale, offset, r0, r1))
    zero = np.zeros(n)
    for r0, r1 in (run_rows if c.target_zero == "run_start" else [(0, n)]):
        zero[r0:r1] = clean.elong_um[r0]
    measured = clean.elong_um - zero + rng.normal(0.0, c.noise_target_um, n)
    target = c.sign * measured * TARGET_PER_UM[c.target_unit]
    roles: dict[int, list[str]] = {}
    for kind, j in chosen.items():
        roles.setdefault(j, []).append("unit_slip" if kind == "slip" else kind)
    return _Readings(temps, noisy, measured, units, target, faults, slips, roles)


# ---------------------------------------------------------------- columns and file


@dataclass
class _Column:
    name: str
    role: str
    unit: str | None
    token: str | None
    cells: list[str]
    sensor: int | None = None


def _fmt(values: np.ndarray, decimals: int) -> list[str]:
    return list(np.char.mod(f"%.{decimals}f", np.asarray(values, float)))


def _time_cells(t: np.ndarray, run_of_row: np.ndarray, run_rows, c: Choices) -> list[str]:
    if c.time_unit == "datetime":
        start = np.datetime64(datetime.datetime.strptime(c.start_datetime, DATETIME_FORMAT))
        stamps = start + np.round(t).astype("timedelta64[s]")
        return [s.replace("T", " ") for s in np.datetime_as_string(stamps, unit="s")]
    written = t.copy()
    if c.time_resets_per_run:
        written = written - t[[r0 for r0, _ in run_rows]][run_of_row]
    whole = not c.jitter and c.time_unit == "s"
    return _fmt(written / TIME_TO_S[c.time_unit], 0 if whole else TIME_DECIMALS[c.time_unit])


def sensor_names(c: Choices) -> list[str]:
    """Column names of the temperature sensors, in order (sensor ``j`` is number ``j + 1``)."""
    bare, full = TEMP_STYLES[c.temp_style]
    names = []
    for j in range(c.n_sensors):
        base = bare.format(i=j + 1)
        if j == c.odd_sensor:
            pattern = ODD_UNIT_NAMES[c.odd_unit][c.temp_style % 2]
            names.append(pattern.format(b=base))
        else:
            names.append(base if c.units_row else full.format(i=j + 1))
    return names


def _columns(c: Choices, t, run_of_row, run_rows, clean: _Clean, rd: _Readings,
             names: list[str]) -> list[_Column]:
    """All columns in file order, cells as written."""
    time_unit = c.time_unit
    cols = [_Column(c.time_name, "time", time_unit, TIME_TOKENS[time_unit],
                    _time_cells(t, run_of_row, run_rows, c))]
    if c.run_marking == "column":
        labels = (run_of_row + c.run_first_label).astype(str)
        cols.append(_Column(c.run_name, "run", None, "-", list(labels)))
    token = "µm" if c.target_unit == "um" else c.target_unit
    target = _Column(c.target_name, "target", c.target_unit, token,
                     _fmt(rd.target, TARGET_DECIMALS[c.target_unit]))
    if c.target_first:
        cols.append(target)
    for j, name in enumerate(names):
        unit = rd.units[j]
        token = c.temp_token if unit == "degC" else ODD_UNIT_TOKENS[unit]
        cols.append(_Column(name, "temperature", unit, token,
                            _fmt(rd.temps[:, j], c.temp_decimals), sensor=j + 1))
    if c.speed_column:
        cols.append(_Column(c.speed_name, "speed", "rpm", "rpm", _fmt(clean.rpm, 0)))
    if c.other_column:
        cols.append(_Column("coolant_on", "other", None, "-",
                            _fmt((clean.rpm > 0).astype(float), 0)))
    if not c.target_first:
        cols.append(target)
    return cols


def _blank_cells(cols: list[_Column], c: Choices, rd: _Readings, rng) -> list[MissingCell]:
    """A few empty or NaN cells in clean temperature columns and the target."""
    if "missing" not in c.faults:
        return []
    pick = [k for k, col in enumerate(cols) if col.role == "target"
            or (col.role == "temperature" and col.sensor - 1 not in rd.roles)]
    n_rows = len(cols[0].cells)
    out = []
    rows = rng.choice(np.arange(1, n_rows), size=int(rng.integers(1, 7)), replace=False)
    for row in sorted(int(r) for r in rows):
        col = cols[int(_choose(rng, pick))]
        written = _choose(rng, ("", "NaN", "nan"))
        col.cells[row] = written
        out.append(MissingCell(row, col.name, written))
    return out


def _write_csv(path: Path, cols: list[_Column], c: Choices, seed: int) -> FormatTruth:
    comments = [COMMENTS[k % len(COMMENTS)].format(m=seed % 7 + 1)
                for k in range(c.comment_lines)]
    with open(path, "w", newline="", encoding="utf-8") as handle:
        for line in comments:
            handle.write(line + "\n")
        writer = csv.writer(handle, delimiter=c.separator, lineterminator="\n")
        writer.writerow([col.name for col in cols])
        if c.units_row:
            writer.writerow([col.token for col in cols])
        writer.writerows(zip(*(col.cells for col in cols)))
    k = c.comment_lines
    return FormatTruth(c.separator, ".", "utf-8", "#", k, k + 1, k + 2 if c.units_row else None,
                       k + 2 + int(c.units_row), len(cols[0].cells), ["", "NaN", "nan"])


# ---------------------------------------------------------------- truth


def _run_rows(run_of_row: np.ndarray, n_runs: int) -> list[tuple[int, int]]:
    starts = np.searchsorted(run_of_row, np.arange(n_runs), side="left")
    ends = np.searchsorted(run_of_row, np.arange(n_runs), side="right")
    return [(int(a), int(b)) for a, b in zip(starts, ends)]


def _regimes(lay: _Layout, t: np.ndarray, run_rows, time_cells: list[str]) -> list[RegimeTruth]:
    """Row ranges of the regimes: from the first row at or after each start to the next
    regime's first row; a run's first and last regime reach its first and last row."""
    spans = lay.regime_spans
    starts = []
    for k, (_, run, t0, _) in enumerate(spans):
        first = k == 0 or spans[k - 1][1] != run
        starts.append(run_rows[run][0] if first else int(np.searchsorted(t, t0, side="left")))
    out = []
    for k, (block, run, t0, t1) in enumerate(spans):
        last = k == len(spans) - 1 or spans[k + 1][1] != run
        r0, r1 = starts[k], run_rows[run][1] if last else starts[k + 1]
        if r1 <= r0:
            raise ValueError(f"regime {k} ({block.kind}) holds no rows; lower sampling_s")
        speeds = [float(rpm) for _, rpm in block.steps]
        out.append(RegimeTruth(k, block.kind, block.program, run, r0, r1, float(t0), float(t1),
                               time_cells[r0], time_cells[r1 - 1], speeds,
                               _step_starts(block, t0)))
    return out


def _step_starts(block: _Block, t0: float) -> list[tuple[float, float]]:
    starts = t0 + np.concatenate([[0.0], np.cumsum([d for d, _ in block.steps])[:-1]])
    return [(round(float(t), 3), float(rpm)) for t, (_, rpm) in zip(starts, block.steps)]


def _prehistory(plan: _Plan) -> list[UnloggedBlock]:
    t = -sum(b.duration for b in plan.pre)
    out = []
    for block in plan.pre:
        out.append(UnloggedBlock(block.kind, block.program, t, t + block.duration,
                                 _step_starts(block, t)))
        t += block.duration
    return out


def _runs(c: Choices, t: np.ndarray, run_rows) -> list[RunTruth]:
    start = datetime.datetime.strptime(c.start_datetime, DATETIME_FORMAT)
    out = []
    for r, (r0, r1) in enumerate(run_rows):
        jump = float(t[r0] - t[run_rows[r - 1][1] - 1]) if r else None
        label = r + c.run_first_label if c.run_marking == "column" else None
        when = start + datetime.timedelta(seconds=float(t[r0]))
        out.append(RunTruth(r, label, r0, r1, float(t[r0]), float(t[r1 - 1]), jump,
                            when.strftime(DATETIME_FORMAT)))
    return out


def _sensor_truths(c: Choices, ph: _Physics, clean: _Clean, rd: _Readings,
                   names: list[str]) -> list[SensorTruth]:
    w = np.abs(ph.alpha_L)
    tau_eff = float(np.sum(w * ph.tau_e) / np.sum(w))
    out = []
    for j, name in enumerate(names):
        corr = float(np.corrcoef(rd.noisy_C[:, j], rd.measured_um)[0, 1])
        weights = {s: float(ph.weights_s[j, i]) for i, s in enumerate(c.sources)}
        out.append(SensorTruth(name, j + 1, rd.units[j], float(ph.tau_s[j]), weights,
                               float(ph.offset_K[j]), bool(ph.on_path[j]),
                               "leads" if tau_eff < ph.tau_s[j] else "lags",
                               round(corr, 4), rd.roles.get(j, [])))
    return out


def _target_truth(c: Choices, ph: _Physics) -> TargetTruth:
    w = np.abs(ph.alpha_L)
    elements = [ElementTruth(name, float(ph.tau_e[k]), float(ph.alpha_L[k]),
                             {s: float(ph.weights_e[k, i]) for i, s in enumerate(c.sources)})
                for k, name in enumerate(("spindle_shaft", "headstock", "column")[:c.n_elements])]
    convention = ("written = sign * (elongation of the tool-to-work loop, positive when it "
                  "grows) * per_um; the elongation is zeroed at " + c.target_zero)
    return TargetTruth(c.target_name, c.target_unit, TARGET_PER_UM[c.target_unit], c.sign,
                       convention, c.target_zero, c.amplitude_um, c.noise_target_um,
                       float(np.sum(w * ph.tau_e) / np.sum(w)), elements)


def _hot_runs(plan: _Plan, ph: _Physics, clean: _Clean, run_rows, names: list[str],
              rd: _Readings) -> list[HotRunTruth]:
    if plan.hot_run is None:
        return []
    r0, r1 = run_rows[plan.hot_run]
    hot = np.zeros(len(clean.elong_um), bool)
    hot[r0:r1] = True
    shift = clean.temps_C[hot].mean(axis=0) - clean.temps_C[~hot].mean(axis=0)
    elong = clean.elong_um - clean.elong_um[0]
    clean_on = ph.on_path & ~np.isin(np.arange(len(names)), list(rd.roles))
    heated = np.where(clean_on, shift, -np.inf)  # the heater's sensor: the largest rise
    typical = [s for r, s in enumerate(plan.heating_shares) if r != plan.hot_run][0]
    return [HotRunTruth(plan.hot_run, "spindle_bearings", plan.heating_shares[plan.hot_run],
                        typical, names[int(np.argmax(heated))],
                        {n: round(float(v), 4) for n, v in zip(names, shift)},
                        round(float(elong[hot].mean() - elong[~hot].mean()), 4))]


def _split(c: Choices, regimes: list[RegimeTruth], n_rows: int) -> SplitTruth | None:
    if c.scenario != "train_split":
        return None
    end = regimes[0].row_end
    return SplitTruth(end, round(end / n_rows, 4), [0], [r.index for r in regimes[1:]])


def _sources(c: Choices, ph: _Physics, lay: _Layout) -> list[SourceTruth]:
    feed = [(round(float(t), 3), round(float(d), 4)) for t, d in zip(lay.feed_t0, lay.feed_duty)]
    return [SourceTruth(s, ph.gains[s], s != "feed_drive", SOURCE_NOTES[s],
                        feed if s == "feed_drive" else None) for s in c.sources]


# ---------------------------------------------------------------- entry points


def make_log(seed: int, out_dir: Path, **choices) -> LogTruth:
    """Write one log ``<name>.csv`` and its truth ``<name>.truth.json`` into ``out_dir``.

    Parameters
    ----------
    seed : int
        Seed of every draw; the same seed and choices give the same files.
    out_dir : Path
        Directory, created if missing.
    **choices
        ``name`` (the file stem, default ``regime_log_s<seed>``) and any field of
        :class:`Choices` to force instead of drawing it.

    Returns
    -------
    LogTruth
        The truth, also written as JSON.

    Raises
    ------
    ValueError
        Unknown or contradicting choices, or ``max_rows`` too small for the log.
    """
    name = str(choices.pop("name", f"regime_log_s{seed}"))
    c = draw_choices(seed, **choices)
    rng_plan, rng_phys, rng_noise, rng_fault = (np.random.default_rng([seed, k])
                                                for k in (1, 2, 3, 4))
    plan = PLANNERS[c.scenario](c, rng_plan)
    lay = _layout(plan, c, rng_plan)
    t, run_of_row, dt = _sample_times(lay, c, rng_plan)
    run_rows = _run_rows(run_of_row, c.n_runs)
    ph = _draw_physics(c, rng_phys)
    clean = _simulate(t, lay, c, ph)
    names = sensor_names(c)
    rd = _readings(c, ph, clean, run_rows, names, plan.hot_run, rng_noise)
    cols = _columns(c, t, run_of_row, run_rows, clean, rd, names)
    missing = _blank_cells(cols, c, rd, rng_fault)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    csv_path, truth_path = out_dir / f"{name}.csv", out_dir / f"{name}.truth.json"
    fmt = _write_csv(csv_path, cols, c, seed)
    regimes = _regimes(lay, t, run_rows, cols[0].cells)
    truth = LogTruth(
        SCHEMA, name, csv_path.name, str(csv_path), str(truth_path), seed, c, fmt,
        [ColumnTruth(k, col.name, col.role, col.unit, col.token if c.units_row else None,
                     col.sensor) for k, col in enumerate(cols)],
        TimeTruth(c.time_name, c.time_unit,
                  DATETIME_FORMAT if c.time_unit == "datetime" else None, dt,
                  0.25 * dt if c.jitter and dt >= 2 else 0.0, c.time_resets_per_run,
                  c.start_datetime, 1.0 if c.time_unit == "datetime" else 0.01),
        _target_truth(c, ph), _sources(c, ph, lay), _sensor_truths(c, ph, clean, rd, names),
        _runs(c, t, run_rows), regimes, _split(c, regimes, len(t)), rd.faults, missing,
        rd.slips, _hot_runs(plan, ph, clean, run_rows, names, rd),
        {"temperature_K": c.noise_temp_K, "target_um": c.noise_target_um, "dead_K": 0.5},
        {"mean_C": c.ambient_mean_C, "amplitude_K": c.ambient_amplitude_K,
         "peak_h": c.ambient_peak_h, "period_s": DAY}, _prehistory(plan))
    truth_path.write_text(json.dumps(truth.to_dict(), indent=1, ensure_ascii=False,
                                     default=_json_default) + "\n", encoding="utf-8")
    return truth


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON: {type(value).__name__}")


def _parse_choice(text: str) -> tuple[str, object]:
    key, sep, raw = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"expected key=value, got {text!r}")
    try:
        return key, json.loads(raw)
    except json.JSONDecodeError:
        return key, raw


def main(argv: list[str] | None = None) -> int:
    """Command line: write one log and its truth JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--choice", type=_parse_choice, action="append", default=[],
                        metavar="KEY=VALUE", help="force a choice (JSON value or string)")
    args = parser.parse_args(argv)
    truth = make_log(args.seed, args.out, **dict(args.choice))
    print(f"{truth.csv_path} ({truth.format.n_rows} rows, {truth.choices.scenario}); "
          f"truth {truth.truth_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
