"""CNC compensation export: per-axis bilateral tables and the ISG-CSV-style volumetric file,
written, read back, applied, and compared with the model (issue 20)."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.cnc_export import (bilateral_tables, read_bilateral_csv,
                                                          read_isg_csv, round_trip, table_grid,
                                                          write_bilateral_csv, write_isg_csv)
from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.errors import MachineDescriptionError, ParameterError
from mt_accuracy_ros.core.kinematics.machine import machine_from_dict
import yaml

from conftest import REPO_ROOT


def _model() -> ErrorModel:
    """The HMC with smooth geometric errors, a squareness, a 10 mm ball-screw pitch error
    (a catalogue effect) and 6 um of X backlash."""
    data = yaml.safe_load((REPO_ROOT / "mt_accuracy_ros" / "machines" / "kidani_hmc.yaml")
                          .read_text())
    data["axes"]["X"]["errors"] = {"EXX": {"polynomial": [0.0, 2e-5, -4e-5]},
                                   "ECX": {"polynomial": [0.0, 3e-5, 0.0, -8e-5]},
                                   "EYX": {"polynomial": [1e-6, 0.0, 1.5e-5]}}
    data["axes"]["Y"]["errors"] = {"EYY": {"polynomial": [0.0, -1e-5]},
                                   "EAY": {"polynomial": [0.0, 0.0, 4e-5]}}
    data["axes"]["Y"]["location_errors"] = {"EC0Y": 12e-6}
    machine = machine_from_dict(data)
    return ErrorModel(machine, {
        "geometric": {},
        "positioning_periodic:EXX": {"family": "positioning_periodic", "variant": "EXX",
                                     "setting": {"period_m": 0.01},
                                     "coefficients": {"cos1": 1e-6, "sin1": 2e-6,
                                                      "cos2": 0.0, "sin2": 0.0}},
        "reversal": {"backlash_m": 6e-6, "axes": ["X"]}})


def test_grid_has_the_spacing_and_ends_at_the_stroke():
    grid = table_grid((0.0, 0.6), 0.025, "X")
    assert grid[0] == 0.0 and grid[-1] == 0.6 and np.allclose(np.diff(grid), 0.025)
    odd = table_grid((0.0, 0.61), 0.025, "X")
    assert odd[-1] == 0.61 and odd[-2] == pytest.approx(0.6)
    with pytest.raises(ParameterError, match="exceeds the X stroke"):
        table_grid((0.0, 0.6), 0.7, "X")
    with pytest.raises(ParameterError, match="positive"):
        table_grid((0.0, 0.6), 0.0, "X")


def test_bilateral_table_round_trips_and_carries_the_reversal():
    model = _model()
    tables = bilateral_tables(model, 0.001)
    x = tables["X"]
    np.testing.assert_allclose(x.reverse["EXX"] - x.forward["EXX"], 6e-6, atol=1e-15)
    np.testing.assert_allclose(x.forward["EYX"], x.reverse["EYX"])
    text = write_bilateral_csv(x, model.machine.name)
    assert text.splitlines()[5].startswith("position_mm,EXX_forward,EXX_reverse")
    back = read_bilateral_csv(text)
    np.testing.assert_allclose(back.positions_m, x.positions_m, atol=1e-15)
    for name in x.forward:
        np.testing.assert_allclose(back.forward[name], x.forward[name], rtol=1e-11, atol=1e-18)
        np.testing.assert_allclose(back.reverse[name], x.reverse[name], rtol=1e-11, atol=1e-18)


def test_volumetric_file_is_isg_csv_style_and_reads_back():
    model = _model()
    text = write_isg_csv(model, 0.02)
    lines = [line for line in text.splitlines() if line and not line.startswith("//")]
    assert lines[0].split() == ["EC0Y"] and float(lines[1]) == pytest.approx(12.0)   # urad
    headers = [lines[i + 1].split() for i, line in enumerate(lines) if line == "#"]
    assert ["X", "EXX", "EYX", "EZX", "EAX", "EBX", "ECX"] in headers and len(headers) == 3
    back = read_isg_csv(text)
    assert back.location == pytest.approx({"EC0Y": 12e-6})
    assert set(back.grids) == {"X", "Y", "Z"}
    with pytest.raises(MachineDescriptionError, match="rows must have"):
        read_isg_csv(text.replace("\n0 ", "\n0 1 ", 1))


@pytest.mark.parametrize("spacing_m", [0.002, 0.001])
def test_applied_tables_match_the_model_within_the_interpolation_error(spacing_m):
    """Each column within h^2/8 max|f''| of the model; the TCP through the CNC's chain
    within the columns' bounds carried through their Abbe arms."""
    result = round_trip(_model(), spacing_m, points=1500)
    for name, error in result.column_max_error.items():
        assert error <= result.column_bound[name] * 1.001 + 1e-12, (name, error)
    assert result.tcp_max_error_m <= result.tcp_bound_m
    assert result.tcp_rms_error_m < 0.05 * result.tcp_model_rms_m


