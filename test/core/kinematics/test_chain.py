"""Kinematic error model: Kidani eq. 2.12 term by term, eqs. 2.14/3.14, Khan & Chen checks,
exact vs first order, vectorised vs per-point, compensation, bad input."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import MachineDescriptionError
from mt_accuracy_ros.core.kinematics.htm import error_htm_exact, rotation, translation
from mt_accuracy_ros.core.kinematics.chain import ErrorOverrides, KinematicModel
from mt_accuracy_ros.core.kinematics.machine import load_machine, machine_from_dict

NAMES = [f"E{c}{a}" for a in "XYZ" for c in "XYZABC"]


@pytest.fixture(scope="module")
def hmc():
    return KinematicModel(load_machine("kidani_hmc"))


@pytest.fixture(scope="module")
def grinder():
    return KinematicModel(load_machine("khan_chen_rpppr"))


def kidani_eq_2_12(E: dict, m, w) -> np.ndarray:
    """Kidani eq. 2.12 as printed (the 3-vector is spread over nine rows in the
    thesis; rows 4-9 continue rows 1-3). Two printed terms are corrected by
    the structure of the equation and by eq. 2.14: '- L_YY E_CX' in e_x is
    '- L_YX E_CX', and '- L_XY E_BX' in e_z is '- L_XX E_BX' (eq. 2.14 gives
    -E_BX (L_XX + L_XY)). ``w`` = (X_w, Y_w, Z_w) is Kidani's "target position on
    the work surface", the machining point, in the table frame."""
    L_XX, L_YX, L_ZX = m.axes["X"].offset
    L_XY, L_YY, L_ZY = m.axes["Y"].offset
    L_XZ, L_YZ, L_ZZ = m.axes["Z"].offset
    Z_t = m.tool[2]
    X_w, Y_w, Z_w = w
    g = lambda n: E.get(n, 0.0)  # noqa: E731
    e_x = (g("EXX") + g("EXY") - g("EXZ") + L_ZY * (g("EBX") + g("EBY"))
           - L_YY * (g("ECX") + g("ECY")) + Z_t * (g("EBX") + g("EBY")) - L_YX * g("ECX")
           + L_ZX * g("EBX") + L_YZ * g("ECZ") - L_ZZ * g("EBZ") + g("ECZ") * Y_w - g("EBZ") * Z_w)
    e_y = (g("EYX") + g("EYY") - g("EYZ") - L_ZY * (g("EAX") + g("EAY"))
           + L_XY * (g("ECX") + g("ECY")) - Z_t * (g("EAX") + g("EAY")) + L_XX * g("ECX")
           - L_ZX * g("EAX") - L_XZ * g("ECZ") + L_ZZ * g("EAZ") - g("ECZ") * X_w + g("EAZ") * Z_w)
    e_z = (g("EZX") + g("EZY") - g("EZZ") + L_YY * (g("EAX") + g("EAY"))
           - L_XY * (g("EBX") + g("EBY")) - L_XX * g("EBX") + L_YX * g("EAX")
           + L_XZ * g("EBZ") - L_YZ * g("EAZ") + g("EBZ") * X_w - g("EAZ") * Y_w)
    return np.array([e_x, e_y, e_z])


ZERO = {"X": np.array([0.0]), "Y": np.array([0.0]), "Z": np.array([0.0])}


@pytest.mark.parametrize("name", NAMES)
def test_first_order_model_reproduces_eq_2_12_coefficient(hmc, name):
    h = 1e-7
    plus = hmc.tcp_error(ZERO, overrides=ErrorOverrides(motion={name: h}))["position"][0]
    minus = hmc.tcp_error(ZERO, overrides=ErrorOverrides(motion={name: -h}))["position"][0]
    coefficient = (plus - minus) / (2 * h)
    expected = kidani_eq_2_12({name: 1.0}, hmc.machine, hmc.machining_point(ZERO)[0])
    np.testing.assert_allclose(coefficient, expected, rtol=0, atol=1e-8)
    linear = hmc.tcp_error_linear(ZERO, overrides=ErrorOverrides(motion={name: 1.0}))["position"][0]
    np.testing.assert_allclose(linear, expected, rtol=0, atol=1e-14)


