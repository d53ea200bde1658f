"""What ``mt-accuracy check`` found: one typed result, rendered three ways.

:class:`CheckResult` is what :func:`~.check.check_bag`, :func:`~.check.check_mapped_csv`
and :func:`~.check_log.check_csv` return. Its renderings:

* the printed lines - :func:`printed_lines`;
* the JSON summary - :meth:`CheckResult.to_json` (schema: ``docs/check_json.md``,
  versioned by :data:`SCHEMA_VERSION`; the result is also a read-only mapping of it, so
  ``result["final_rmse"]`` reads as the JSON does);
* the HTML report - :mod:`~mt_accuracy_ros.report.sections`, reading the same fields.

A sentence that two renderings share is made here once (:func:`weights_sentence`,
:func:`readings_text`, :func:`as_paragraph`). Every figure is SI (metres, 1/K) as the
engine computed it; a rendering converts it, printed lines in micrometres (a survey, a
bag) or the log target's own unit.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

#: Version of the JSON summary's layout (``docs/check_json.md``): raised when a key is
#: renamed, removed or changes its meaning; adding a key keeps it.
SCHEMA_VERSION = 1

#: "not added" lines a thermal log's check prints (the JSON holds them all).
SHOWN_REFUSALS = 5
#: Whole models of a thermal log shown with their forward and held-out figures.
SHOWN_CONTESTANTS = 5
#: Candidates of the ranking printed.
SHOWN_RANKING = 5

#: The JSON summary's keys per kind of data, in order (``docs/check_json.md``).
JSON_KEYS = {
    "bag": ("data", "kind", "namespace", "sensors_kept", "readings", "figures_before_m",
            "figures_after_m", "baseline_rmse", "baseline_cv_rmse", "ranking", "named",
            "dropped", "verdict", "localisation", "added", "final_rmse", "steps", "band",
            "final_diagnosis", "final_verdict", "final_localisation", "machine", "model_yaml",
            "warnings"),
    "survey_csv": ("data", "kind", "rows_read", "rows_dropped", "rows_note", "machine",
                   "machine_note", "setup_pose_rad", "error_convention", "travel_warning",
                   "namespace", "readings",
                   "figures_before_m", "figures_after_m", "baseline_rmse", "baseline_cv_rmse",
                   "ranking", "named", "dropped", "verdict", "localisation", "added",
                   "final_rmse", "steps", "band", "final_diagnosis", "final_verdict",
                   "final_localisation", "model_yaml", "runs", "validation", "warnings",
                   "sensor_notes", "sensors_kept"),
    "thermal_log": ("data", "kind", "target", "target_unit", "target_unit_per_m", "component",
                    "rows", "rows_read", "rows_dropped", "rows_note", "readings", "train_rows",
                    "band", "machine", "validation", "decided_on", "figures_before_held_out_m",
                    "figures_after_held_out_m", "baseline_rmse", "baseline_cv_rmse",
                    "held_out_baseline_rmse", "ranking", "named", "verdict", "localisation",
                    "added", "final_rmse", "steps", "final_diagnosis", "final_verdict",
                    "not_added", "not_added_lines", "constant_held_out_rmse", "warnings",
                    "notes", "step_by_step_added", "model_contest_forward_rmse",
                    "model_chosen", "model_contest", "judged_on",
                    "all_inputs_least_squares_held_out_rmse", "baselines_held_out_m",
                    "sensors_carrying_weight", "sensors_carrying_weight_of", "model_yaml",
                    "runs", "zeroed_runs", "walk_forward")}
#: Keys a summary leaves out when there is nothing to say (None); every other key is
#: always there (a thermal log's ``runs`` is null without runs).
OPTIONAL_KEYS = {"bag": {"warnings"},
                 "survey_csv": {"runs", "validation", "warnings", "sensor_notes"},
                 "thermal_log": {"walk_forward"}}


def _plain(value):
    """``value`` as JSON holds it: dataclasses as dicts (their None fields left out)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return value.as_dict() if hasattr(value, "as_dict") else dataclasses.asdict(value)
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return value


