"""Hidden-effect trials of the open catalogue on data from :mod:`studies.foreign_machine`.

One trial: a survey of a bundled machine with hidden effects drawn from the
foreign generator; the starting model is the nominal machine (nothing
known); the workbench diagnoses, adds what it names, and is judged against
the noise-free truth:

* named first: the first effect added is one of the names the hidden effect
  may fairly be given (``Hidden.accepted``);
* localised: the variable that explains most of the residual, or one the data
  cannot rank below it (within half a point of its share; how many there were is
  kept as ``tied_variables``), is one the hidden effect lives in
  (``Hidden.variables``);
* removed: 1 - RMS(truth - what the added effects predict) / RMS(truth);
* a false alarm: anything added when nothing is hidden.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.kinematics.machine import load_machine
from mt_accuracy_ros.core.workbench.diagnosis import Observations, add_effects, diagnose
from studies.foreign_machine import Trial, make_trial


def observations(trial: Trial) -> Observations:
    survey = trial.survey
    return Observations(dict(survey.positions), trial.measured_m,
                        np.ones_like(trial.measured_m, dtype=bool), survey.time_s,
                        dict(survey.velocities), dict(survey.temperatures),
                        2.0 * trial.noise_m, directions=dict(survey.directions),
                        accelerations=dict(survey.accelerations),
                        spindle_speed_rad_s=survey.spindle_speed_rad_s)


@dataclass
class Outcome:
    machine: str
    kinds: tuple[str, ...]
    seed: int
    magnitudes_um: list[float]
    found: list[str]
    named_first: bool
    all_named: bool
    localised: bool
    top_variable: str
    tied_variables: int
    top_right: bool
    rms_before_um: float
    rms_after_um: float
    removed: float
    false_alarm: bool
    sentence: str
    text: str


def _rms(error: np.ndarray) -> float:
    centred = error - error.mean(axis=0)
    return float(np.sqrt(np.mean(np.sum(centred ** 2, axis=1))))


def run_trial(machine: str, kinds: tuple[str, ...], seed: int, **kwargs) -> Outcome:
    trial = make_trial(machine, kinds, seed, **kwargs)
    obs = observations(trial)
    model = ErrorModel(load_machine(machine), {})
    diagnosis = diagnose(model, obs)
    after = add_effects(model, diagnosis.selected, obs)
    predicted = after.tcp_error(obs.positions, **obs.model_inputs(), fresh=True)[0] - \
        model.tcp_error(obs.positions, **obs.model_inputs(), fresh=True)[0]
    before = _rms(trial.truth_m)
    remaining = _rms(trial.truth_m - predicted)
    found = [c.name for c in diagnosis.selected]
    first_ok = bool(found) and bool(kinds) and found[0] in trial.hidden[0].accepted | \
        set().union(*(h.accepted for h in trial.hidden))
    all_named = all(any(f in h.accepted for f in found) for h in trial.hidden)
    # Localisation is judged on the residual before anything is added.
    from mt_accuracy_ros.core.workbench.localisation import localise
    from mt_accuracy_ros.core.effects import Context
    from mt_accuracy_ros.core.workbench.diagnosis import residuals

    variables = obs.variables(model.reference_temperatures_c)
    ctx = Context(model.machine, variables, model._kinematics)
    where = localise(residuals(model, obs), obs.measured_mask, variables,
                     ctx.structure_sensors(), obs.uncertainty_m / 2,
                     {a: model.machine.axes[a].stroke for a in model.machine.axis_order})
    top = where.top().variable if where.top() else ""
    group = {s.variable for s in where.top_group()}
    wanted = set().union(*(h.variables for h in trial.hidden)) if trial.hidden else set()
    return Outcome(machine, tuple(kinds), seed, [m * 1e6 for m in trial.magnitudes_m], found,
                   first_ok, all_named, bool(group & wanted), top, len(group), top in wanted,
                   before * 1e6,
                   remaining * 1e6,
                   1.0 - remaining / before if before > 0 else 0.0,
                   bool(found) and not kinds, where.sentence(), diagnosis.text())