def test_yaw_only_case_is_eq_2_14(hmc):
    m = hmc.machine
    E = {"EBX": 3e-6, "EBZ": -2e-6, "ECY": 5e-6}
    L_XX, _, L_ZX = m.axes["X"].offset
    L_XY, L_YY, L_ZY = m.axes["Y"].offset
    L_XZ, _, L_ZZ = m.axes["Z"].offset
    Z_t, (X_w, _, Z_w) = m.tool[2], hmc.machining_point(ZERO)[0]
    eq_2_14 = np.array([
        -E["EBZ"] * (L_ZZ + Z_w) + E["EBX"] * (L_ZX + L_ZY + Z_t) - L_YY * E["ECY"],
        L_XY * E["ECY"],
        -E["EBX"] * (L_XX + L_XY) + E["EBZ"] * (L_XZ + X_w)])
    linear = hmc.tcp_error_linear(ZERO, overrides=ErrorOverrides(motion=E))["position"][0]
    np.testing.assert_allclose(linear, eq_2_14, atol=1e-18)
    exact = hmc.tcp_error(ZERO, overrides=ErrorOverrides(motion=E))["position"][0]
    np.testing.assert_allclose(exact, eq_2_14, atol=1e-10)


def test_y_axis_yaw_with_tool_offset_d_is_eqs_3_13_to_3_16():
    d = 0.3
    machine = machine_from_dict({"name": "y_only", "chain": "[w b Y t]", "tool": [d, 0, 0],
                                 "workpiece": [0, 0, 0],
                                 "axes": {"Y": {"stroke": [-0.44, 0], "offset": [0, 0, 0]}}})
    model = KinematicModel(machine)
    y = np.linspace(-0.44, 0, 12)
    yaw_t1 = 2e-6 * np.sin(8 * y)
    yaw_t2 = yaw_t1 + np.where(y > -0.16, 70e-6, 0.0)
    e1 = model.tcp_error({"Y": y}, overrides=ErrorOverrides(motion={"ECY": yaw_t1}))["position"]
    e2 = model.tcp_error({"Y": y}, overrides=ErrorOverrides(motion={"ECY": yaw_t2}))["position"]
    np.testing.assert_allclose(e1[:, 1], np.sin(yaw_t1) * d, atol=1e-15)   # eq. 3.14 (exact: sin)
    np.testing.assert_allclose((e2 - e1)[:, 1], (yaw_t2 - yaw_t1) * d, rtol=1e-6)  # eq. 3.16
    assert np.max(np.abs(e2 - e1)[:, 1]) == pytest.approx(21e-6, rel=1e-3)


def test_exact_and_first_order_agree_to_second_order(hmc, grinder):
    rng = np.random.default_rng(0)
    for model in (hmc, grinder):
        axes = model.machine.axis_order
        n = 50
        positions = {a: rng.uniform(*model.machine.axes[a].stroke, n) for a in axes}
        names = [f"E{c}{a}" for a in axes for c in "XYZABC"]
        base = {name: rng.normal(0, 1, n) for name in names}
        gaps = []
        for scale in (1e-4, 5e-5):
            overrides = ErrorOverrides(motion=base, scale=scale)
            exact = model.tcp_error(positions, overrides=overrides)
            linear = model.tcp_error_linear(positions, overrides=overrides)
            matrix_first = model.tcp_error(positions, overrides=overrides, first_order=True)
            gaps.append(np.max(np.abs(exact["position"] - linear["position"])))
            # First-order matrices differ from the linear sum by second order too.
            assert np.max(np.abs(matrix_first["position"] - linear["position"])) < 50 * scale ** 2
            assert np.max(np.abs(exact["orientation"] - linear["orientation"])) < 50 * scale ** 2
        # Halving the errors quarters the disagreement: it is second order.
        assert gaps[1] / gaps[0] == pytest.approx(0.25, abs=0.02)