class _AsDict:
    """``as_dict``: the fields in order, those that are None left out."""

    def as_dict(self) -> dict:
        return {f.name: _plain(getattr(self, f.name)) for f in dataclasses.fields(self)
                if getattr(self, f.name) is not None}


@dataclass
class ModelStep(_AsDict):
    """One version of the model in the check's search, and what was added to make the next.

    Attributes
    ----------
    model_version : int
        The model's version.
    effects : list of str
        Its effects, sorted.
    rmse : float
        In-sample RMS of its residual [m] (a thermal log: on the training rows).
    diagnosis : str
        The diagnosis of its residual, in words.
    held_out_rmse, cv_rmse, validation_rmse : float or None
        A thermal log only: RMS error on the held-out rows, cross-validated on the
        training rows, and predicting the last training block from the blocks before [m].
    added : list of str or None
        The effects added to this version to make the next (None on the last).
    parameters, parameter_uncertainties : dict or None
        Per added effect, its parameters and their k = 1 uncertainties (SI).
    """

    model_version: int
    effects: list[str]
    rmse: float
    diagnosis: str
    held_out_rmse: float | None = None
    cv_rmse: float | None = None
    validation_rmse: float | None = None
    added: list[str] | None = None
    parameters: dict | None = None
    parameter_uncertainties: dict | None = None

    def record_added(self, candidates) -> None:
        """Record ``candidates`` (the workbench's, with ``name``, ``parameters`` and
        ``parameter_uncertainties``) as what was added to this version."""
        self.added = [c.name for c in candidates]
        self.parameters = {c.name: c.parameters for c in candidates}
        self.parameter_uncertainties = {c.name: c.parameter_uncertainties for c in candidates}


@dataclass
class RunFigures(_AsDict):
    """One run of the data (rows sharing a run column's value).

    Attributes
    ----------
    run : str
        Its name (the run column's value).
    rows : int
        Its rows.
    part : str or None
        A thermal log: "training" when the selection saw it, else "held out".
    constant_rmse, least_squares_rmse, model_rmse : float or None
        A thermal log: RMS error on the run of a constant, of least squares on every
        input and of the chosen model [m].
    """

    run: str
    rows: int
    part: str | None = None
    constant_rmse: float | None = None
    least_squares_rmse: float | None = None
    model_rmse: float | None = None


@dataclass
class NotAdded(_AsDict):
    """A candidate with a large cross-validated gain that a thermal log's check did not add.

    Attributes
    ----------
    name : str
        The candidate.
    cv_reduction : float
        Its cross-validated error reduction (a fraction).
    test : str
        The test that refused it, in words.
    before, after : float or None
        When refused for predicting the last training block worse: that block's RMS error
        without and with it [m].
    """

    name: str
    cv_reduction: float
    test: str
    before: float | None = None
    after: float | None = None


