"""A fitted rotary line's offsets and tilts, and a tilt's pivot lever, reach the CNC's
volumetric file; an effect no file can hold is said, never left out silently."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.cnc_export import (carried_effects, read_isg_csv,
                                                          write_isg_csv)
from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.compensation.tables import machine_with_table
from mt_accuracy_ros.core.effects.geometric import lever_line_offsets
from mt_accuracy_ros.core.kinematics.chain import KinematicModel
from mt_accuracy_ros.core.kinematics.machine import load_machine

from conftest import REPO_ROOT

LINES = {"rotary_location:AC": {
    "family": "rotary_location", "variant": "AC", "setting": {},
    "coefficients": {"EY0A": 20e-6, "EZ0A": -10e-6, "EB0A": 40e-6, "EC0A": -30e-6,
                     "EX0C": 15e-6, "EY0C": -25e-6, "EA0C": 30e-6, "EB0C": -20e-6}}}
LEVER = {"angular:EBX": {
    "family": "angular", "variant": "EBX",
    "setting": {"order": 1, "constant": True, "located": True, "lever": True},
    "coefficients": {"P1": 20e-6, "P0": 10e-6, "lever_x": 30e-6, "lever_z": -20e-6}}}
# A rotary axis' own error motion (an axial run-out of A with its angle): no per-axis table
# of a linear axis, nor the location block, holds it.
RUN_OUT = {"rotary_error:EZA": {"family": "rotary_error", "variant": "EZA",
                                "setting": {"harmonics": 1},
                                "coefficients": {"cos1": 5e-6, "sin1": -3e-6}}}


def _poses(machine, n=300, seed=3):
    rng = np.random.default_rng(seed)
    return {a: rng.uniform(*machine.axes[a].stroke, n) for a in machine.axis_order}


def _through_file(model, q):
    applied = machine_with_table(model.machine, read_isg_csv(write_isg_csv(model, 0.01)))
    return KinematicModel(applied).tcp_error(q, check_stroke=False)["position"]


def test_a_fitted_rotary_lines_errors_are_the_files_location_block():
    model = ErrorModel(load_machine("trunnion_ac"), dict(LINES))
    text = write_isg_csv(model, 0.01)
    lines = text.splitlines()
    names = lines[lines.index("// location errors (constant)") + 1].split()
    values = dict(zip(names, map(float, lines[lines.index("// location errors (constant)")
                                              + 2].split())))
    # Offsets in mm, tilts in urad (the file's units).
    assert values == pytest.approx({"EY0A": 0.020, "EZ0A": -0.010, "EB0A": 40.0,
                                    "EC0A": -30.0, "EX0C": 0.015, "EY0C": -0.025,
                                    "EA0C": 30.0, "EB0C": -20.0}, rel=1e-12)


def test_the_file_applied_through_the_chain_is_the_models_prediction_of_the_lines():
    """Two formulations: the catalogue's design (the workbench's) against the described
    chain turning each body about its actual line from the set-up pose (ISO 230-7)."""
    model = ErrorModel(load_machine("trunnion_ac"), dict(LINES))
    q = _poses(model.machine)
    predicted = model.tcp_error(q, referred=False)[0]
    assert np.sqrt(np.mean(np.sum(predicted ** 2, axis=1))) > 10e-6   # something to carry
    # First order (the catalogue) against exact (the chain): they part only in the second
    # order, so the gap is small and falls with the square of the errors.
    gap = np.abs(_through_file(model, q) - predicted).max()
    assert gap < 2e-8
    tenth = {name: {**entry, "coefficients": {k: 0.1 * v for k, v in
                                              entry["coefficients"].items()}}
             for name, entry in LINES.items()}
    small = ErrorModel(model.machine, tenth)
    small_gap = np.abs(_through_file(small, q) - small.tcp_error(q, referred=False)[0]).max()
    assert small_gap < 0.02 * gap


def test_a_tilts_pivot_lever_goes_in_as_the_carried_lines_offsets():
    model = ErrorModel(load_machine("trunnion_ac"), dict(LEVER))
    # X carries A (along x) and C (along z): the lever's z is A's EZ0A, its x is C's EX0C.
    assert model.location_table() == pytest.approx({"EZ0A": -20e-6, "EX0C": 30e-6})
    assert model.location_table() == lever_line_offsets(
        model.machine, "EBX", {"lever_x": 30e-6, "lever_z": -20e-6})
    q = _poses(model.machine)
    np.testing.assert_allclose(_through_file(model, q), model.tcp_error(q, referred=False)[0],
                               atol=2e-8, rtol=0)


def test_what_the_file_carries_is_judged_effect_by_effect():
    model = ErrorModel(load_machine("trunnion_ac"), {**LINES, **LEVER, **RUN_OUT})
    judged = {c.name: c for c in carried_effects(model, 0.01)}
    assert set(judged) == {"rotary_location:AC", "angular:EBX", "rotary_error:EZA"}
    assert judged["rotary_location:AC"].carried and judged["angular:EBX"].carried
    assert judged["rotary_location:AC"].gap_rms_m < 1e-3 * judged["rotary_location:AC"].model_rms_m
    run_out = judged["rotary_error:EZA"]
    assert not run_out.carried
    # Left out whole: the file leaves all of it.
    assert run_out.gap_rms_m == pytest.approx(run_out.model_rms_m, rel=1e-9)
    assert run_out.model_rms_m > 1e-6


def test_a_fitted_line_beside_the_descriptions_own_is_carried():
    """The description's EX0C (50 um) and a fitted one (20 um) sum in the file (70 um); the
    fitted effect is judged carried, not compared against the description's."""
    machine = load_machine("trunnion_ac")
    axes = dict(machine.axes)
    axes["C"] = replace(axes["C"], location_errors={"X": 50e-6})
    described = replace(machine, axes=axes)
    fitted = {"rotary_location:C": {"family": "rotary_location", "variant": "C",
                                    "setting": {}, "coefficients": {"EX0C": 20e-6, "EY0C": 0.0,
                                                                    "EA0C": 0.0, "EB0C": 0.0}}}
    model = ErrorModel(described, {"geometric": {}, **fitted})
    assert model.location_table()["EX0C"] == pytest.approx(70e-6)
    (judged,) = carried_effects(model, 0.01)
    assert judged.carried and judged.gap_rms_m < 1e-3 * judged.model_rms_m