def test_error_frames_give_the_central_difference_of_the_exact_chain(hmc, grinder):
    """The analytic sensitivities (frame + lever) against the exact HTM product,
    differentiated numerically: a central difference is exact to O(step^2)."""
    from mt_accuracy_ros.core.effects.base import Context
    from mt_accuracy_ros.core.effects.variables import Variables

    rng = np.random.default_rng(4)
    step = 1e-6
    for model in (hmc, grinder):
        axes = model.machine.axis_order
        n = 40
        positions = {a: rng.uniform(*model.machine.axes[a].stroke, n) for a in axes}
        ctx = Context(model.machine, Variables(positions), model)
        names = [f"E{c}{a}" for a in axes for c in "XYZABC"] + \
            [f"E{c}0{a}" for a in axes for c in "XYZABC"]
        for name in names:
            moved = []
            for value in (step, -step):
                overrides = ErrorOverrides(use_description=False)
                if len(name) == 4:
                    overrides.location[name] = value
                else:
                    overrides.motion[name] = np.full(n, value)
                moved.append(model.tcp_error(positions, overrides=overrides,
                                             check_stroke=False)["position"])
            numeric = (moved[0] - moved[1]) / (2 * step)
            np.testing.assert_allclose(ctx.jacobian(name), numeric, rtol=0, atol=1e-8,
                                       err_msg=f"{model.machine.name} {name}")
        assert np.all(ctx.jacobian("EXW") == 0.0)  # not an axis of this chain

def _per_point_reference(model, positions, overrides, work_point=None):
    """Plain per-point 4x4 loop, written independently of KinematicModel.branch.

    The work point is the machining point (the nominal tool point in the workpiece
    frame, inverted here with a 4x4 inverse) unless ``work_point`` is given."""
    m = model.machine
    out = []
    n = len(next(iter(positions.values())))
    for i in range(n):
        frames = {}
        for which, axes in (("t", m.tool_branch), ("w", m.workpiece_branch)):
            act, nom = np.eye(4), np.eye(4)
            parent = np.zeros(3)
            for a in axes:
                spec = m.axes[a]
                q = positions[a][i]
                move = (rotation("xyz"[spec.direction], q) if spec.is_rotary else
                        translation(*(np.eye(3)[spec.direction] * q)))
                errs = np.array([overrides.motion.get(f"E{c}{a}", np.zeros(n))[i]
                                 for c in "XYZABC"])
                act = act @ translation(*parent) @ move @ error_htm_exact(errs)
                nom = nom @ translation(*parent) @ move
                parent = spec.offset
            frames[which] = (act @ translation(*parent), nom @ translation(*parent))
        tool_point = np.append(m.tool, 1.0)
        nominal_tool = frames["t"][1] @ tool_point
        if work_point is None:
            point = np.linalg.inv(frames["w"][1]) @ nominal_tool
        else:
            point = np.append(work_point, 1.0)
        actual = frames["t"][0] @ tool_point - frames["w"][0] @ point
        nominal = nominal_tool - frames["w"][1] @ point
        out.append((actual - nominal)[:3])
    return np.array(out)


def test_vectorised_map_equals_a_per_point_loop(grinder):
    rng = np.random.default_rng(1)
    axes = grinder.machine.axis_order
    positions = {a: rng.uniform(*grinder.machine.axes[a].stroke, 40) for a in axes}
    overrides = ErrorOverrides(motion={f"E{c}{a}": rng.normal(0, 1e-5, 40)
                                       for a in axes for c in "XYZABC"})
    fast = grinder.tcp_error(positions, overrides=overrides)["position"]
    slow = _per_point_reference(grinder, positions, overrides)
    np.testing.assert_allclose(fast, slow, rtol=0, atol=1e-15)
    # A fixed target on the workpiece side (an R-test sphere) is evaluated there.
    sphere = np.array([0.05, -0.01, 0.03])
    fast = grinder.tcp_error(positions, overrides=overrides, work_point=sphere)["position"]
    slow = _per_point_reference(grinder, positions, overrides, work_point=sphere)
    np.testing.assert_allclose(fast, slow, rtol=0, atol=1e-15)


def _summed(frames, motion):
    """First-order TCP error as the sum of each error's frame sensitivity times its value."""
    summed = 0.0
    for name, value in motion.items():
        sign, rot, lever = frames[name]
        c = "XYZABC".index(name[1])
        column = rot[:, :, c] if c < 3 else np.cross(rot[:, :, c - 3], lever)
        summed = summed + sign * column * value[:, None]
    return summed