@dataclass
class ContestEntry(_AsDict):
    """A whole model of a thermal log in the contest by forward validation.

    Attributes
    ----------
    name : str
        "step by step", or the whole-model candidate's name.
    terms : list of str
        The effects it consists of.
    forward_rmse : float
        Its forward-validation error pooled over the training blocks [m] (what decides).
    forward_blocks : list of dict
        Per judged block: ``trained_rows``, ``judged_rows`` and ``rmse`` [m].
    held_out_rmse : float
        Its error on the held-out rows [m], computed after the decision (decides nothing).
    chosen : bool
        Whether it is the model.
    cross_regime_rmse : float or None
        Its error on each regime of the training rows predicted by a fit on the others,
        pooled over the regimes that tell models apart (some model predicts them better
        than a constant, :func:`~.check_log.telling_regimes`) [m]; None when the training
        rows hold one regime or none tells.
    cross_regime_blocks : list of dict
        Per regime: ``regime``, ``trained_rows``, ``judged_rows``, ``rmse`` [m],
        ``range_excess`` (how far its inputs left the fitted range, a share of the span)
        and ``decides`` (the regime tells models apart: some model predicts it better than
        a constant).
    score : float
        What decides: the worse of the forward and the cross-regime errors [m].
    range_excess : float
        How far its inputs left their fitted range on the regimes it was judged on (the
        largest over them), a share of the range's span.
    held_out_range_excess : float
        The same on the held-out rows against every training row (decides nothing).
    """

    name: str
    terms: list[str]
    forward_rmse: float
    forward_blocks: list[dict]
    held_out_rmse: float
    chosen: bool
    cross_regime_rmse: float | None = None
    cross_regime_blocks: list[dict] = field(default_factory=list)
    score: float = float("nan")
    range_excess: float = 0.0
    held_out_range_excess: float = 0.0


@dataclass
class DataSource(_AsDict):
    """Where the readings came from, and what was said about reading them.

    Attributes
    ----------
    rows_read, rows_dropped : int or None
        A CSV's data rows read and left out.
    rows_note : str or None
        A CSV: the rows used and why any were left out, in one line.
    namespace : str or None
        A bag: the machine's namespace ("" for a survey).
    machine_note : str or None
        A survey: the machine assumed, the set-up and the error columns' reading, in words.
    setup_pose_rad : dict or None
        A survey: each rotary axis' set-up angle [rad].
    error_convention : dict or None
        A survey: how its error columns were read (``of``, ``as``, ``frame``,
        ``aligned_at``, and ``stated``: whether the column map said so).
    travel_warning : str or None
        A survey: readings outside the machine's travel ("" when none).
    sensors_kept : list of str or None
        A bag or survey: the temperature sensors every model may use.
    sensor_notes : list of str or None
        A survey: what the sensors' judge found (None when nothing).
    """

    rows_read: int | None = None
    rows_dropped: int | None = None
    rows_note: str | None = None
    namespace: str | None = None
    machine_note: str | None = None
    setup_pose_rad: dict | None = None
    error_convention: dict | None = None
    travel_warning: str | None = None
    sensors_kept: list[str] | None = None
    sensor_notes: list[str] | None = None


@dataclass
class ThermalLog(_AsDict):
    """What only a thermal log's check says (``docs/check_json.md`` gives each key).

    Attributes
    ----------
    target, target_unit : str
        The displacement column and the unit the printed lines speak.
    target_unit_per_m : float
        That unit per metre (1e6 for um).
    component : str
        The direction of the displacement ("x", "y" or "z").
    rows, train_rows : int
        Rows used, and the leading rows the selection saw.
    decided_on, judged_on : str
        What decided and what judged, in words.
    figures_before_held_out_m, figures_after_held_out_m : dict
        RMSE, max and range of the residual on the held-out rows [m], before and after.
    held_out_baseline_rmse, constant_held_out_rmse : float
        On the held-out rows: the starting model's and a constant's RMS error [m].
    all_inputs_least_squares_held_out_rmse : float
        The same of least squares on every input [m].
    baselines_held_out_m : dict
        The three held-out figures by name [m].
    not_added : list of NotAdded
        Large gains not added, and why.
    not_added_lines : list of str
        The same in the printed words.
    notes : list of str
        Decisions taken on reading the log.
    step_by_step_added : list of str
        What the step-by-step search added (whether or not it won the contest).
    model_contest_forward_rmse : dict
        Each whole model's pooled forward error [m].
    model_chosen : str
        The winner.
    model_contest : list of ContestEntry
        The contest, best first.
    sensors_carrying_weight : dict
        The sensors a sensor model leans on: name -> share of its spread.
    sensors_carrying_weight_of : dict
        Whose weights those are: ``name``, ``sensors``, ``in_model`` and ``words``.
    zeroed_runs : bool
        Whether the instrument was zeroed at each run's start.
    walk_forward : WalkForward or None
        The log replayed in time (``--walk-forward``): each period predicted by the model
        made from every row before it, and by the baselines
        (:class:`~mt_accuracy_ros.core.workbench.walk_forward.WalkForward`).
    """

    target: str
    target_unit: str
    target_unit_per_m: float
    component: str
    rows: int
    train_rows: int
    decided_on: str
    figures_before_held_out_m: dict
    figures_after_held_out_m: dict
    held_out_baseline_rmse: float
    not_added: list[NotAdded]
    not_added_lines: list[str]
    constant_held_out_rmse: float
    notes: list[str]
    step_by_step_added: list[str]
    model_contest_forward_rmse: dict
    model_chosen: str
    model_contest: list[ContestEntry]
    judged_on: str
    all_inputs_least_squares_held_out_rmse: float
    baselines_held_out_m: dict
    sensors_carrying_weight: dict
    sensors_carrying_weight_of: dict
    zeroed_runs: bool
    walk_forward: object = None


