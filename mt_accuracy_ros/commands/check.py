"""``mt-accuracy check``: compare a model with measurements, find and add what is missing.

DATA is a bag of this package's topics (``reference/tcp_error`` readings,
``temperatures``, ``systematic/<axis>`` profiles) checked against an
:class:`~mt_accuracy_ros.core.compensation.error_model.ErrorModel`, or a CSV table checked
as a thermal log on the same engine (:mod:`~mt_accuracy_ros.core.workbench.thermal_log`).
Effects are ranked by time-blocked cross-validation; ``--add`` adds named ones,
``--auto`` keeps adding the top significant candidate. The JSON holds
``baseline_rmse``, ``ranking`` [{effect, cv_rmse_after, explanation}], ``added``
and ``final_rmse``; the HTML report shows where the model fails and the error
falling.
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from ..core.errors import InputDataError, MtAccuracyError
from .check_result import CheckResult, DataSource, ModelStep, RunFigures


def error_figures(residual: np.ndarray, unit_scale: float = 1.0) -> dict:
    """RMSE, max |error| and the ISO 230-2-style range (max - min, the E/M-like spread
    of the deviations) of a residual, per component for (N, 3) residuals."""
    r = np.atleast_2d(np.asarray(residual, dtype=np.float64).T).T
    figures = {"rmse": float(np.sqrt(np.mean(r ** 2))) * unit_scale,
               "max_abs": float(np.max(np.abs(r))) * unit_scale}
    labels = "xyz" if r.shape[1] == 3 else [""]
    for c, label in enumerate(labels):
        figures[f"range{'_' + label if label else ''}"] = float(np.ptp(r[:, c])) * unit_scale
    return figures


# ------------------------------------------------------------------ bag path
def observations_from_bag(bag: Path, namespace: str = "", kinematics=None):
    """Readings, temperatures at their stamps, the profile history of a bag, and the
    sentences saying where a documented default uncertainty was taken.

    Readings whose instrument states a fixed target (``target_point``) are taken there;
    the others at the machining point of ``kinematics`` (the model's chain)."""
    from ..core.workbench.diagnosis import Observations
    from ..io.bag_reader import decode, read_messages, topics
    from ..core.workbench.diagnosis import work_points
    from ..core.workbench.statistics import DEFAULT_POSITION_UNCERTAINTY_M, stated_uncertainty
    from ..io.fields import (machine_direction_error, machine_error, stamp_to_nanoseconds,
                             target_point, unpack_float64)

    prefix = namespace.rstrip("/")
    available = topics(bag)
    wanted = {f"{prefix}/reference/tcp_error", f"{prefix}/temperatures"} | \
        {f"{prefix}/systematic/{a}" for a in "xyz"}
    if f"{prefix}/reference/tcp_error" not in available:
        raise InputDataError(f"{bag}: no {prefix}/reference/tcp_error topic; topics: "
                             f"{', '.join(sorted(available))}")
    from tqdm import tqdm

    from ..io.bag_reader import bag_info

    readings, temps, profiles = [], [], []
    chosen = sorted(wanted & set(available))
    counts = bag_info(bag)["topics"]
    # A long bag takes a while: a progress bar on a terminal (none when piped).
    for message in tqdm(read_messages(bag, chosen), desc=f"reading {Path(bag).name}", unit="msg",
                        total=sum(counts.get(t, {}).get("count", 0) for t in chosen),
                        disable=None, leave=False):
        data = decode(message)
        stamp = stamp_to_nanoseconds(data.header.stamp)
        if message.topic.endswith("reference/tcp_error"):
            readings.append((stamp, data))
        elif message.topic.endswith("temperatures"):
            temps.append((stamp, list(data.sensor_names), unpack_float64(data.temperatures).copy()))
        else:
            difference = unpack_float64(data.baseline_difference).copy()
            profiles.append((stamp, data.error_name, unpack_float64(data.positions).copy(),
                             unpack_float64(data.systematic).copy(),
                             difference if difference.size else None))
    if len(readings) < 10:
        raise InputDataError(f"{bag}: only {len(readings)} reference readings")
    readings.sort(key=lambda r: r[0])
    axes = [a.upper() for a in readings[0][1].command_axes]
    stamps = np.array([r[0] for r in readings], dtype=np.int64)
    temperatures = sampled_temperatures(temps, stamps)
    keep, sensor_notes = judge_bag_sensors(temperatures, stamps, prefix)
    readings, stamps = [r for r, k in zip(readings, keep) if k], stamps[keep]
    temperatures = {name: values[keep] for name, values in temperatures.items()}
    obs = Observations(
        positions={a: np.array([r[1].command_positions[i] for r in readings]) for i, a in
                   enumerate(axes)},
        measured_m=np.array([machine_error(r[1]) for r in readings]),
        measured_mask=np.array([list(r[1].measured) for r in readings], dtype=bool),
        time_s=(stamps - stamps[0]) / 1e9,
        velocities={a: np.array([r[1].command_velocities[i] if len(r[1].command_velocities) ==
                                 len(axes) else 0.0 for r in readings])
                    for i, a in enumerate(axes)},
        temperatures=temperatures,
        uncertainty_m=DEFAULT_POSITION_UNCERTAINTY_M)
    obs.uncertainty_m, note = stated_uncertainty([r[1].uncertainty for r in readings],
                                                 DEFAULT_POSITION_UNCERTAINTY_M,
                                                 "reference readings", "m")
    notes = sensor_notes + ([note] if note else [])
    if all(len(getattr(r[1], "command_directions", [])) == len(axes) for r in readings):
        obs.directions = {a: np.array([r[1].command_directions[i] or
                                       np.sign(obs.velocities[a][k])
                                       for k, r in enumerate(readings)], dtype=float)
                          for i, a in enumerate(axes)}
    # An R-test's tool direction: a second measured quantity, fitted beside the tip.
    note = obs.set_directions([machine_direction_error(r[1]) for r in readings],
                              [getattr(r[1], "orientation_uncertainty", 0.0) for r in readings])
    notes += [note] if note else []
    targets = [target_point(r[1]) for r in readings]
    if any(t is not None for t in targets):
        if kinematics is None:
            raise InputDataError(f"{bag}: readings with a target_point need the model's chain")
        obs.work_point = work_points(kinematics, obs.positions, targets)
    return obs, stamps, sorted(profiles, key=lambda p: p[0]), notes


def sampled_temperatures(temps: list[tuple[int, list[str], np.ndarray]], stamps: np.ndarray
                         ) -> dict[str, np.ndarray]:
    """Each sensor's temperature [degC] at the reference readings' ``stamps`` [ns].

    Linear between the ``/temperatures`` messages (stamp [ns], sensor names, readings
    [degC]) around a stamp; NaN where the message nearest the stamp gave no reading (a
    gap stays a gap for the sensors' judge, and a sensor with no reading at all is
    judged dead, not dropped unsaid). The sensors are the last message's."""
    if not temps:
        return {}
    temps = sorted(temps, key=lambda t: t[0])
    at = stamps.astype(np.float64)
    t_stamps = np.array([t[0] for t in temps], dtype=np.float64)
    first_after = np.searchsorted(t_stamps, at)
    after = np.minimum(first_after, t_stamps.size - 1)
    before = np.maximum(first_after - 1, 0)
    nearest = np.where(np.abs(t_stamps[after] - at) <= np.abs(t_stamps[before] - at),
                       after, before)
    out = {}
    for j, name in enumerate(temps[-1][1]):
        values = np.array([t[2][j] if j < len(t[2]) else np.nan for t in temps])
        ok = np.isfinite(values)
        sampled = np.interp(at, t_stamps[ok], values[ok]) if ok.any() else \
            np.full(at.size, np.nan)
        sampled[~ok[nearest]] = np.nan
        out[name] = sampled
    return out


def judge_bag_sensors(temperatures: dict[str, np.ndarray], stamps: np.ndarray,
                      prefix: str = "") -> tuple[np.ndarray, list[str]]:
    """(the reference readings kept (N,), one note per finding): the bag's temperatures,
    as sampled at the readings, judged by the one rule of logs and surveys
    (:func:`~..core.inputs.sensor_health.judge_sensors`). A sensor mostly bad (dead,
    stuck, jumping ...) is left out of every model (``temperatures`` loses it); a few bad
    readings leave out those reference readings. Findings name the reference readings
    by index (1-based, in stamp order); the first note says so, with reading 1's stamp."""
    from ..core.inputs.sensor_health import judge_sensors

    keep = np.ones(stamps.size, dtype=bool)
    if not temperatures:
        return keep, []
    health = judge_sensors(temperatures, np.arange(1, stamps.size + 1), row_label="reading")
    for name in list(temperatures):
        if name in health.kept:
            temperatures[name] = health.kept[name]
        else:
            del temperatures[name]
    if not health.findings:
        return keep, []
    bad = health.rows_left_out
    if bad.size:
        keep = ~bad
    notes = [f"temperature sensors judged at the {stamps.size} reference readings "
             f"({prefix}/reference/tcp_error, numbered 1.. in stamp order; reading 1 at "
             f"stamp {int(stamps[0])} ns), the temperatures sampled at their stamps"]
    notes += health.notes
    if not keep.all():
        notes.append(f"{int((~keep).sum())} reference readings with a bad sensor reading "
                     "left out (see the notes above)")
    return keep, notes


def judge_survey_sensors(survey) -> list[str]:
    """The survey's temperature columns judged by the one rule of logs and bags
    (:func:`~..core.inputs.sensor_health.judge_sensors`): a sensor mostly bad is left out
    of every model, a few bad rows leave out those rows (counted in the survey's dropped
    rows, as a log's are). Findings name the file's rows (the header is row 1). One note
    per finding."""
    from ..core.inputs.sensor_health import judge_sensors

    if not survey.temperatures:
        return []
    health = judge_sensors(survey.temperatures, survey.file_rows, survey.run_of_row,
                           survey.run_names, row_label="file row")
    survey.temperatures = health.kept
    bad = health.rows_left_out
    if bad.size and bad.any():
        survey.without_rows(bad, f"{int(bad.sum())} with a bad sensor reading (see the notes)")
    return health.notes


def predict_with_history(model, obs, stamps, profiles, delay_ns: int = 500_000_000,
                         refused: dict | None = None):
    """Model prediction at each reading with the profiles live at that time (like the monitor).

    A recorded profile the model refuses (a wrong length, an axis it does not have) is left
    out of the predictions and, with ``refused`` given, recorded there: (stamp, name) ->
    the reason."""
    import copy

    position = np.zeros((obs.n, 3))
    orientation = np.zeros((obs.n, 3))
    state = copy.deepcopy(model)
    state._lag_states = {}   # lagged effects start in steady state at the first reading
    next_profile = 0
    group_start = 0
    for i in range(obs.n + 1):
        limit = stamps[i] - delay_ns if i < obs.n else None
        due = i < obs.n and next_profile < len(profiles) and profiles[next_profile][0] <= limit
        if due or i == obs.n:
            if i > group_start:
                rows = np.arange(group_start, i)
                sub = obs.subset(rows)
                p, o = state.tcp_error(sub.positions, **sub.model_inputs())
                position[rows], orientation[rows] = p, o
            group_start = i
            while i < obs.n and next_profile < len(profiles) and profiles[next_profile][0] <= limit:
                stamp, name, x, y, difference = profiles[next_profile]
                try:
                    state.apply_profile(name, x, y, difference)
                except MtAccuracyError as exc:
                    if refused is not None:
                        refused[(stamp, name)] = str(exc)
                next_profile += 1
    return position, orientation


def candidate_named(diagnosis, name: str, why: str, where: str):
    """The candidate ``name`` of a diagnosis, or a one-line error saying why it cannot be
    ``why``-ed (not a candidate in this ``where``, or refused by physics)."""
    from ..core.workbench.diagnosis import pick_candidate

    candidate = pick_candidate(diagnosis, name)
    if candidate is None:
        raise InputDataError(f"cannot {why} {name}: not a candidate here (in the model "
                             f"already, unknown, or no regressors in this {where})")
    if candidate.refusal:
        raise InputDataError(f"cannot {why} {candidate.name}: physics refuses its fit "
                             f"({candidate.refusal})")
    return candidate


def check_observations(model, obs, add: list[str], auto: int, min_reduction: float,
                       predict=None, blocks=None, *, kind: str, data: str) -> CheckResult:
    """The workbench loop on observations: diagnose, add what is asked or named, again.

    ``predict(model)`` -> (position (N, 3), orientation (N, 3)) predictions made
    elsewhere (a bag's profile history), or None for the model itself. ``--auto N``
    adds up to N of the effects the forward selection names (jointly fitted),
    ``add`` the named ones first. ``kind`` and ``data`` name what was read (the caller
    adds its :class:`~.check_result.DataSource`).
    """
    from ..core.workbench.diagnosis import add_effect, add_effects, diagnose, residuals
    from ..core.workbench.context_memo import ContextMemo
    from ..core.workbench.localisation import LocalisationMemo

    # What the named effects leave is localised in the first look and again in the look
    # at the model with them added: one localisation serves both. Both looks see the
    # readings through the same chain: one context (and its designs) serves both.
    localisations, contexts = LocalisationMemo(), ContextMemo()
    started = time.perf_counter()
    for sensor, values in obs.temperatures.items():
        model.reference_temperatures_c.setdefault(sensor, float(values[0]))

    steps: list[ModelStep] = []
    step_residuals = []

    def evaluate(current, first_look: bool = False):
        if predict is not None:
            obs.predicted_m, obs.predicted_orientation = predict(current)
        # Each model's residual once: kept for the report, and what the look fits.
        step_residuals.append(residuals(current, obs))
        # Pairs of effects hiding each other are sought in the first look only: after
        # the named effects are added, what they leave is judged one effect at a time.
        return diagnose(current, obs, min_reduction=min_reduction, blocks=blocks,
                        folds=5 if blocks is None else int(blocks[-1]) + 1,
                        pair_lookahead=first_look, localisations=localisations,
                        contexts=contexts, residual=step_residuals[-1])

    diagnosis = evaluate(model, first_look=True)
    first = diagnosis
    queue = list(add)
    while True:
        steps.append(ModelStep(model.version, sorted(model.effects), diagnosis.baseline_rmse,
                               diagnosis.text()))
        added_so_far = sum(len(s.added or []) for s in steps)
        if queue:
            chosen = [candidate_named(diagnosis, queue.pop(0), "add", "data")]
        elif auto and diagnosis.selected and added_so_far < auto:
            chosen = diagnosis.selected[:auto - added_so_far]
        else:
            break
        model = add_effects(model, chosen, obs) if len(chosen) > 1 else \
            add_effect(model, chosen[0], obs)
        steps[-1].record_added(chosen)
        diagnosis = evaluate(model)
    # The model did not change after the last residual was taken.
    residual_before, residual = step_residuals[0], step_residuals[-1]
    searched = time.perf_counter() - started
    result = CheckResult(
        kind=kind, data=data, machine=model.machine.name, readings=obs.n,
        band=obs.uncertainty_m, baseline_rmse=first.baseline_rmse,
        baseline_cv_rmse=first.baseline_cv_rmse,
        ranking=[c.as_dict() for c in first.ranking[:30]],
        named=[c.as_dict() for c in first.selected], verdict=first.verdict(),
        localisation=first.localisation.as_dict() if first.localisation else {},
        added=[name for s in steps for name in s.added or []],
        final_rmse=diagnosis.baseline_rmse, steps=steps, final_diagnosis=diagnosis.text(),
        final_verdict=diagnosis.verdict(), model_yaml=_model_yaml(model),
        figures_before_m=error_figures(residual_before), figures_after_m=error_figures(residual),
        dropped=first.dropped,
        final_localisation=diagnosis.localisation.as_dict() if diagnosis.localisation else {},
        plot={"time": obs.time_s, "positions": obs.positions,
              "residual_before": residual_before, "residual_after": residual,
              "temperatures": obs.temperatures, "measured": obs.measured_m,
              "mask": obs.measured_mask, "step_residuals": step_residuals,
              "velocities": obs.velocities, "directions": obs.directions,
              "model": model, "localisation": first.localisation})
    result.seconds["search"] = searched
    return result


def _model_yaml(model) -> str:
    import yaml

    from ..core.compensation.error_model import model_to_dict

    return yaml.safe_dump(model_to_dict(model), sort_keys=False)


def check_bag(bag: Path, model_text: str, add: list[str], auto: int, namespace: str,
              min_reduction: float) -> CheckResult:
    """A bag of this package's topics (``reference/tcp_error`` readings, temperatures,
    ``systematic/<axis>`` profiles) against the model ``model_text`` (bundled name, path
    or inline YAML), the profiles applied as the monitor applied them."""
    from ..core.compensation.error_model import resolve_model

    model = resolve_model(model_text)  # a bad model is refused before a long bag is read
    obs, stamps, profiles, notes = observations_from_bag(bag, namespace, model.kinematics)
    refused: dict = {}
    result = check_observations(model, obs, add, auto, min_reduction,
                                lambda current: predict_with_history(current, obs, stamps,
                                                                     profiles, refused=refused),
                                kind="bag", data=str(bag))
    warnings = list(notes)
    if refused:
        (_, name), why = next(iter(refused.items()))
        warnings.append(f"{len(refused)} of {len(profiles)} recorded profiles could not be "
                        f"applied and were left out of the predictions (the first, {name}: "
                        f"{why})")
    result.warnings = warnings or None
    result.source = DataSource(namespace=namespace, sensors_kept=sorted(obs.temperatures))
    return result


def survey_model(survey, model_text: str | None, machine: str | None,
                 tool_offset_m: float | None = None, work_axes: tuple[str, ...] = (),
                 setup_axes: tuple[str, ...] = ()):
    """The model a survey is checked against, and a note on the machine it assumes
    (``setup_axes``: the rotary axes whose set-up the column map gives).

    ``model_text`` (a model names its machine), else ``machine`` (a bundled name or a
    machine YAML) with no effects, else a generic Cartesian machine whose strokes are
    the travel the readings cover and whose tool is ``tool_offset_m`` long (the column
    map's ``tool_offset``: the Abbe arm of angular errors; :func:`generic_cartesian`).
    """
    from ..core.compensation.error_model import ErrorModel, resolve_model
    from ..core.kinematics.machine import generic_cartesian, load_machine

    if model_text is not None and machine is not None:
        raise InputDataError("give --model or --machine, not both: a model names its machine")
    if model_text is not None or machine is not None:
        # The map's set-up replaces the machine file's: an impossible one there is said,
        # not refused (the survey's own is what the readings were located at).
        model = resolve_model(model_text) if model_text is not None else \
            ErrorModel(load_machine(machine, {a: "the column map's setup_pose"
                                              for a in setup_axes}), {})
        refuse_contradicting_work_axes(model.machine, work_axes)
        return model, ""
    travel = {axis: (float(np.min(q)), float(np.max(q))) for axis, q in survey.positions.items()
              if axis in "XYZ" and q.size}
    model = ErrorModel(generic_cartesian(travel, tool_length_m=tool_offset_m or 0.0,
                                         work_axes=work_axes), {})
    spans = ", ".join(f"{a} {low * 1e3:.1f}..{high * 1e3:.1f} mm" for a, (low, high) in
                      travel.items())
    arm = (f"the tool {tool_offset_m * 1e3:.1f} mm long (the map's tool_offset)"
           if tool_offset_m else "a tilt's arm along the tool, which the map does not give "
           "(tool_offset), fitted (angular_arm)")
    layout = (f"the workpiece on {', '.join(work_axes)} (bed outwards), the tool on the rest"
              if work_axes else "every axis on the tool side (give the map's work_axes)")
    return model, (f"machine: none given (--machine): a generic Cartesian machine over the "
                   f"surveyed travel ({spans}), {layout}; angular errors act through the "
                   f"other axes' positions and {arm}")


def survey_machine(flag: str | None, mapped: str | None, model_text: str | None) -> str | None:
    """The machine a survey names: ``--machine`` or the column map's ``machine:`` (the same
    one when both are given; a model names its own)."""
    if mapped is None:
        return flag
    if model_text is not None:
        raise InputDataError("the column map names a machine and --model names one too: "
                             "leave the map's machine: out, or give --machine instead of --model")
    if flag is not None and Path(flag).resolve() != Path(mapped).resolve() and flag != mapped:
        raise InputDataError(f"--machine {flag} contradicts the column map's machine: "
                             f"{mapped}: give one")
    return mapped


def refuse_rotary_without_machine(positions: dict, machine) -> None:
    """One line when the survey has rotary columns its machine has no axes for (a generic
    Cartesian machine knows no rotary axis: its A and C would be dropped)."""
    rotary = [a for a in positions if a in "ABC"]
    missing = [a for a in rotary if a not in machine.axes]
    if missing:
        raise InputDataError(
            f"the survey has rotary position columns ({', '.join(missing)}) that "
            f"{machine.name} has no axis for: describe the machine (--machine FILE.yaml or "
            "the map's machine:) - its chain says where the rotary axes are")


def survey_targets(survey, column_map, machine):
    """The readings' target in the workpiece frame: the map's fixed ``target_point``,
    per-row ``target.x/y/z`` columns, or None (the machining point). A survey gives its
    sphere as a CNC program does, in work coordinates: from the work offset (the
    machine's ``workpiece`` point), along the workpiece frame's axes."""
    if survey.targets:
        return np.column_stack([survey.targets[c] for c in "xyz"]) + machine.workpiece
    if column_map.target_point_m is None:
        return None
    return column_map.target_point_m + machine.workpiece


def setup_note(machine) -> str:
    """What the check assumed about where the work was set up ("" without rotary axes)."""
    rotary = [a for a in machine.axis_order if machine.axes[a].is_rotary]
    if not rotary:
        return ""
    pose = ", ".join(f"{a} = {np.degrees(machine.setup_angle(a)):g} deg" for a in rotary)
    given = "the column map's or the machine's setup_pose" if machine.setup_pose else \
        "no setup_pose given: every rotary axis at 0"
    notes = "".join(f"; {note}" for note in machine.setup_notes)
    return (f"set-up pose {pose} ({given}): the rotary axes turn about their actual lines "
            f"from there, so the zero-angle error of each side's last rotary axis is taken "
            f"out by the set-up; an outer axis' zero turns the lines it carries (ISO 230-7) "
            f"and is said with them{notes}")


def in_package_convention(measured, mask, direction_errors: dict, convention, machine,
                          positions) -> tuple[np.ndarray, dict, str]:
    """A survey's errors turned into the package's convention: the tool relative to the
    work, actual minus nominal, along the machine's axes.

    Parameters
    ----------
    measured : ndarray, shape (N, 3)
        The error columns as read [m] (0 where ``mask`` is False).
    mask : ndarray of bool, shape (N, 3)
        Which components the survey measured.
    direction_errors : dict of str to ndarray, shape (N,)
        The tool direction's change per component [rad] (may be empty).
    convention : ErrorConvention
        What the columns mean (the column map's ``error_convention``).
    machine : MachineDescription
        The machine whose nominal chain gives a turning frame's orientation (and the
        set-up pose, for ``aligned_at: setup``).
    positions : dict of str to ndarray, shape (N,)
        Axis commands [m, rad].

    Returns
    -------
    tuple of (ndarray, shape (N, 3); dict; str)
        The errors [m], the direction changes [rad], and the sentence saying how they were
        read.
    """
    measured = convention.sign * measured
    directions = {c: convention.sign * v for c, v in direction_errors.items()}
    if convention.frame == "machine":
        return measured, directions, convention.note()
    missing = [c for c in "xyz" if not mask[:, "xyz".index(c)].all()]
    missing_directions = [c for c in "xyz" if directions and c not in directions]
    if missing or missing_directions:
        what = "error" if missing else "direction_errors"
        raise InputDataError(
            f"error_convention: frame: {convention.frame} needs all three {what} components "
            f"(missing {', '.join(missing or missing_directions)}): a turning frame's "
            "components mix along the machine's axes")
    rotation = frame_rotation(machine, positions, convention)
    measured = np.einsum("nij,nj->ni", rotation, measured)
    if directions:
        change = np.column_stack([directions[c] for c in "xyz"])
        turned = np.einsum("nij,nj->ni", rotation, change)
        directions = {c: turned[:, k] for k, c in enumerate("xyz")}
    return measured, directions, convention.note()


def frame_rotation(machine, positions, convention) -> np.ndarray:
    """(N, 3, 3) R with machine axes = R @ the instrument's axes, for an instrument that
    turns with the work (``frame: work``) or the spindle (``frame: tool``), on the
    nominal chain; its axes are the machine's at every rotary axis at 0, or at the set-up
    pose (``aligned_at: setup``: R = R(q) R(q_setup)^T)."""
    from ..core.kinematics.chain import KinematicModel

    branch = {"work": "workpiece", "tool": "tool"}[convention.frame]
    chain = KinematicModel(machine)
    rotation = chain.branch(branch, positions, errors=False, check_stroke=False)[:, :3, :3]
    if convention.aligned_at == "setup":
        at_setup = {a: np.full(1, machine.setup_angle(a) if machine.axes[a].is_rotary else 0.0)
                    for a in machine.axis_order}
        aligned = chain.branch(branch, at_setup, errors=False, check_stroke=False)[0, :3, :3]
        rotation = rotation @ aligned.T
    return rotation


def with_tool_direction(obs, direction_errors: dict, machine) -> str:
    """Put a two-sphere R-test's tool-direction readings into ``obs`` and say so.

    A reading is the change du of the tool axis' unit vector relative to the work
    (machine frame); the workbench's orientation is the rotation vector across the tool
    axis, theta = u x du (du = theta x u for theta across u).
    """
    from ..core.kinematics.chain import KinematicModel

    missing = [c for c in "xyz" if c not in direction_errors]
    if missing:
        raise InputDataError(f"direction_errors: give all three components (missing "
                             f"{', '.join(missing)}): the change of the tool axis' unit vector")
    change = np.column_stack([direction_errors[c] for c in "xyz"])
    axis = KinematicModel(machine).tool_axis(obs.positions)
    along = np.abs(np.einsum("nc,nc->n", change, axis))
    if np.any(along > 1e-3):
        row = int(np.argmax(along))
        raise InputDataError(f"direction_errors: reading {row + 1} changes the tool direction "
                             f"along the tool axis by {along[row]:.3g} - not a small change of a "
                             "unit vector (check the unit: urad?)")
    obs.measured_orientation_rad = np.cross(axis, change)
    obs.orientation_measured = np.ones(obs.n, dtype=bool)
    return (f"tool direction: {obs.n} readings of the tool axis' change (across the tool "
            f"axis), judged with a k = 2 uncertainty of "
            f"{obs.orientation_uncertainty_rad * 1e6:.1f} urad (assumed: the documented "
            "default; a column map does not state the direction's uncertainty)")


def refuse_contradicting_work_axes(machine, work_axes: tuple[str, ...]) -> None:
    """One line (InputDataError) when a column map's ``work_axes`` are not the given
    machine's axes that carry the workpiece (its chain says which they are)."""
    if not work_axes:
        return
    carried = tuple(a for a in machine.workpiece_branch if not machine.axes[a].is_rotary)
    if tuple(work_axes) != carried:
        raise InputDataError(
            f"the column map's work_axes [{', '.join(work_axes)}] contradict {machine.name}, "
            f"whose chain {machine.chain} puts the workpiece on "
            f"[{', '.join(carried) or 'no linear axis'}] (bed outwards): correct the map or "
            "leave work_axes out")


def arm_verdicts(named: list[dict], tool_offset_m: float | None) -> tuple[list[str], str]:
    """What the named ``angular_arm`` effects say about the tool offset.

    Returns (notes, refusal): a note per tilt whose arm was fitted, and a one-line
    refusal when the map gave a tool offset the data contradict, naming the value the
    data support. A tilt's arm reaches from its pivot to the tool tip, so one tilt whose
    arm differs from the map's tool offset (by more than 3 standard uncertainties and
    5 mm) says its pivot lies that far from the carriage's reference - or that the
    offset is wrong: the readings cannot tell (the difference moves the tool as a
    straightness of that axis would), and a note says both. The data contradict the
    offset only when two or more tilts, whose pivots are unrelated, agree on one other
    tool tip. The tool points along +z for a positive or absent offset.
    """
    from ..core.effects.geometric import AngularWithArm

    notes, away = [], []
    given = tool_offset_m or 0.0
    along_z = -1.0 if given < 0 else 1.0
    supported_tools: list[tuple[str, float, float]] = []
    for entry in named:
        if entry.get("effect") != "angular_arm":
            continue
        values = entry["parameters"]
        shape = [values[k] for k in values if not k.startswith("arm_")]
        arm = [values[k] for k in values if k.startswith("arm_")]
        extra = AngularWithArm.arm_m(shape + arm)
        # l = <a, b> / <a, a>: its standard uncertainty from the b's (dl/db_k = a_k / |a|^2)
        spread = entry.get("parameter_uncertainties", {})
        weights = np.asarray(shape, dtype=np.float64) / max(float(np.dot(shape, shape)), 1e-300)
        sigma = float(np.sqrt(np.sum((weights * np.array(
            [spread.get(k, 0.0) for k in values if k.startswith("arm_")])) ** 2)))
        supported = given + along_z * extra
        supported_tools.append((entry["variant"], supported, sigma))
        if tool_offset_m is None:
            notes.append(f"{entry['name']}: the tilt acts through {extra * 1e3:+.1f} "
                         f"± {2e3 * sigma:.1f} mm of arm along the tool beyond the surveyed "
                         f"axes' (k = 2): a tool offset of {supported * 1e3:.1f} mm; give it "
                         "as the map's tool_offset and the tilt is named with its arm known")
        elif abs(extra) > max(3.0 * sigma, 5e-3):
            away.append((entry["variant"], supported, sigma))
            notes.append(f"{entry['name']}: the tilt acts through an arm that puts the tool "
                         f"tip at {supported * 1e3:.1f} ± {2e3 * sigma:.1f} mm (k = 2), "
                         f"{extra * 1e3:+.1f} mm from the map's tool_offset "
                         f"{given * 1e3:.1f} mm: its pivot lies that far from the carriage's "
                         "reference, or the tool_offset is wrong (the readings cannot tell: "
                         "the difference moves the tool as a straightness of the axis would);"
                         " the map's tool_offset is kept")
        else:
            notes.append(f"{entry['name']}: its arm agrees with the map's tool_offset within "
                         f"{abs(extra) * 1e3:.1f} mm")
    refusal = contradicted_tool_offset(away, given)
    notes += one_tool_for_the_stack(supported_tools)
    return notes, refusal


def contradicted_tool_offset(away: list[tuple[str, float, float]], given_m: float) -> str:
    """A one-line refusal when two or more tilts whose arms miss the map's tool offset
    ((variant, tool tip [m], its standard uncertainty [m]) each) agree on one other tool
    tip, naming it; "" otherwise (one tilt's arm may as well say where its pivot is)."""
    if len(away) < 2:
        return ""
    tips = np.array([tip for _, tip, _ in away])
    sigmas = np.array([max(sigma, 1e-6) for _, _, sigma in away])
    mean = float(np.sum(tips / sigmas ** 2) / np.sum(1.0 / sigmas ** 2))
    sigma_mean = float(np.sqrt(1.0 / np.sum(1.0 / sigmas ** 2)))
    if not np.all(np.abs(tips - mean) <= np.maximum(3.0 * sigmas, 5e-3)):
        return ""
    names = ", ".join(variant for variant, _, _ in away)
    return (f"the column map's tool_offset {given_m * 1e3:.1f} mm contradicts the data: the "
            f"tilts {names} act through arms that agree on a tool tip at {mean * 1e3:.1f} ± "
            f"{2e3 * sigma_mean:.1f} mm (k = 2); correct the map's tool_offset")


def one_tool_for_the_stack(supported: list[tuple[str, float, float]]) -> list[str]:
    """The tilts of one stack act through one tool: a line saying whether the tool tips
    their arms put it at agree ((variant, tool tip [m], its standard uncertainty [m]))."""
    if len(supported) < 2:
        return []
    values = np.array([v for _, v, _ in supported])
    sigmas = np.array([max(s, 1e-6) for _, _, s in supported])
    mean = float(np.sum(values / sigmas ** 2) / np.sum(1.0 / sigmas ** 2))
    names = ", ".join(f"{n} {v * 1e3:.1f} mm" for n, v, _ in supported)
    if np.all(np.abs(values - mean) <= np.maximum(3.0 * sigmas, 5e-3)):
        return [f"the tilts of one stack agree on one tool: its tip at {mean * 1e3:.1f} mm "
                f"({names})"]
    return [f"warning: the tilts of one stack put the tool tip at different heights ({names}):"
            " one tool cannot serve both - a tilt is named with a stand-in, or the layout "
            "(work_axes) is not the machine's"]


def outside_travel(machine, positions: dict, tolerance_m: float = 1e-6) -> str:
    """One warning line when readings lie outside ``machine``'s strokes ("" if none do)."""
    parts, outside, units = [], np.zeros(0, dtype=bool), []
    for axis, q in positions.items():
        if axis not in machine.axes or not np.size(q):
            continue
        low, high = machine.axes[axis].stroke
        beyond = (q < low - tolerance_m) | (q > high + tolerance_m)
        outside = beyond if outside.size == 0 else (outside | beyond)
        if beyond.any():
            rotary = machine.axes[axis].is_rotary
            scale, unit = (180.0 / np.pi, "deg") if rotary else (1e3, "mm")
            parts.append(f"{axis} {np.min(q) * scale:.4g}..{np.max(q) * scale:.4g} {unit} "
                         f"against its {low * scale:.4g}..{high * scale:.4g}")
            as_degrees = np.radians(q)
            if rotary and as_degrees.min() >= low - 1e-6 and as_degrees.max() <= high + 1e-6:
                units.append(f"the {axis} column looks like degrees declared as rad")
    if not parts:
        return ""
    mend = "; ".join(units) + " - declare its unit" if units else \
        ("its strokes and Abbe arms may not be this machine's - check the position columns' "
         "units, or give the machine the survey was taken on (--machine), or none for a "
         "generic one from the data")
    return (f"warning: {int(outside.sum())} of {outside.size} readings lie outside "
            f"{machine.name}'s travel ({'; '.join(parts)}): {mend}")


def check_mapped_csv(path: Path, column_map, model_text: str | None, add: list[str],
                     auto: int, min_reduction: float, machine: str | None = None
                     ) -> CheckResult:
    """A data logger's CSV of reference readings (column map) against a model (or a
    machine, or a generic Cartesian machine from the survey: :func:`survey_model`)."""
    from ..core.kinematics.machine import with_setup_pose
    from ..core.workbench.diagnosis import Observations
    from ..io.column_map import read_mapped_csv

    survey = read_mapped_csv(path, column_map)
    sensor_notes = judge_survey_sensors(survey)
    machine = survey_machine(machine, column_map.machine, model_text)
    model, machine_note = survey_model(survey, model_text, machine, column_map.tool_offset_m,
                                       column_map.work_axes, tuple(column_map.setup_pose))
    refuse_rotary_without_machine(survey.positions, model.machine)
    model = model.with_machine(with_setup_pose(model.machine, column_map.setup_pose,
                                               "the column map's setup_pose"))
    n = survey.time_s.size
    missing = [a for a in model.machine.axis_order if a not in survey.positions]
    if missing:
        raise InputDataError(f"{path}: the model's machine {model.machine.name} has axis "
                             f"{', '.join(missing)} with no position column (pos."
                             f"{missing[0]}=COLUMN)")
    measured = np.zeros((n, 3))
    mask = np.zeros((n, 3), dtype=bool)
    for c, component in enumerate("xyz"):
        if component in survey.errors:
            measured[:, c] = survey.errors[component]
            mask[:, c] = True
    measured, direction_errors, convention_note = in_package_convention(
        measured, mask, survey.direction_errors, column_map.error_convention, model.machine,
        survey.positions)
    obs = Observations(survey.positions, measured, mask, survey.time_s, survey.velocities,
                       survey.temperatures, column_map.uncertainty_m,
                       directions=survey.directions, accelerations=survey.accelerations,
                       spindle_speed_rad_s=survey.spindle_speed_rad_s,
                       run_of_row=survey.run_of_row,
                       work_point=survey_targets(survey, column_map, model.machine))
    instrument_notes = [setup_note(model.machine), convention_note]
    if direction_errors:
        instrument_notes.append(with_tool_direction(obs, direction_errors, model.machine))
    warning = outside_travel(model.machine, survey.positions)
    blocks = None
    if survey.run_of_row is not None:
        from ..core.workbench.log_runs import run_blocks

        # Whole runs are the folds (at most 5): a run is never cut between fit and judge.
        blocks = run_blocks(survey.run_of_row, 5)
        if blocks is not None and blocks[-1] < 2:
            blocks = None      # two runs cannot cross-validate a selection
    result = check_observations(model, obs, add, auto, min_reduction, blocks=blocks,
                                kind="survey_csv", data=str(path))
    if survey.run_names is not None:
        result.runs = [RunFigures(name, int(np.sum(survey.run_of_row == k)))
                       for k, name in enumerate(survey.run_names)]
        result.validation = "by whole runs" if blocks is not None else \
            "time blocks (fewer than three runs)"
    # Printed and in the JSON's warnings (None: the JSON has none to say).
    warnings = None
    if not model.machine.abbe_arms_known:
        warnings, refusal = arm_verdicts(result.named, column_map.tool_offset_m)
        if refusal:
            raise InputDataError(f"{path}: {refusal}")
    if column_map.uncertainty_note():
        # Said as the bag path says its default.
        warnings = [column_map.uncertainty_note(), *(warnings or [])]
    if sensor_notes:
        # In the warnings (the bag's way), and apart as sensor_notes.
        warnings = [*(warnings or []), *sensor_notes]
    result.warnings = warnings
    result.source = DataSource(
        rows_read=survey.rows_read, rows_dropped=survey.rows_dropped,
        rows_note=survey.summary(Path(path).name), namespace="",
        machine_note="; ".join(n for n in [machine_note, *instrument_notes] if n),
        setup_pose_rad=dict(model.machine.setup_pose),
        error_convention=column_map.error_convention.as_dict(), travel_warning=warning,
        sensors_kept=sorted(survey.temperatures), sensor_notes=sensor_notes or None)
    return result


# ------------------------------------------------------------------ thermal log path
def _column_and_unit(flag: str, names: list[str], quantity: str, what: str,
                     units: dict[str, str] | None = None) -> tuple[str, float, str]:
    """``COLUMN[:UNIT]`` -> (column, SI scale, unit); the unit from the flag, else from a
    units row under the header (``units``), else the column's name (``ch5_um``,
    ``dial [µm]``, ``spindle_rpm``)."""
    from ..io.column_map import UNIT_SPELLINGS, UNITS, column_unit

    column, unit = (flag.rsplit(":", 1) + [""])[:2] if ":" in flag else (flag, "")
    column, unit = column.strip(), unit.strip()
    if column not in names:
        raise InputDataError(f"no {what} column {column!r}; have {', '.join(names)}")
    table = UNITS[quantity]
    known = ", ".join(u for u in table if u)
    if unit and UNIT_SPELLINGS.get(unit, unit) not in table:
        raise InputDataError(f"{what} {column!r}: unknown {quantity} unit {unit!r}; known: "
                             f"{known}")
    unit = UNIT_SPELLINGS.get(unit, unit) or column_unit(column, quantity, units)
    if not unit:
        raise InputDataError(f"{what} {column!r}: give its unit as {column}:UNIT (one of "
                             f"{known}); none could be read off its name")
    return column, float(table[unit]), unit


# ------------------------------------------------------------------ report
def write_outputs(result: CheckResult, json_path: str | None, report_path: str | None) -> None:
    """The report (HTML beside its plots) and the JSON summary of ``result``, each when a
    path is given; the JSON carries the report's content too (same sections, tables)."""
    if report_path:
        from ..report import write_check_report

        result.report = write_check_report(result, Path(report_path)).as_dict()
    if json_path:
        Path(json_path).parent.mkdir(parents=True, exist_ok=True)
        Path(json_path).write_text(json.dumps(result.to_json(), indent=2, default=float))


# ------------------------------------------------------------------ the command line
#: What ``check`` reads: a bag, a thermal log (a CSV with --target) or a survey (a CSV
#: with a column map), as the refusals name them.
CHECK_DATA_KINDS = {"bag": "a bag", "log": "a thermal log (a CSV with --target)",
                    "survey": "a survey (a CSV with a column map: --columns or --col)"}
#: Each data-specific option of ``check`` (its argparse name), as typed, and the kinds of
#: data whose reader takes it; given with any other it would be ignored, so it is refused.
CHECK_OPTION_SCOPES = {
    "model": ("--model", ("bag", "survey")), "namespace": ("--namespace", ("bag",)),
    "machine": ("--machine", ("survey",)), "columns": ("--columns", ("survey",)),
    "col": ("--col", ("survey",)), "uncertainty_um": ("--uncertainty-um", ("log", "survey")),
    "row_period": ("--row-period", ("log", "survey")),
    "time_column": ("--time-column", ("log",)), "target": ("--target", ("log",)),
    "inputs": ("--inputs", ("log",)), "driver": ("--driver", ("log",)),
    "term": ("--term", ("log",)), "component": ("--component", ("log",)),
    "structure_length": ("--structure-length", ("log",)),
    "train_fraction": ("--train-fraction", ("log",)), "run": ("--run", ("log",)),
    "zeroed_runs": ("--zeroed-runs", ("log",)), "walk_forward": ("--walk-forward", ("log",))}
#: Suffixes of table files; other text files are tables too, unless they are descriptions.
TABLE_SUFFIXES = (".csv", ".tsv", ".txt", ".dat")
DESCRIPTION_SUFFIXES = (".yaml", ".yml", ".json", ".xml", ".html")
#: Defaults of the thermal log's options (None in the parser: given or not is known).
LOG_TIME_COLUMN, LOG_TRAIN_FRACTION, LOG_COMPONENT = "time_s", 0.5, "z"


def _is_table(path: Path) -> bool:
    """Whether ``check`` reads ``path`` as a CSV table (by its suffix, or a text file that
    is no description) rather than a bag."""
    from ..core.inputs.file_kinds import MCAP_MAGIC, looks_like_text, read_head

    suffix = path.suffix.lower()
    if suffix in TABLE_SUFFIXES:
        return True
    if suffix in DESCRIPTION_SUFFIXES or not path.is_file():
        return False
    try:
        head = read_head(path)
    except OSError:
        return False
    return not head.startswith(MCAP_MAGIC) and looks_like_text(head)


def data_kind(args) -> str:
    """What ``check``'s DATA is: "bag", "log" or "survey" (:data:`CHECK_DATA_KINDS`)."""
    if not _is_table(Path(args.data)):
        return "bag"
    return "survey" if args.columns or args.col else "log"


def validate_check(args) -> None:
    """Every option of ``check`` before any work: the options of the data's kind only, in
    range, a thermal log's by its own rule, the outputs; a bag's files are MCAP."""
    from ..core.errors import ParameterError
    from ..core.inputs.options import in_range, not_applicable
    from ..io.output_paths import Output, check_outputs

    kind = data_kind(args)
    if kind == "log" and not args.target:
        raise ParameterError("a CSV needs --target COLUMN (a thermal log) or a column map "
                             "(--columns FILE.yaml or --col ROLE=COLUMN[:UNIT]) for a "
                             "reference survey")
    for name, (flag, kinds) in CHECK_OPTION_SCOPES.items():
        if kind not in kinds and getattr(args, name) not in (None, False, "", []):
            raise not_applicable(flag, " or ".join(CHECK_DATA_KINDS[k] for k in kinds),
                                 CHECK_DATA_KINDS[kind])
    if kind == "log":
        from .check_log import validate_log_options

        # The thermal log's own rule (one implementation), before any row is read.
        validate_log_options(args.auto, LOG_TRAIN_FRACTION if args.train_fraction is None
                             else args.train_fraction)
        if args.zeroed_runs and not args.run:
            raise ParameterError("--zeroed-runs needs --run COLUMN (the instrument was zeroed "
                                 "at each run's start)")
        if args.walk_forward:
            from ..core.workbench.walk_forward import parse_period

            parse_period(args.walk_forward)
    in_range("--auto", args.auto, low=0, what="an integer")
    in_range("--min-reduction", args.min_reduction, low=0, high=1, high_open=True,
             what="a fraction")
    in_range("--uncertainty-um", args.uncertainty_um, low=0, low_open=True, unit="um, k = 2")
    if args.uncertainty_um is not None:
        from ..core.inputs.plausibility import check_plausible

        check_plausible(np.array([args.uncertainty_um]), "uncertainty", "um", "--uncertainty-um",
                        mend="the flag is in micrometres")
    in_range("--row-period", args.row_period, low=0, low_open=True, unit="s")
    in_range("--structure-length", args.structure_length, low=0, low_open=True, unit="m")
    check_outputs([Output("--json", args.json), Output("--report", args.report)],
                  [args.data, args.columns])
    if kind == "bag" and Path(args.data).exists():
        from ..io.bag_reader import mcap_files

        mcap_files(args.data)       # a truncated or foreign bag: refused before the model


def _column_map(args):
    """The survey's column map from --columns and --col."""
    import yaml

    from ..io.column_map import ColumnMap, column_map_from_dict, parse_col_flags

    column_map = ColumnMap()
    if args.columns:
        try:
            text = Path(args.columns).read_text()
            column_map = column_map_from_dict(yaml.safe_load(text), args.columns)
        except (OSError, yaml.YAMLError) as exc:
            raise InputDataError(f"column map {args.columns}: {exc}") from exc
    column_map = parse_col_flags(args.col or [], column_map)
    if args.uncertainty_um is not None:
        column_map.uncertainty_m = args.uncertainty_um * 1e-6
    if args.row_period is not None:
        column_map.row_period_s = args.row_period
    return column_map


def check_data(args) -> CheckResult:
    """``check``'s result of its DATA, by kind (the options checked by
    :func:`validate_check`)."""
    from . import check_log

    data = Path(args.data)
    kind = data_kind(args)
    if kind == "survey":
        return check_mapped_csv(data, _column_map(args), args.model, args.add or [], args.auto,
                                args.min_reduction, machine=args.machine)
    if kind == "log":
        return check_log.check_csv(
            data, args.target, args.time_column or LOG_TIME_COLUMN, args.inputs or ["*"],
            args.driver or [], args.add or [], args.auto,
            LOG_TRAIN_FRACTION if args.train_fraction is None else args.train_fraction,
            args.min_reduction, args.term or [], row_period_s=args.row_period,
            component=args.component or LOG_COMPONENT,
            uncertainty_m=None if args.uncertainty_um is None else args.uncertainty_um * 1e-6,
            structure_length_m=args.structure_length, run_column=args.run,
            zeroed_runs=args.zeroed_runs, walk_forward_period=args.walk_forward,
            progress=_progress_line)
    return check_bag(data, args.model or "demo", args.add or [], args.auto,
                     args.namespace or "", args.min_reduction)


def _progress_line(line: str) -> None:
    """A long job's progress, on stderr (stdout holds the result)."""
    print(line, file=sys.stderr, flush=True)


def check_command(args) -> int:
    """Check the data, write the report and the JSON, print the result's lines."""
    from .check_result import printed_lines

    result = check_data(args)
    write_outputs(result, args.json, args.report)
    for line in printed_lines(result):
        print(line)
    return 0


def add_parser(commands) -> None:
    """``check`` on the subcommands ``commands``."""
    check = commands.add_parser("check", help="model vs measurement: rank missing effects, "
                                "add them")
    check.add_argument("data", help="bag (this package's topics) or CSV file")
    check.add_argument("--model", default=None,
                       help="model: bundled name, path or inline YAML (default: 'demo' for a "
                            "bag; for a survey, none - see --machine)")
    check.add_argument("--machine", default=None,
                       help="survey CSV: the machine it was taken on, a bundled name or a "
                            "machine YAML (default: a generic Cartesian machine over the "
                            "surveyed travel); readings outside its travel are warned about")
    check.add_argument("--add", action="append", metavar="EFFECT", help="add this effect (repeat)")
    check.add_argument("--auto", type=int, default=0, metavar="N",
                       help="add up to N top significant candidates by themselves")
    check.add_argument("--report", help="HTML report path")
    check.add_argument("--json", help="JSON summary path")
    check.add_argument("--namespace", default=None, help="bag: machine namespace in the bag "
                       "(/mt1)")
    check.add_argument("--min-reduction", type=float, default=0.05,
                       help="smallest CV error reduction that counts")
    check.add_argument("--columns", metavar="FILE.yaml",
                       help="CSV survey: column map (which column is which axis, error, "
                            "temperature, and its unit)")
    check.add_argument("--col", action="append", metavar="ROLE=COLUMN[:UNIT]",
                       help="CSV survey: one column of the map, e.g. pos.X=x_mm:mm, err.x=dev:um, "
                            "temp.column=T3:degC, time=t:min, vel.X=f:mm/min, spindle=S:rpm")
    check.add_argument("--uncertainty-um", type=float, default=None,
                       help="CSV survey: the instrument's k = 2 uncertainty [um]")
    check.add_argument("--row-period", type=float, default=None,
                       help="CSV survey without a time column: seconds between rows")
    _add_log_options(check)
    check.set_defaults(handler=check_command, validate=validate_check)


def _add_log_options(check) -> None:
    """The thermal log's options of ``check``."""
    check.add_argument("--time-column", default=None,
                       help=f"CSV log: time column [s] (default {LOG_TIME_COLUMN})")
    check.add_argument("--target", metavar="COLUMN[:UNIT]",
                       help="CSV log: the measured displacement column (unit from the flag or "
                            "the name's suffix, e.g. ch5_um)")
    check.add_argument("--inputs", nargs="+", help="CSV log: temperature columns [degC] "
                       "(names or patterns)")
    check.add_argument("--driver", nargs="+", metavar="COLUMN[:UNIT]",
                       help="CSV log: the spindle speed (rpm, rad/s, Hz), a heat source")
    check.add_argument("--term", action="append",
                       help="CSV log: effects the starting model holds (fitted first)")
    check.add_argument("--component", default=None, choices=["x", "y", "z"],
                       help="CSV log: the direction the target displacement is measured in "
                            f"(default {LOG_COMPONENT})")
    check.add_argument("--structure-length", type=float, default=None, metavar="METRES",
                       help="CSV log: structure between the sensors and the tool (bounds a "
                            "physical thermal gain; default 1 m)")
    check.add_argument("--train-fraction", type=float, default=None,
                       help="CSV log: fit on this leading fraction, judge on the rest (with "
                            f"--run: at the run boundary nearest it; default "
                            f"{LOG_TRAIN_FRACTION})")
    check.add_argument("--run", metavar="COLUMN",
                       help="CSV log of many runs: rows of one run share this column's value "
                            "(time restarts or jumps between runs; lags restart each run; "
                            "whole runs judge one another)")
    check.add_argument("--walk-forward", metavar="PERIOD",
                       help="CSV log: also replay it in time - at each PERIOD's end (4h, "
                            "30min, 900s, or 'run') the model is made again from every row so "
                            "far and judged on the next period, beside a constant, least "
                            "squares on every input and no model")
    check.add_argument("--zeroed-runs", action="store_true",
                       help="CSV log with --run: the instrument was zeroed at each run's "
                            "start (each run has its own zero; default: absolute readings)")