def test_the_machining_point_is_the_nominal_tool_point_on_the_work(hmc, grinder):
    """w is the nominal tool point in the workpiece frame, so the nominal
    tool-to-work vector is zero at every configuration; and the three
    formulations (matrices, twist sum, error frames) take the error there."""
    rng = np.random.default_rng(11)
    for model in (hmc, grinder):
        m = model.machine
        n = 30
        q = {a: rng.uniform(*m.axes[a].stroke, n) for a in m.axis_order}
        w = model.machining_point(q)
        np.testing.assert_allclose(model.nominal_relative(q, work_point=w), 0.0, atol=1e-15)
        assert np.ptp(w, axis=0).max() > 0.1   # it moves with the axes
        overrides = ErrorOverrides(motion={f"E{c}{a}": rng.normal(0, 1e-6, n)
                                           for a in m.axis_order for c in "XYZABC"},
                                   use_description=False)
        linear = model.tcp_error_linear(q, overrides=overrides, check_stroke=False)
        first = model.tcp_error(q, overrides=overrides, first_order=True, check_stroke=False)
        exact = model.tcp_error(q, overrides=overrides, check_stroke=False)
        np.testing.assert_allclose(first["position"], linear["position"], atol=5e-11)  # 2nd order
        np.testing.assert_allclose(exact["position"], linear["position"], atol=1e-10)
        # the error frames' sum of sensitivities is the same first-order error
        np.testing.assert_allclose(_summed(model.error_frames(q), overrides.motion),
                                   linear["position"], atol=1e-12)
        # ... and with a fixed target all three move their arm together
        target = np.array([0.02, 0.03, -0.01])
        linear_t = model.tcp_error_linear(q, overrides=overrides, check_stroke=False,
                                          work_point=target)
        exact_t = model.tcp_error(q, overrides=overrides, check_stroke=False, work_point=target)
        np.testing.assert_allclose(exact_t["position"], linear_t["position"], atol=1e-10)
        np.testing.assert_allclose(_summed(model.error_frames(q, work_point=target),
                                           overrides.motion), linear_t["position"], atol=1e-12)


def test_a_table_pitch_acts_through_the_arm_to_the_tool(hmc):
    """The issue's case: a 10 urad pitch of the Z table (EAZ) on the HMC moves the
    part under the tool by eps x (tool - table frame), so Y changes the error."""
    y = np.array([-0.44, -0.20, 0.0])
    q = {"X": np.full(3, 0.2), "Y": y, "Z": np.full(3, 0.25)}
    pitch = ErrorOverrides(motion={"EAZ": 1e-5}, use_description=False)
    e = hmc.tcp_error(q, overrides=pitch)["position"]
    table_origin = np.array([0.0, 0.0, 0.25])   # where the Z table's motion error acts
    tool = hmc.branch("tool", q, errors=False)[:, :3, 3]
    expected = -np.cross([1e-5, 0.0, 0.0], tool - table_origin)
    np.testing.assert_allclose(hmc.tcp_error_linear(q, overrides=pitch)["position"], expected,
                               atol=1e-15)
    np.testing.assert_allclose(e, expected, atol=1e-10)
    assert abs(e[0, 2] - e[2, 2]) == pytest.approx(1e-5 * 0.44, rel=1e-6)


class TestKhanChenValidation:
    """Khan & Chen section 7: identity-style checks of the loops and eq. 17."""

    def positions(self, grinder, **values):
        base = {a: np.array([0.0]) for a in grinder.machine.axis_order}
        base.update({a: np.array([v]) for a, v in values.items()})
        return base

    def test_no_error_gives_zero_error_and_nominal_loops(self, grinder):
        pos = self.positions(grinder, X=0.3, Y=0.2, Z=0.1, A=0.7, B=-0.4)
        out = grinder.tcp_error(pos)
        assert np.all(out["position"] == 0) and np.all(np.abs(out["orientation"]) < 1e-15)
        np.testing.assert_allclose(grinder.branch("tool", pos),
                                   grinder.branch("tool", pos, errors=False))

    def test_pure_displacement_gives_the_same_displacement(self, grinder):
        pos = self.positions(grinder, Y=0.2)
        out = grinder.tcp_error(pos, overrides=ErrorOverrides(motion={"EXY": 7e-6, "EZY": -3e-6}))
        np.testing.assert_allclose(out["position"][0], [7e-6, 0, -3e-6], atol=1e-18)
        # A displacement of the workpiece slide moves the TCP relative to the work the other way.
        out = grinder.tcp_error(pos, overrides=ErrorOverrides(motion={"EYX": 4e-6}))
        np.testing.assert_allclose(out["position"][0], [0, -4e-6, 0], atol=1e-18)

    def test_pure_rotation_gives_that_rotation(self, grinder):
        pos = self.positions(grinder, B=0.3)
        out = grinder.tcp_error(pos, overrides=ErrorOverrides(motion={"EBB": 2e-5}))
        np.testing.assert_allclose(out["orientation"][0], [0, 2e-5, 0], atol=1e-15)
        # The tool tip (l = 0.1 from the B axis, turned by 0.3 rad) swings by
        # exactly (R_y(eps) - I) r, which is eps x r to first order.
        r = rotation("y", 0.3)[:3, :3] @ grinder.machine.tool
        swing = (rotation("y", 2e-5)[:3, :3] - np.eye(3)) @ r
        np.testing.assert_allclose(out["position"][0], swing, rtol=0, atol=1e-16)
        np.testing.assert_allclose(swing, np.cross([0, 2e-5, 0], r), rtol=1e-4)

    def test_combined_errors_give_the_combined_effect(self, grinder):
        pos = self.positions(grinder, X=0.1, Y=0.2, Z=0.3, A=0.5, B=0.2)
        single = [{"EXY": 5e-6}, {"ECZ": 1e-5}, {"EAA": -2e-5}]
        combined = {k: v for d in single for k, v in d.items()}
        parts = sum(grinder.tcp_error(pos, overrides=ErrorOverrides(motion=d))["position"]
                    for d in single)
        together = grinder.tcp_error(pos, overrides=ErrorOverrides(motion=combined))["position"]
        np.testing.assert_allclose(together, parts, atol=1e-10)  # additive to first order