@dataclass(eq=False)
class CheckResult(Mapping):
    """``mt-accuracy check``'s result on a bag, a survey or a thermal log.

    The fields are named as the JSON summary's keys (``docs/check_json.md``); those of
    one kind of data only are None on the others (a thermal log's are in :attr:`log`, a
    CSV's and a bag's source in :attr:`source`). As a :class:`~collections.abc.Mapping`
    the result reads as its JSON summary (:meth:`to_json`).

    Attributes
    ----------
    kind : str
        "bag", "survey_csv" or "thermal_log".
    data : str
        The file or bag checked.
    machine : str
        The model's machine.
    readings : int
        Readings the model was judged on.
    band : float
        The reference instrument's k = 2 uncertainty [m].
    baseline_rmse, baseline_cv_rmse : float
        The starting model's residual RMS, in-sample and cross-validated [m].
    ranking : list of dict
        The first diagnosis' candidates, best first (at most 30; the diagnosis' candidate
        entries: ``effect``, ``name``, ``cv_rmse_after`` [m], ``error_reduction``,
        ``significant``, ``confidence``, ``explanation``, ``display`` ...).
    named : list of dict
        The candidates the first diagnosis named, in the same form.
    verdict, final_verdict : str
        What the first and the final diagnoses conclude, in words.
    localisation : dict
        Where the starting model's residual lives (``sentence``, ``shares``, ``peaks``).
    added : list of str
        The effects added, in order.
    final_rmse : float
        The final model's RMS error [m] (a thermal log: on the held-out rows).
    steps : list of ModelStep
        Every version of the model.
    final_diagnosis : str
        The final model's diagnosis, in words.
    model_yaml : str
        The final model as YAML.
    source : DataSource
        Where the readings came from.
    log : ThermalLog or None
        A thermal log's own figures.
    figures_before_m, figures_after_m : dict or None
        A bag or survey: RMSE, max and range of the residual before and after [m].
    dropped : list of dict or None
        A bag or survey: named effects the joint fit dropped (each with its ``sentence``).
    final_localisation : dict or None
        A bag or survey: where the final model's residual lives.
    warnings : list of str or None
        What the reader must know (printed and in the JSON); None: nothing was said.
    runs : list of RunFigures or None
        The data's runs.
    validation : str or None
        How candidates were cross-validated, in words.
    plot : dict
        The arrays the report plots (not in the JSON).
    report : dict or None
        The report's content once written (:meth:`~..report.Report.as_dict`).
    seconds : dict
        Where the check's time went (not in the JSON): ``search``, the diagnoses' wall
        time [s] (what ``mt-accuracy fleet`` reports per task beside reading the data).
    """

    kind: str
    data: str
    machine: str
    readings: int
    band: float
    baseline_rmse: float
    baseline_cv_rmse: float
    ranking: list[dict]
    named: list[dict]
    verdict: str
    localisation: dict
    added: list[str]
    final_rmse: float
    steps: list[ModelStep]
    final_diagnosis: str
    final_verdict: str
    model_yaml: str
    source: DataSource = field(default_factory=DataSource)
    log: ThermalLog | None = None
    figures_before_m: dict | None = None
    figures_after_m: dict | None = None
    dropped: list[dict] | None = None
    final_localisation: dict | None = None
    warnings: list[str] | None = None
    runs: list[RunFigures] | None = None
    validation: str | None = None
    plot: dict = field(default_factory=dict, repr=False)
    report: dict | None = None
    seconds: dict = field(default_factory=dict, repr=False)

    def _value(self, key: str):
        """The field named ``key``: this result's, its source's or its log's."""
        for part in (self, self.source, self.log):
            if part is not None and key in _FIELDS[type(part)]:
                return getattr(part, key)
        raise KeyError(key)

    def to_json(self) -> dict:
        """The JSON summary: ``schema_version`` first, then :data:`JSON_KEYS` of this
        kind in order (those of :data:`OPTIONAL_KEYS` only when said), then ``report``
        once one was written. Figures in SI units."""
        out = {"schema_version": SCHEMA_VERSION}
        optional = OPTIONAL_KEYS[self.kind]
        for key in JSON_KEYS[self.kind]:
            value = self._value(key)
            if value is None and key in optional:
                continue
            out[key] = _plain(value)
        if self.report is not None:
            out["report"] = self.report
        return out

    def __getitem__(self, key: str):
        return self.to_json()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.to_json())

    def __len__(self) -> int:
        return len(self.to_json())

    @property
    def unit_and_scale(self) -> tuple[str, float]:
        """(unit, that unit per metre) the printed lines speak: a thermal log its target's,
        a survey or a bag micrometres (a metrologist's unit)."""
        if self.log is not None:
            return self.log.target_unit, self.log.target_unit_per_m
        return "um", 1e6