def test_the_round_trip_error_falls_with_the_square_of_the_spacing():
    coarse = round_trip(_model(), 0.002, points=1500)
    fine = round_trip(_model(), 0.001, points=1500)
    assert fine.column_max_error["EXX"] == pytest.approx(coarse.column_max_error["EXX"] / 4,
                                                         rel=0.35)


def test_a_rotary_axis_location_error_reaches_the_cnc_through_the_volumetric_file():
    """A five-axis machine: the rotary axis has no table, its location error (an A tilt)
    is in the file's location block and applied by the CNC's chain."""
    from mt_accuracy_ros.core.compensation.tables import machine_with_table
    from mt_accuracy_ros.core.kinematics.machine import load_machine

    model = ErrorModel(load_machine("khan_chen_rpppr"),
                       {"squareness": {"errors_rad": {"EB0A": 20e-6, "EC0Y": 5e-6}}})
    read = read_isg_csv(write_isg_csv(model, 0.05))
    assert read.machine == "khan_chen_rpppr" and set(read.grids) == {"X", "Y", "Z"}
    applied = machine_with_table(model.machine, read)
    assert applied.axes["A"].location_errors == pytest.approx({"B": 20e-6})
    result = round_trip(model, 0.05, points=500)
    assert result.tcp_model_rms_m > 1e-6 and result.tcp_max_error_m < 1e-12


def _user_model(expression: str, acts_on: str, k: float = 1e-3):
    from mt_accuracy_ros.core.compensation.error_model import resolve_model

    return resolve_model(f"{{machine: kidani_hmc, effects: {{mine: {{expression: '{expression}',"
                         f" parameters: [k], acts_on: {acts_on}, values: {{k: {k:.6e}}}}}}}}}")


@pytest.mark.parametrize("expression, acts_on, table, column, values", [
    ("k * x", "x", "X", "EXX", lambda q: 1e-3 * q),
    ("k * x", "X", "X", "EXX", lambda q: 1e-3 * q),
    ("k * y * y", "z", "Y", "EZY", lambda q: 1e-3 * q * q),
])
def test_user_effects_of_one_position_go_into_the_tables(expression, acts_on, table, column,
                                                         values):
    """Issue 29: a user effect reaches the controller. The tables hold its error motion
    (up to the sign the axis' branch gives), and the round trip - read back, applied
    through the chain - matches the model *with* the user effect, computed from its
    expression, not from the tables."""
    from mt_accuracy_ros.core.compensation.cnc_export import round_trip

    model = _user_model(expression, acts_on)
    tables = bilateral_tables(model, 0.005)
    written = tables[table].forward[column]
    assert np.max(np.abs(written)) > 1e-5, "the user effect is not in the table"
    expected = values(tables[table].positions_m)
    sign = np.sign(written[np.argmax(np.abs(written))] * expected[np.argmax(np.abs(expected))])
    np.testing.assert_allclose(written, sign * expected, rtol=1e-9, atol=1e-15)
    others = [name for t in tables.values() for name, v in t.forward.items()
              if np.any(v) and name != column]
    assert others == []
    check = round_trip(model, 0.005)
    assert check.tcp_model_rms_m > 1e-5           # the reference holds the user effect
    assert check.tcp_max_error_m < 1e-8
    # Had the tables left it out, the round trip would see the whole effect.
    bare = ErrorModel(model.machine, {})
    applied = round_trip(bare, 0.005)
    assert applied.tcp_model_rms_m < 1e-9


def test_a_user_effect_no_table_can_hold_is_refused_and_a_thermal_one_stays_real_time():
    from mt_accuracy_ros.core.compensation.cnc_export import write_isg_csv

    twisted = _user_model("k * x * y", "x")
    with pytest.raises(ParameterError, match="user effect 'mine' depends on 2 axes"):
        bilateral_tables(twisted, 0.005)
    with pytest.raises(ParameterError, match="export refused"):
        write_isg_csv(twisted, 0.005)
    thermal = _user_model("k * T_bed", "x", 1e-6)
    tables = bilateral_tables(thermal, 0.005)
    assert not any(np.any(v) for t in tables.values() for v in t.forward.values())