def test_inventory_counts_52_potential_and_39_considered(grinder):
    inventory = grinder.error_inventory()
    assert len(inventory["potential"]) == 52
    assert len(inventory["considered"]) == 39
    assert {"EC0Y", "EB0Z", "EA0Z", "EC0A", "EB0A", "EC0B", "EA0B", "EX0B", "EZ0B"} <= set(
        inventory["considered"])


def test_squareness_error_grows_with_the_other_axis(hmc):
    pos = {"X": np.array([0.2]), "Y": np.array([-0.3]), "Z": np.array([0.1])}
    out = hmc.tcp_error(pos, overrides=ErrorOverrides(location={"EC0Y": 1e-5}))["position"][0]
    # Y is mounted on X; a squareness about z tilts the Y travel (and all below) into -x.
    lever = np.array([0.0, -0.3, 0.0]) + hmc.machine.axes["Y"].offset + hmc.machine.tool
    np.testing.assert_allclose(out, np.cross([0, 0, 1e-5], lever), atol=1e-10)  # + 2nd order


def test_compensation_removes_the_error_and_iteration_helps(hmc):
    rng = np.random.default_rng(2)
    n = 200
    pos = {a: rng.uniform(*hmc.machine.axes[a].stroke, n) * 0.9 + 0.05 * np.array(
        hmc.machine.axes[a].stroke).sum() for a in "XYZ"}
    # Position-dependent errors of X and a squareness of Y, from the description.
    machine = machine_from_dict({
        "name": "t", "chain": "[w Z b X Y t]", "tool": [0, 0, 0.15], "workpiece": [0, 0.05, 0],
        "axes": {"X": {"stroke": [0, 0.39], "offset": [0, 0.35, -0.15],
                       "errors": {"EXX": {"polynomial": [0, 2e-4, 3e-3]},
                                  "ECX": {"table": {"positions": [0, 0.39], "values": [0, 4e-5]}}}},
                 "Y": {"stroke": [-0.44, 0], "offset": [0.12, 0, 0.45],
                       "location_errors": {"EC0Y": 1.5e-5}},
                 "Z": {"stroke": [0, 0.495], "offset": [0, 0.6, 0.2]}}})
    model = KinematicModel(machine)
    one = model.compensate(pos, iterations=1)
    many = model.compensate(pos, iterations=4)
    initial = np.max(np.linalg.norm(one["initial"], axis=1))
    assert initial > 20e-6
    assert np.max(np.linalg.norm(one["residual"], axis=1)) < 0.05 * initial
    assert np.max(np.linalg.norm(many["residual"], axis=1)) < 1e-12


def test_rotary_correction_reduces_orientation_error(grinder):
    pos = {a: np.array([v]) for a, v in zip("XAYZB", (0.1, 0.4, 0.2, 0.1, 0.3))}
    overrides = ErrorOverrides(motion={"EAA": 3e-5, "EBB": -2e-5})
    out = grinder.compensate_orientation(pos, overrides=overrides)
    assert np.linalg.norm(out["residual"]) < 0.05 * np.linalg.norm(out["initial"])