_FIELDS = {cls: {f.name for f in dataclasses.fields(cls)}
           for cls in (CheckResult, DataSource, ThermalLog)}


# --------------------------------------------------------------- sentences made once
def as_paragraph(line: str) -> str:
    """A printed line as a report's sentence: capitalised, with a full stop."""
    return line[0].upper() + line[1:] + "."


def weights_sentence(log: ThermalLog) -> str:
    """Which sensors a thermal log's sensor model leans on ("" when none does): "the model
    all_sensors_ridge over 16 sensors leans on: t4_C 18 %, ..." (share of its spread)."""
    if not log.sensors_carrying_weight:
        return ""
    whose = (log.sensors_carrying_weight_of or {}).get("words", "the sensor model")
    return f"{whose} leans on: " + ", ".join(
        f"{sensor} {100 * share:.0f} %" for sensor, share in log.sensors_carrying_weight.items())


def readings_text(entry: dict) -> str:
    """A candidate's parameters as read: "bx = 1.59 ± 0.53 µm/K; ..." (U, k = 2)."""
    from ..core.effects.display import display_parameters

    shown = entry.get("display") or display_parameters(
        entry.get("effect", ""), entry.get("variant", ""), entry.get("parameters", {}),
        entry.get("parameter_uncertainties", {}))
    return "; ".join(f"{name} = {text}" for name, text in shown.items())