def test_a_surveys_set_up_is_no_machine_effect_to_carry():
    model = ErrorModel(load_machine("trunnion_ac"), {
        "setup_location:work": {"family": "setup_location", "variant": "work", "setting": {},
                                "coefficients": {"v_x": 10e-6, "v_y": -8e-6, "v_z": 5e-6}},
        **LINES})
    assert [c.name for c in carried_effects(model, 0.01)] == ["rotary_location:AC"]


def test_an_outer_axis_set_up_off_zero_is_read_otherwise_by_the_check_and_said(tmp_path,
                                                                               capsys):
    """A set up at -30 deg: the chain turns A's body from there, the model reads A's line
    as a located instrument does (the raw turn, the part's set-up error turning with the
    work); they part once C leaves its set-up, so the check reports a gap for A's line and
    says why, while C's line (the last axis) agrees."""
    import yaml

    from mt_accuracy_ros.cli import main

    machine = load_machine("trunnion_ac")
    moved = replace(machine, setup_pose={"A": np.radians(-30.0), "C": 0.0})
    a_only = {name: {**entry, "coefficients": {k: (v if k[3] == "A" else 0.0)
                                              for k, v in entry["coefficients"].items()}}
              for name, entry in LINES.items()}
    c_only = {name: {**entry, "coefficients": {k: (v if k[3] == "C" else 0.0)
                                              for k, v in entry["coefficients"].items()}}
              for name, entry in LINES.items()}
    (outer,) = carried_effects(ErrorModel(moved, a_only), 0.01)
    (inner,) = carried_effects(ErrorModel(moved, c_only), 0.01)
    assert not outer.carried and inner.carried
    text = yaml.safe_load((REPO_ROOT / "mt_accuracy_ros" / "machines" / "trunnion_ac.yaml")
                          .read_text())
    text["setup_pose"] = {"A": {"value": -30.0, "unit": "deg"}, "C": {"value": 0.0,
                                                                      "unit": "deg"}}
    (tmp_path / "m.yaml").write_text(yaml.safe_dump(text))
    (tmp_path / "model.yaml").write_text(yaml.safe_dump(
        {"machine": str(tmp_path / "m.yaml"), "effects": a_only}))
    assert main(["export", str(tmp_path / "model.yaml"), "--out", str(tmp_path / "t")]) == 0
    said = capsys.readouterr().out
    assert "rotary_location:AC" in said and "A = -30 deg" in said and "ISO 230-7" in said