@pytest.mark.parametrize("mutate,field", [
    (lambda d: d.update(chain="[w Q b X Y t]"), "chain"),
    (lambda d: d.update(chain="w Z b X Y t"), "chain"),
    (lambda d: d.update(chain="[w Z b X Z t]"), "chain"),
    (lambda d: d["axes"]["X"].pop("offset"), "axes.X"),
    (lambda d: d.pop("tool"), "tool"),
    (lambda d: d["axes"]["X"].update(errors={"EXX": float("nan")}), "axes.X.errors.EXX"),
    (lambda d: d["axes"]["X"].update(errors={"EXY": 1e-6}), "axes.X.errors.EXY"),
    (lambda d: d["axes"]["X"].update(
        errors={"ECX": {"table": {"positions": [0, 0], "values": [0, 1]}}}),
     "ECX"),
    (lambda d: d["axes"].update(W={"stroke": [0, 1], "offset": [0, 0, 0]}), "axes.W"),
])
def test_bad_descriptions_name_the_field(mutate, field):
    import copy
    import yaml
    from pathlib import Path

    import mt_accuracy_ros

    data = yaml.safe_load(Path(mt_accuracy_ros.__file__).parent.joinpath(
        "machines", "kidani_hmc.yaml").read_text())
    data = copy.deepcopy(data)
    mutate(data)
    with pytest.raises(MachineDescriptionError, match=field.replace(".", r"\.")):
        machine_from_dict(data)


def test_positions_outside_the_stroke_or_unknown_axes_are_refused(hmc):
    with pytest.raises(MachineDescriptionError, match="axis X.*outside the stroke"):
        hmc.tcp_error({"X": np.array([0.5]), "Y": np.array([0.0]), "Z": np.array([0.0])})
    with pytest.raises(MachineDescriptionError, match="unknown axis 'W'"):
        hmc.tcp_error({"X": [0.1], "Y": [0.0], "Z": [0.0], "W": [0.0]})
    with pytest.raises(MachineDescriptionError, match="missing for axis Z"):
        hmc.tcp_error({"X": [0.1], "Y": [0.0]})


def test_a_knn_profile_feeds_the_model_as_an_error_function():
    from dataclasses import replace

    from mt_accuracy_ros.core.kinematics.error_functions import from_profile
    from mt_accuracy_ros.core.scales.knn import extract_systematic

    rng = np.random.default_rng(3)
    x = rng.uniform(0, 0.39, 4000)
    yaw = 4e-6 * np.sin(2 * np.pi * x / 0.3) + rng.normal(0, 3e-7, x.size)
    grid = np.linspace(0, 0.39, 40)
    profile = extract_systematic(x, yaw, grid, k_lim=50)
    machine = load_machine("kidani_hmc")
    axis = machine.axes["X"]
    motion = dict(axis.motion_errors, C=from_profile(grid, profile.systematic))
    machine = replace(machine, axes=dict(machine.axes, X=replace(axis, motion_errors=motion)))
    model = KinematicModel(machine)
    pos = {"X": grid, "Y": np.zeros(40), "Z": np.zeros(40)}
    e = model.tcp_error(pos)["position"]
    lever_y = machine.axes["X"].offset[1] + machine.axes["Y"].offset[1]
    np.testing.assert_allclose(e[:, 0], -profile.systematic * lever_y, rtol=1e-6, atol=1e-13)


def test_samples_are_read_only_views_or_one_value_repeated():
    """The chain and the model's variables take each axis' values as a read-only (n,)
    array: what np.broadcast_to gave, the caller's data never written through it."""
    from mt_accuracy_ros.core.validation import as_samples

    data = np.arange(4.0)
    samples = as_samples(data, 4)
    np.testing.assert_array_equal(samples, data)
    assert np.shares_memory(samples, data) and not samples.flags.writeable
    with pytest.raises(ValueError):
        samples[0] = 1.0
    np.testing.assert_array_equal(as_samples(2.5, 3), [2.5, 2.5, 2.5])
    np.testing.assert_array_equal(as_samples([[1.0, 2.0], [3.0, 4.0]], 4), data + 1.0)
    with pytest.raises(ValueError):
        as_samples(data, 3)
