"""``mt-accuracy check``'s typed result, rendered three ways from one object.

A thermal log's and a survey's result are built here by hand, with figures whose printed
and reported forms are known: the printed lines, the report's sections and the JSON each
read the same fields, and a sentence both the printed lines and the report say is made
once (the same words in both).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from mt_accuracy_ros.commands.check_result import (
    JSON_KEYS, OPTIONAL_KEYS, SCHEMA_VERSION, CheckResult, ContestEntry, DataSource,
    ModelStep, NotAdded, RunFigures, ThermalLog, as_paragraph, printed_lines, readings_text,
    weights_sentence)

NAMED = {"effect": "structural_thermal_drift", "variant": "t1_C",
         "name": "structural_thermal_drift:t1_C", "setting_display": "tau 5 min",
         "display": {"bz": "2.0 ± 0.1 µm/K"}, "cv_rmse_after": 1.5e-6, "error_reduction": 0.5,
         "significant": True, "confidence": 0.99, "share_of_excess": 0.8,
         "explanation": "the structure grows as it warms", "setting": {"tau_s": 300.0},
         "parameters": {"bz": 2e-6}, "parameter_uncertainties": {"bz": 5e-8}, "refusal": ""}


def _log_result() -> CheckResult:
    """Three runs of a log in micrometres: the step-by-step model beat one rival."""
    n = 12
    log = ThermalLog(
        target="dz_um", target_unit="um", target_unit_per_m=1e6, component="z", rows=n,
        train_rows=8, decided_on="the training rows only", figures_before_held_out_m={},
        figures_after_held_out_m={}, held_out_baseline_rmse=4e-6,
        not_added=[NotAdded("thermal_lag:t2_C", 0.3, "predicting run r2", 2e-6, 2.5e-6)],
        not_added_lines=["not added: thermal_lag:t2_C (CV 30 % better) - predicting run r2"],
        constant_held_out_rmse=5e-6, notes=["units from the row under the header"],
        step_by_step_added=[NAMED["name"]],
        model_contest_forward_rmse={"step by step": 1e-6, "sensor_least_squares:t1_C": 2e-6},
        model_chosen="step by step",
        model_contest=[ContestEntry("step by step", [NAMED["name"]], 1e-6,
                                    [{"trained_rows": 4, "judged_rows": 4, "rmse": 1e-6}],
                                    1.2e-6, True),
                       ContestEntry("sensor_least_squares:t1_C", ["sensor_least_squares:t1_C"],
                                    2e-6, [{"trained_rows": 4, "judged_rows": 4, "rmse": 2e-6}],
                                    2.2e-6, False)],
        judged_on="held-out rows", all_inputs_least_squares_held_out_rmse=3e-6,
        baselines_held_out_m={"constant": 5e-6, "least squares on every input": 3e-6,
                              "model": 1.2e-6},
        sensors_carrying_weight={"t1_C": 0.75, "t2_C": 0.25},
        sensors_carrying_weight_of={"words": "the model sensor_least_squares over 2 sensors"},
        zeroed_runs=False)
    steps = [ModelStep(1, [], 4e-6, "a residual", 4e-6, 3e-6, 2e-6),
             ModelStep(2, [NAMED["name"]], 1e-6, "nothing left", 1.2e-6, 1e-6, 1e-6)]
    steps[0].added, steps[0].parameters = [NAMED["name"]], {NAMED["name"]: {"bz": 2e-6}}
    steps[0].parameter_uncertainties = {NAMED["name"]: {"bz": 5e-8}}
    time = np.arange(n) * 600.0
    target = np.linspace(0, 8e-6, n)
    return CheckResult(
        kind="thermal_log", data="log.csv", machine="generic", readings=n, band=1e-6,
        baseline_rmse=4e-6, baseline_cv_rmse=3e-6, ranking=[NAMED], named=[NAMED],
        verdict="what is left is noise", localisation={"sentence": "in z, with t1_C"},
        added=[NAMED["name"]], final_rmse=1.2e-6, steps=steps, final_diagnosis="noise",
        final_verdict="noise", model_yaml="effects: {}\n",
        source=DataSource(rows_read=n, rows_dropped=0, rows_note="log.csv: 12 of 12 rows used"),
        log=log, warnings=["warning: least squares on every input (3 um) beats a constant"],
        runs=[RunFigures(f"r{k}", 4, "training" if k < 2 else "held out", 5e-6, 3e-6, 1e-6)
              for k in range(3)],
        validation="forward by whole runs",
        plot={"time": time, "target": target, "before": target * 0.5, "after": target * 0.9,
              "train": np.arange(n) < 8, "unit_scale": 1e6, "unit": "um",
              "run_starts": np.array([0, 4, 8]), "run_names": ["r0", "r1", "r2"]})


def test_a_sentence_the_printed_lines_and_the_report_share_is_made_once(tmp_path):
    """The sensors a sensor model leans on, and a named effect's readings: the printed
    line and the report's paragraph or cell hold the same words, from one function."""
    from mt_accuracy_ros.report.sections import csv_report_sections

    result = _log_result()
    lines = printed_lines(result)
    sentence = "the model sensor_least_squares over 2 sensors leans on: t1_C 75 %, t2_C 25 %"
    assert weights_sentence(result.log) == sentence and sentence in lines
    readings = "bz = 2.0 ± 0.1 µm/K"
    assert readings_text(NAMED) == readings
    assert f"       {readings} (U, k = 2); tau 5 min" in lines
    sections = {s.title: s for s in csv_report_sections(result, tmp_path, "r")}
    headline = sections["Headline"].paragraphs
    assert "The model sensor_least_squares over 2 sensors leans on: t1_C 75 %, t2_C 25 % " \
        "(share of its spread)." in headline
    # Every warning printed is a sentence of the headline, the same words.
    assert result.warnings[0] in lines
    assert as_paragraph(result.warnings[0]) in headline
    # The named effect's row: the readings printed, and its explanation.
    (named,) = [t for t in sections["Where the residual lives"].tables
                if t.columns[0] == "effect named"]
    cells = [c.text for c in named.rows[0].cells]
    assert readings in cells and NAMED["explanation"] in cells