# --------------------------------------------------------------- the printed lines
def printed_lines(result: CheckResult) -> list[str]:
    """What ``mt-accuracy check`` prints of ``result``, line by line."""
    lines = [result.source.rows_note] if result.source.rows_note else []
    lines += [note for note in (result.source.machine_note, result.source.travel_warning)
              if note]
    lines += list(result.warnings or [])
    if result.log is not None:
        lines += _log_lines(result)
    unit, scale = result.unit_and_scale
    lines.append(f"baseline RMSE {result.baseline_rmse * scale:.4g} {unit}")
    for entry in result.ranking[:SHOWN_RANKING]:
        flag = "*" if entry["significant"] else " "
        lines.append(f" {flag} {entry.get('name', entry['effect'])[:60]:60s} CV RMSE after "
                     f"{entry['cv_rmse_after'] * scale:.4g} {unit} "
                     f"({100 * entry['error_reduction']:.1f} %)")
    lines += _named_lines(result)
    if result.log is not None and weights_sentence(result.log):
        lines.append(weights_sentence(result.log))
    lines.append(f"added: {', '.join(result.added) or 'nothing'}; final "
                 f"{'held-out ' if result.log is not None else ''}RMSE "
                 f"{result.final_rmse * scale:.4g} {unit}")
    return lines


def _named_lines(result: CheckResult) -> list[str]:
    """The named effects with their readings, the dropped ones, where and the verdict."""
    lines = []
    for entry in result.named:
        lines.append(f"named: {entry['name']} (confidence {100 * entry['confidence']:.0f} %): "
                     f"{entry['explanation']}")
        readings = readings_text(entry)
        if readings:
            setting = entry.get("setting_display", "")
            lines.append(f"       {readings} (U, k = 2){'; ' + setting if setting else ''}")
    lines += [entry["sentence"] for entry in result.dropped or []]
    if result.localisation.get("sentence"):
        lines.append(f"where: {result.localisation['sentence']}")
    if result.verdict:
        lines.append(f"verdict: {result.verdict}")
    return lines


def _log_lines(result: CheckResult) -> list[str]:
    """A thermal log's own lines: refusals, notes, held-out figures, the contest, runs."""
    log = result.log
    unit, scale = result.unit_and_scale
    lines = log.not_added_lines[:SHOWN_REFUSALS]
    if len(log.not_added_lines) > SHOWN_REFUSALS:
        lines.append(f"... and {len(log.not_added_lines) - SHOWN_REFUSALS} more not added "
                     "(the JSON's not_added)")
    lines += [f"note: {line}" for line in log.notes]
    lines.append(f"held-out RMSE (rows after the first {log.train_rows}) "
                 f"{log.held_out_baseline_rmse * scale:.4g} {unit}; a constant's "
                 f"{log.constant_held_out_rmse * scale:.4g} {unit}; least squares on every "
                 f"input {log.all_inputs_least_squares_held_out_rmse * scale:.4g} {unit}")
    if len(log.model_contest) > 1:
        across = any(e.cross_regime_rmse is not None for e in log.model_contest)
        lines.append("whole models contested (forward over the training blocks"
                     + (" / each training regime from the others, the worse decides;"
                        " inputs beyond their fitted range" if across else "")
                     + " -> held out; the held-out figure decided nothing):")
        for entry in log.model_contest[:SHOWN_CONTESTANTS]:
            name = entry.name if entry.name != "step by step" else \
                f"step by step ({', '.join(entry.terms) or 'nothing added'})"
            regimes = (f" / {entry.cross_regime_rmse * scale:.4g} "
                       f"(x{entry.range_excess:.2g})" if entry.cross_regime_rmse is not None
                       else "")
            lines.append(f"  {'*' if entry.chosen else ' '} {name[:60]:60s} "
                         f"{entry.forward_rmse * scale:.4g}{regimes} -> "
                         f"{entry.held_out_rmse * scale:.4g} {unit}")
    if log.walk_forward is not None:
        from .check_walk import walk_forward_lines

        lines += walk_forward_lines(log.walk_forward, unit, scale)
    for run in result.runs or []:
        lines.append(f"  run {run.run:>12s} ({run.part}, {run.rows} rows): constant "
                     f"{run.constant_rmse * scale:.4g}, least squares "
                     f"{run.least_squares_rmse * scale:.4g}, model "
                     f"{run.model_rmse * scale:.4g} {unit} RMS")
    return lines
