"""CNC tables on a machine whose tables carry the workpiece (the bundled VMC): a table
axis' angular error enters its table and reaches the tool through the arm to the
machining point. Written, read back and applied, the tables are judged against the
virtual machine's own rigid-body truth (sim.rigid_body), not against the chain that
wrote them."""
from __future__ import annotations

import numpy as np
import yaml

from mt_accuracy_ros.core.compensation.cnc_export import (bilateral_tables, read_bilateral_csv,
                                                          read_isg_csv, round_trip,
                                                          write_bilateral_csv, write_isg_csv)
from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.compensation.tables import machine_with_table
from mt_accuracy_ros.core.kinematics.chain import KinematicModel
from mt_accuracy_ros.core.kinematics.machine import machine_from_dict
from mt_accuracy_ros.sim.rigid_body import BodyErrors, tool_against_work

from conftest import REPO_ROOT

#: Table pitch and saddle roll [rad] as polynomials in the axis' position [m]
#: (coefficients of q^0, q^1, ...), and a head tilt for contrast.
TILTS = {"X": {"EBX": [0.0, 4e-5, 0.0, -2e-4]}, "Y": {"EAY": [0.0, -5e-5, 3e-4]},
         "Z": {"EBZ": [0.0, 2e-5]}}


def _machine():
    data = yaml.safe_load((REPO_ROOT / "mt_accuracy_ros" / "machines" / "vmc.yaml").read_text())
    for axis, errors in TILTS.items():
        data["axes"][axis]["errors"] = {name: {"polynomial": coefficients}
                                        for name, coefficients in errors.items()}
    data["axes"]["Y"]["location_errors"] = {"EC0Y": 10e-6}
    return machine_from_dict(data)


def _truth(q):
    """The tilts as the virtual machine's rigid bodies carry them (no kinematic chain)."""
    n = q["X"].size
    errors = BodyErrors()
    for axis, tilt in TILTS.items():
        for name, coefficients in tilt.items():
            errors.add("motion", axis, "XYZABC".index(name[1]),
                       np.polynomial.polynomial.polyval(q[axis], coefficients), n)
    errors.add("location", "Y", 5, 10e-6, n)
    nominal = {a: v for a, v in q.items()}
    return tool_against_work(_machine(), nominal, nominal, errors)[0]


def test_table_tilts_in_the_cncs_tables_reach_the_tool_through_the_arm_to_the_cut():
    model = ErrorModel(_machine(), {"geometric": {}})
    rng = np.random.default_rng(8)
    q = {a: rng.uniform(*model.machine.axes[a].stroke, 600) for a in model.machine.axis_order}
    truth = _truth(q)
    assert np.sqrt(np.mean(np.sum(truth ** 2, axis=1))) > 2e-6
    # Taken at a fixed point of the table (the work offset) instead of the cut, the same
    # tables would miss the truth by microns: the arm is what the tables must carry.
    fixed = model.kinematics.tcp_error(q, check_stroke=False,
                                       work_point=model.machine.workpiece)["position"]
    assert np.max(np.abs(fixed - truth)) > 2e-6
    # What the CNC holds: the volumetric file (per-axis tables + location block), read back.
    applied = KinematicModel(machine_with_table(model.machine, read_isg_csv(
        write_isg_csv(model, 0.002)))).tcp_error(q, check_stroke=False)["position"]
    # Linear interpolation of cubic tilts at 2 mm: < 1e-10 rad; through arms < 1 m.
    np.testing.assert_allclose(applied, truth, rtol=0, atol=2e-10)
    # The CNC takes it out: the correction it applies leaves nothing but the table's
    # interpolation error and the second order.
    corrected = model.kinematics.compensate(q, overrides=None)
    assert np.max(np.abs(corrected["residual"])) < 1e-10


def test_the_per_axis_bilateral_tables_round_trip_on_a_table_carrying_machine():
    model = ErrorModel(_machine(), {"geometric": {}})
    tables = bilateral_tables(model, 0.005)
    assert set(tables) == {"X", "Y", "Z"}
    for axis, table in tables.items():
        read = read_bilateral_csv(write_bilateral_csv(table, "vmc"))
        grid = np.linspace(*model.machine.axes[axis].stroke, 50)
        for name, coefficients in TILTS[axis].items():
            np.testing.assert_allclose(read.at(grid, 1.0)[name],
                                       np.polynomial.polynomial.polyval(grid, coefficients),
                                       atol=2e-9)
    result = round_trip(model, 0.002, points=1000)
    assert result.tcp_model_rms_m > 2e-6
    assert result.tcp_max_error_m <= result.tcp_bound_m
    assert result.tcp_rms_error_m < 1e-3 * result.tcp_model_rms_m


def test_a_tables_positioning_error_enters_the_controllers_table_in_the_axis_own_terms():
    """SINUMERIK EEC on the VMC's X table (sign -1: a positive command moves the table
    backwards). The control moves the axis against each table value; applied on the
    virtual machine's rigid bodies, the table must leave the tool on the cut - written
    without the axis' sign it would double the error instead."""
    import re

    from mt_accuracy_ros.core.compensation.controller_tables import siemens_eec

    data = yaml.safe_load((REPO_ROOT / "mt_accuracy_ros" / "machines" / "vmc.yaml").read_text())
    coefficients = [0.0, 6e-6, 2e-5]                  # E_XX of the table [m], q in m
    data["axes"]["X"]["errors"] = {"EXX": {"polynomial": coefficients}}
    machine = machine_from_dict(data)
    model = ErrorModel(machine, {"geometric": {}})
    text, _ = siemens_eec(model, 0.005)
    values = {int(n): float(v) * 1e-3 for n, v in
              re.findall(r"\$AA_ENC_COMP\[0,(\d+),X1\]=(-?[\d.]+)", text)}
    low = float(re.search(r"\$AA_ENC_COMP_MIN\[0,X1\]=(-?[\d.]+)", text)[1]) * 1e-3
    step = float(re.search(r"\$AA_ENC_COMP_STEP\[0,X1\]=(-?[\d.]+)", text)[1]) * 1e-3
    points = low + step * np.arange(len(values))
    table = np.array([values[k] for k in range(len(values))])
    q = np.linspace(-0.38, 0.38, 301)
    n = q.size
    command = {"X": q, "Y": np.full(n, 0.05), "Z": np.full(n, -0.2)}

    def truth_at(axis_x):
        errors = BodyErrors()
        errors.add("motion", "X", 0, np.polynomial.polynomial.polyval(axis_x, coefficients), n)
        return tool_against_work(machine, dict(command, X=axis_x), command, errors)[0][:, 0]

    uncompensated = truth_at(q)
    # A positive value moves the axis in the negative direction.
    compensated = truth_at(q - np.interp(q, points, table))
    assert np.ptp(uncompensated) > 5e-6
    # What is left is the value at the reference point (a datum the control zeroes) and
    # the table's interpolation.
    assert np.ptp(compensated) < 0.02e-6, np.ptp(compensated)