def test_the_printed_lines_of_a_thermal_log_in_its_unit():
    """Each figure in the target's unit (um), from the result's own fields, in order."""
    lines = printed_lines(_log_result())
    assert lines[:4] == ["log.csv: 12 of 12 rows used",
                         "warning: least squares on every input (3 um) beats a constant",
                         "not added: thermal_lag:t2_C (CV 30 % better) - predicting run r2",
                         "note: units from the row under the header"]
    assert "held-out RMSE (rows after the first 8) 4 um; a constant's 5 um; least squares " \
        "on every input 3 um" in lines
    assert f"  * {'step by step (' + NAMED['name'] + ')':60s} 1 -> 1.2 um" in lines
    assert "  run           r2 (held out, 4 rows): constant 5, least squares 3, model 1 um " \
        "RMS" in lines
    assert "baseline RMSE 4 um" in lines
    assert f" * {NAMED['name']:60s} CV RMSE after 1.5 um (50.0 %)" in lines
    assert "where: in z, with t1_C" in lines and "verdict: what is left is noise" in lines
    assert lines[-1] == f"added: {NAMED['name']}; final held-out RMSE 1.2 um"


def test_the_json_is_the_typed_result_with_its_schema_version():
    """The JSON is the documented key set of its kind, in order, the result's own values
    (nested dataclasses as objects, their empty fields left out); the result reads as it."""
    result = _log_result()
    summary = result.to_json()
    # Without --walk-forward its key is left out (nothing to say).
    assert list(summary) == ["schema_version", *[k for k in JSON_KEYS["thermal_log"]
                                                 if k != "walk_forward"]]
    assert summary["schema_version"] == SCHEMA_VERSION == 1
    assert summary["final_rmse"] == 1.2e-6 and summary["target_unit"] == "um"
    assert summary["steps"][1] == {"model_version": 2, "effects": [NAMED["name"]],
                                   "rmse": 1e-6, "diagnosis": "nothing left",
                                   "held_out_rmse": 1.2e-6, "cv_rmse": 1e-6,
                                   "validation_rmse": 1e-6}
    assert summary["steps"][0]["added"] == [NAMED["name"]]
    assert summary["not_added"][0] == {"name": "thermal_lag:t2_C", "cv_reduction": 0.3,
                                       "test": "predicting run r2", "before": 2e-6,
                                       "after": 2.5e-6}
    assert "plot" not in summary and "report" not in summary
    json.dumps(summary)                                 # nothing but JSON in it
    assert dict(result) == summary and result["model_chosen"] == "step by step"
    result.report = {"title": "t"}
    assert list(result.to_json())[-1] == "report"


def test_a_survey_leaves_out_what_it_has_nothing_to_say_about():
    """A survey without runs, warnings or sensor findings writes none of those keys (its
    summary before the schema was versioned did not either); the rest are always there."""
    result = CheckResult(
        kind="survey_csv", data="s.csv", machine="kidani_hmc", readings=3, band=1e-6,
        baseline_rmse=2e-6, baseline_cv_rmse=2e-6, ranking=[], named=[], verdict="",
        localisation={}, added=[], final_rmse=2e-6, steps=[ModelStep(1, [], 2e-6, "")],
        final_diagnosis="", final_verdict="", model_yaml="",
        source=DataSource(rows_read=3, rows_dropped=0, rows_note="", namespace="",
                          machine_note="", setup_pose_rad={}, travel_warning="",
                          sensors_kept=[]),
        figures_before_m={}, figures_after_m={}, dropped=[], final_localisation={})
    keys = list(result.to_json())
    absent = [k for k in JSON_KEYS["survey_csv"] if k not in keys]
    assert sorted(absent) == sorted(OPTIONAL_KEYS["survey_csv"])
    result.warnings = []                  # said, though empty: a generic machine's arms
    assert "warnings" in result.to_json()
    assert printed_lines(result) == ["baseline RMSE 2 um", "added: nothing; final RMSE 2 um"]


def test_a_key_of_no_field_is_refused():
    with pytest.raises(KeyError):
        _log_result()["no_such_key"]
