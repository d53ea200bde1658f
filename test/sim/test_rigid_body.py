"""The virtual machine's own truth (sim.rigid_body) against the kinematic chain and
against closed-form Abbe cases: the simulator judges the model with poses it
computes itself."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from mt_accuracy_ros.core.kinematics.chain import ErrorOverrides, KinematicModel
from mt_accuracy_ros.core.kinematics.machine import load_machine
from mt_accuracy_ros.sim.machine_tool import simulate
from mt_accuracy_ros.sim.rigid_body import BodyErrors, point_under_tool, tool_against_work
from mt_accuracy_ros.sim.scenario import scenario_from_yaml

MACHINES = ("kidani_hmc", "khan_chen_rpppr", "vmc", "trunnion_ac")
#: Set-up poses the rotary machines are also tried with [rad] (ISO 230-7: the bodies turn
#: about their actual lines from there).
SETUP_POSES = {"khan_chen_rpppr": {"A": 0.4, "B": -0.3}, "trunnion_ac": {"A": -1.2, "C": 0.8}}


def _random_errors(machine, n, rng, size):
    errors = BodyErrors()
    for axis in machine.axis_order:
        errors.motion[axis] = rng.normal(0.0, size, (n, 6))
        errors.location[axis] = rng.normal(0.0, size, (n, 6))
        errors.thermal[axis] = rng.normal(0.0, size, (n, 6))
    errors.thermal["bed_tool"] = rng.normal(0.0, size, (n, 6))
    errors.thermal["bed_work"] = rng.normal(0.0, size, (n, 6))
    return errors


def _as_overrides(errors: BodyErrors) -> ErrorOverrides:
    """The same errors in the chain's vocabulary (ISO 230-1 names)."""
    overrides = ErrorOverrides(use_description=False)
    for axis, twist in errors.motion.items():
        for i, c in enumerate("XYZABC"):
            overrides.motion[f"E{c}{axis}"] = twist[:, i]
    for axis, twist in errors.location.items():
        for i, c in enumerate("XYZABC"):
            overrides.location[f"E{c}0{axis}"] = twist[:, i]
    overrides.thermal.update(errors.thermal)
    return overrides


def _scaled(errors: BodyErrors, factor: float) -> BodyErrors:
    return BodyErrors({k: v * factor for k, v in errors.motion.items()},
                      {k: v * factor for k, v in errors.location.items()},
                      {k: v * factor for k, v in errors.thermal.items()})


@pytest.mark.parametrize("name, setup", [(name, False) for name in MACHINES] +
                         [(name, True) for name in SETUP_POSES])
def test_the_simulators_truth_is_the_chain_at_first_order_and_exactly(name, setup):
    from dataclasses import replace

    machine = load_machine(name)
    if setup:
        machine = replace(machine, setup_pose=SETUP_POSES[name])
    chain = KinematicModel(machine)
    rng = np.random.default_rng(3)
    n = 50
    q = {a: rng.uniform(*machine.axes[a].stroke, n) for a in machine.axis_order}
    errors = _random_errors(machine, n, rng, 2e-6)
    overrides = _as_overrides(errors)
    for work_point in (None, np.array([0.04, -0.03, 0.02])):
        # first order: the simulator linearised (errors scaled down by 1e3) against the
        # chain's twist sum
        small = 1e-3
        position, orientation = tool_against_work(machine, q, q, _scaled(errors, small),
                                                  work_point)
        linear = chain.tcp_error_linear(q, overrides=overrides, check_stroke=False,
                                        work_point=work_point)
        np.testing.assert_allclose(position / small, linear["position"], rtol=0, atol=1e-12)
        np.testing.assert_allclose(orientation / small, linear["orientation"], rtol=0, atol=1e-12)
        # exact: both compose the same rigid motions, by different code
        position, orientation = tool_against_work(machine, q, q, errors, work_point)
        exact = chain.tcp_error(q, overrides=overrides, check_stroke=False,
                                work_point=work_point)
        np.testing.assert_allclose(position, exact["position"], rtol=0, atol=1e-15)
        np.testing.assert_allclose(orientation, exact["orientation"], rtol=0, atol=1e-15)
        assert np.abs(position).max() > 1e-6
    np.testing.assert_allclose(point_under_tool(machine, q), chain.machining_point(q), atol=1e-15)


# ------------------------------------------------------------ closed-form Abbe cases
def _vmc_at(x, y, z):
    n = np.size(z)
    return {"X": np.broadcast_to(x, n) * 1.0, "Y": np.broadcast_to(y, n) * 1.0,
            "Z": np.broadcast_to(z, n) * 1.0}


def _one(machine, q, kind, axis, component, value):
    n = np.size(next(iter(q.values())))
    errors = BodyErrors()
    errors.add(kind, axis, "XYZABC".index(component), value, n)
    return tool_against_work(machine, q, q, errors)[0]


def test_a_table_pitch_acts_through_the_spindles_height():
    """VMC, X-table pitch EBX = b about y at the table's guideway (0.5 m below the
    spindle nose): the part under the tool moves by b times the tool's height above
    it, e_x = -b (Z - L_tool + 0.5), e_z = b x (x = the tool's place across the table)."""
    machine = load_machine("vmc")
    b = 10e-6
    z = np.linspace(-0.508, 0.0, 7)
    for x in (-0.3, 0.0, 0.25):
        e = _one(machine, _vmc_at(x, 0.1, z), "motion", "X", "B", b)
        height = z - 0.10 + 0.50
        np.testing.assert_allclose(e[:, 0], -b * height, atol=1e-10)
        np.testing.assert_allclose(e[:, 2], b * x, atol=1e-10)
    assert np.ptp(e[:, 0]) == pytest.approx(b * 0.508, rel=1e-4)   # 5.08 um over the stroke


def test_a_table_yaw_acts_through_the_other_axis_position():
    """HMC, Z-table yaw EBZ = c about y: the part under the tool moves by c times the
    column's X (Kidani's L_XY = 0.12 m beyond it), e_z = c (X + 0.12)."""
    machine = load_machine("kidani_hmc")
    c = 8e-6
    x = np.linspace(0.0, 0.39, 9)
    q = {"X": x, "Y": np.full(9, -0.2), "Z": np.full(9, 0.3)}
    e = _one(machine, q, "motion", "Z", "B", c)
    np.testing.assert_allclose(e[:, 2], c * (x + 0.12), atol=1e-10)
    # VMC: the saddle's yaw ECY acts through Y (the saddle carries the table under a
    # fixed spindle) and not through X: the tool stays where it is while the table moves.
    vmc = load_machine("vmc")
    grid = np.meshgrid(np.linspace(-0.38, 0.38, 5), np.linspace(-0.2, 0.2, 5))
    q = _vmc_at(grid[0].ravel(), grid[1].ravel(), np.full(25, -0.3))
    e = _one(vmc, q, "motion", "Y", "C", c)
    np.testing.assert_allclose(e[:, 0], c * q["Y"], atol=1e-10)
    np.testing.assert_allclose(e[:, 1], 0.0, atol=1e-10)


def test_a_head_tilt_acts_through_the_tool_length():
    """VMC, spindle head tilt EBZ = b: the tool tip moves by b times the tool length,
    e_x = -b L (the tool points down), whatever the table does."""
    b = 12e-6
    for length in (0.05, 0.10, 0.25):
        machine = replace(load_machine("vmc"), tool=np.array([0.0, 0.0, -length]))
        q = _vmc_at(np.array([-0.2, 0.1, 0.3]), np.array([0.1, -0.15, 0.0]),
                    np.array([-0.4, -0.1, 0.0]))
        e = _one(machine, q, "motion", "Z", "B", b)
        # exact poses: the second order (b^2 L / 2 ~ 1e-11 m) is all that is left
        np.testing.assert_allclose(e[:, 0], -b * length, atol=1e-10)
        np.testing.assert_allclose(e[:, 1:], 0.0, atol=1e-10)


def test_a_virtual_run_with_table_tilts_is_the_chain_at_the_machining_point():
    """A whole VMC scenario (geometric errors, table tilts, squareness, a column
    drift) with lag and backlash off: the simulator's truth at every sample equals the
    chain evaluated with the simulator's error twists, at the machining point."""
    scenario = scenario_from_yaml(
        "machine: vmc\nseed: 3\nduration_s: 6\nsample_rate_hz: 200\n"
        "program: {type: random_points, axes: [X, Y, Z], points: 6, seed: 1, dwell_s: 0.2}\n"
        "effects: {table_tilt: {errors_rad: {EBX: 1.0e-5, EAY: -8.0e-6, ECX: 6.0e-6}},"
        " squareness: {errors_rad: {EC0Y: 1.5e-5}},"
        " structural_thermal_drift: {time_constant_s: 2, rise_k: 2.0}}\n")
    result = simulate(scenario)
    rows = np.arange(0, result.time_s.size, 17)
    truth = result.tcp_error(rows)
    q = {a: result.actual[a][rows] for a in scenario.machine.axis_order}
    overrides = _as_overrides(result.body_errors(rows, q))
    chain = KinematicModel(scenario.machine).tcp_error(q, overrides=overrides,
                                                       check_stroke=False)["position"]
    np.testing.assert_allclose(truth, chain, rtol=0, atol=1e-15)
    assert np.ptp(truth[:, 0]) > 3e-6
