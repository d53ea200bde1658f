"""The CNC's compensation inputs: fixed-delay real-time offset and tables."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.controller import RealtimeOffset, TableCompensation
from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.core.kinematics.machine import load_machine

MS = 1_000_000


def test_offset_applies_at_the_first_cycle_after_stamp_plus_delay():
    offset = RealtimeOffset(cycle_s=0.001, delay_s=0.02, max_age_s=0.1)
    assert offset.offer(100 * MS + 300_000, 105 * MS, [1e-6, 0, 0], 1) is None
    assert offset.offer(110 * MS, 112 * MS, [2e-6, 0, 0], 1) is None
    # 100.3 ms + 20 ms = 120.3 ms -> cycle tick 121 ms; 110 + 20 = 130 ms.
    values, versions = offset.at(np.array([120, 120.9, 121, 129.99, 130, 500]) * MS)
    np.testing.assert_array_equal(values[:, 0], [0, 0, 1e-6, 1e-6, 2e-6, 2e-6])
    np.testing.assert_array_equal(versions, [0, 0, 1, 1, 1, 1])
    p50, p99, worst = offset.statistics.latency_percentiles()
    assert worst == pytest.approx(0.0207) and offset.statistics.applied == 2


def test_a_late_correction_applies_at_arrival_and_a_stale_one_never():
    offset = RealtimeOffset(cycle_s=0.001, delay_s=0.02, max_age_s=0.1)
    assert offset.offer(0, 5 * MS, [1e-6, 0, 0], 1) is None
    assert offset.offer(10 * MS, 50 * MS, [2e-6, 0, 0], 1) is None      # 40 ms late: at 50 ms
    reason = offset.offer(20 * MS, 200 * MS, [9e-6, 0, 0], 1)            # 180 ms > 100 ms
    assert reason.startswith("stale")
    values, _ = offset.at(np.array([30, 49, 50, 300]) * MS)
    # The last valid correction stays after the stale one.
    np.testing.assert_array_equal(values[:, 0], [1e-6, 1e-6, 2e-6, 2e-6])
    assert offset.statistics.stale == 1 and offset.statistics.refused == 0
    # When the path missed its deadline, and by how much: kept for the operator.
    assert offset.offer(30 * MS, 400 * MS, [9e-6, 0, 0], 1).startswith("stale")   # 370 ms
    stats = offset.statistics
    assert (stats.first_stale_ns, stats.last_stale_ns) == (20 * MS, 30 * MS)
    assert stats.worst_stale_age_s == pytest.approx(0.37)


@pytest.mark.parametrize("stamp, correction, version, word", [
    (5, [np.nan, 0, 0], 2, "not finite"), (5, [1e-2, 0, 0], 2, "too large"),
    (1, [0, 0, 0], 2, "out of order"), (5, [0, 0, 0], 0, "old model")])
def test_bad_corrections_are_refused_and_the_last_valid_one_stays(stamp, correction, version,
                                                                  word):
    offset = RealtimeOffset(cycle_s=0.001, delay_s=0.0, max_age_s=1.0)
    assert offset.offer(2 * MS, 2 * MS, [3e-6, 0, 0], 1) is None
    assert word in offset.offer(stamp * MS, stamp * MS, correction, version)
    assert offset.at(np.array([10 * MS]))[0][0, 0] == 3e-6
    assert offset.statistics.refused == 1


def test_the_correction_limit_is_the_controllers_own_parameter():
    """Issue 29: the limit is the CNC's, not the model's: a controller set to 50 um refuses
    a 60 um correction and a 60 um table value a looser one takes."""
    strict = RealtimeOffset(cycle_s=0.001, delay_s=0.0, max_age_s=1.0, max_correction_m=50e-6)
    loose = RealtimeOffset(cycle_s=0.001, delay_s=0.0, max_age_s=1.0)
    assert "controller's limit 5e-05 m" in strict.offer(MS, MS, [60e-6, 0, 0], 1)
    assert loose.offer(MS, MS, [60e-6, 0, 0], 1) is None
    machine = load_machine("kidani_hmc")
    grid = np.linspace(*machine.axes["X"].stroke, 11)
    table = ("X", ["X_m", "EXX_m", "EBX_rad"],
             np.column_stack([grid, np.full(11, 60e-6), np.full(11, 60e-6)]).ravel(), [], [], 1)
    assert "controller's limit" in TableCompensation(machine, max_correction_m=50e-6).offer(*table)
    assert TableCompensation(machine).offer(*table) is None
    with pytest.raises(ParameterError, match="max_correction_m"):
        RealtimeOffset(cycle_s=0.001, delay_s=0.0, max_age_s=1.0, max_correction_m=0.0)


def test_bad_controller_parameters_are_refused():
    with pytest.raises(ParameterError):
        RealtimeOffset(cycle_s=0.0, delay_s=0.0, max_age_s=1.0)
    with pytest.raises(ParameterError):
        RealtimeOffset(cycle_s=0.001, delay_s=0.5, max_age_s=0.1)


def test_forgetting_keeps_the_live_correction():
    offset = RealtimeOffset(cycle_s=0.001, delay_s=0.0, max_age_s=1.0)
    for k in range(10):
        offset.offer(k * MS, k * MS, [k * 1e-7, 0, 0], 1)
    offset.forget_before(5 * MS)
    assert offset.at(np.array([5 * MS, 9 * MS]))[0][:, 0].tolist() == [5e-7, 9e-7]


def _tables_of(model: ErrorModel, points: int = 41):
    """Per-axis tables of the model's geometric errors, as the broadcaster sends them."""
    out = []
    for axis in model.machine.axis_order:
        grid = np.linspace(*model.machine.axes[axis].stroke, points)
        columns, values = [f"{axis}_m"], [grid]
        for component in "XYZABC":
            unit = "m" if component in "XYZ" else "rad"
            columns.append(f"E{component}{axis}_{unit}")
            values.append(model.machine.axes[axis].motion_errors[component](grid))
        out.append((axis, columns, np.column_stack(values).ravel()))
    return out


def test_tables_reproduce_the_models_geometric_error_through_the_chain():
    """Second formulation: the error model's own evaluation of the same description."""
    machine = load_machine("kidani_hmc")
    rng = np.random.default_rng(3)
    # A machine with smooth component errors: linear in position, so the table's
    # linear interpolation is exact.
    for axis in machine.axis_order:
        spec = machine.axes[axis]
        for component in "XYZABC":
            slope = rng.normal(0, 2e-5)
            spec.motion_errors[component] = _linear(slope, spec.stroke)
    model = ErrorModel(machine, {"geometric": {}, "squareness": {"errors_rad": {"EC0Y": 8e-6}}})
    tables = TableCompensation(machine)
    for axis, columns, values in _tables_of(model):
        assert tables.offer(axis, columns, values, ["EC0Y"], [8e-6], 1) is None
    positions = {a: rng.uniform(*machine.axes[a].stroke, 50) for a in machine.axis_order}
    expected = model.tcp_error(positions)[0]
    np.testing.assert_allclose(tables.correction(positions), -expected, atol=1e-12)
    assert np.max(np.abs(expected)) > 5e-6  # the test means something


def _linear(slope: float, stroke):
    from mt_accuracy_ros.core.kinematics.error_functions import ErrorFunction

    x = np.array(stroke, dtype=float)
    return ErrorFunction(kind="profile", positions=x, values=slope * (x - x.mean()))


def _offer_other_axes(tables, machine, version, skip="X"):
    """Zero tables of every linear axis but ``skip`` (a version goes live whole)."""
    for axis in machine.axis_order:
        if axis != skip and not machine.axes[axis].is_rotary:
            grid = np.linspace(*machine.axes[axis].stroke, 11)
            values = np.column_stack([grid, np.zeros(11)]).ravel()
            assert tables.offer(axis, [f"{axis}_m", f"E{axis}{axis}_m"], values, [], [],
                                version) is None


def test_a_constant_positioning_error_is_corrected_along_its_axis():
    machine = load_machine("kidani_hmc")
    tables = TableCompensation(machine)
    low, high = machine.axes["X"].stroke
    grid = np.linspace(low, high, 11)
    values = np.column_stack([grid, np.full(11, 5e-6)]).ravel()
    assert tables.offer("x", ["X_m", "EXX_m"], values, [], [], 2) is None
    _offer_other_axes(tables, machine, 2)
    correction = tables.correction({a: np.zeros(1) + 0.5 * sum(machine.axes[a].stroke)
                                    for a in machine.axis_order})
    direction = ErrorModel(machine).axis_direction("X", {a: np.zeros(1) for a in
                                                         machine.axis_order})[0]
    np.testing.assert_allclose(correction[0], -5e-6 * direction, atol=1e-15)


@pytest.mark.parametrize("change, word", [
    (lambda t: ("W", t[1], t[2], 2), "unknown axis"),
    (lambda t: ("X", t[1], np.where(np.arange(t[2].size) == 7, np.nan, t[2]), 2), "gap"),
    (lambda t: ("X", t[1], np.delete(t[2].reshape(11, 2), 5, axis=0).ravel(), 2), "gap"),
    (lambda t: ("X", t[1], t[2][:-4], 2), "gap"),
    (lambda t: ("X", ["X_m", "EXQ_m"], t[2], 2), "bad columns"),
    (lambda t: ("X", t[1], t[2], 0), "old model")])
def test_bad_tables_are_refused_and_the_axis_keeps_its_table(change, word):
    machine = load_machine("kidani_hmc")
    tables = TableCompensation(machine)
    grid = np.linspace(*machine.axes["X"].stroke, 11)
    good = ("X", ["X_m", "EXX_m"], np.column_stack([grid, np.full(11, 5e-6)]).ravel())
    assert tables.offer(*good, [], [], 1) is None
    _offer_other_axes(tables, machine, 1)
    axis, columns, values, version = change(good)
    reason = tables.offer(axis, columns, values, [], [], version)
    assert reason is not None and word in reason, reason
    assert tables.tables["X"].components["EXX"][0] == 5e-6 and tables.version == 1


def test_a_new_version_of_the_tables_goes_live_whole():
    """Issue 29 (loaded runs): X's new table with Y's old one (or none) is a machine no
    model describes. A version switches only when every linear axis' table of it is in;
    until then the previous version stays applied, all of it."""
    machine = load_machine("kidani_hmc")
    tables = TableCompensation(machine)
    middle = {a: np.array([0.5 * sum(machine.axes[a].stroke)]) for a in machine.axis_order}
    grid = np.linspace(*machine.axes["X"].stroke, 11)

    def x_table(value):
        return "X", ["X_m", "EXX_m"], np.column_stack([grid, np.full(11, value)]).ravel()
    assert tables.offer(*x_table(5e-6), [], [], 1) is None
    assert tables.version == 0 and not np.any(tables.correction(middle))   # X alone: not yet
    _offer_other_axes(tables, machine, 1)
    assert tables.version == 1
    before = tables.correction(middle)
    assert tables.offer(*x_table(9e-6), [], [], 2) is None                  # v2 begins
    assert tables.version == 1
    np.testing.assert_array_equal(tables.correction(middle), before)      # v1 whole, still
    _offer_other_axes(tables, machine, 2)
    assert tables.version == 2
    np.testing.assert_allclose(tables.correction(middle), before * 9 / 5, atol=1e-15)
    # A refinement of the live version (a new profile) applies per axis at once.
    assert tables.offer(*x_table(7e-6), [], [], 2) is None
    np.testing.assert_allclose(tables.correction(middle), before * 7 / 5, atol=1e-15)
    # Versions that never complete do not pile up.
    for version in range(3, 103):
        assert tables.offer(*x_table(1e-6), [], [], version) is None
    assert len(tables._staged) <= 4 and tables.version == 2


def test_the_revision_counts_every_change_of_what_is_live_and_nothing_else():
    """A correction kept from an unchanged revision is the one the tables give now: the
    revision moves when a version goes live or the live one is refined, and not for a
    version still incomplete or a refused table."""
    machine = load_machine("kidani_hmc")
    tables = TableCompensation(machine)
    middle = {a: np.array([0.5 * sum(machine.axes[a].stroke)]) for a in machine.axis_order}
    grid = np.linspace(*machine.axes["X"].stroke, 11)

    def x_table(value):
        return "X", ["X_m", "EXX_m"], np.column_stack([grid, np.full(11, value)]).ravel()
    assert tables.revision == 0
    assert tables.offer(*x_table(5e-6), [], [], 1) is None
    assert tables.revision == 0                                   # v1 incomplete
    _offer_other_axes(tables, machine, 1)
    assert tables.revision == 1 and tables.version == 1
    kept = (tables.revision, tables.correction(middle))
    assert tables.offer(*x_table(9e-6), [], [], 2) is None         # v2 staged
    assert tables.offer("X", ["X_m", "EXQ_m"], x_table(1e-6)[2], [], [], 1) is not None
    assert tables.revision == kept[0]
    np.testing.assert_array_equal(tables.correction(middle), kept[1])
    assert tables.offer(*x_table(7e-6), [], [], 1) is None         # v1 refined
    assert tables.revision == 2
    assert not np.array_equal(tables.correction(middle), kept[1])
    _offer_other_axes(tables, machine, 2)                           # v2 live
    assert tables.revision == 3 and tables.version == 2


def test_the_tables_correct_each_command_on_its_own_whatever_the_batch():
    """The virtual CNC evaluates the tables once per 2 s window of commands and hands
    each 10-sample batch its rows: the same numbers as evaluating every batch apart."""
    from mt_accuracy_ros.nodes._scenario import resolve_scenario
    from mt_accuracy_ros.sim.machine_tool import simulate

    for scenario in ("demo", "demo_trunnion"):
        machine = resolve_scenario(scenario).machine
        tables = TableCompensation(machine)
        rng = np.random.default_rng(5)
        linear = [a for a in machine.axis_order if not machine.axes[a].is_rotary]
        for axis in linear:
            grid = np.linspace(*machine.axes[axis].stroke, 21)
            columns = [f"{axis}_m"] + [f"E{c}{axis}_{'m' if c in 'XYZ' else 'rad'}"
                                       for c in "XYZABC"]
            values = np.column_stack([grid] + [rng.normal(0, 5e-6, 21) for _ in range(6)])
            assert tables.offer(axis, columns, values.ravel(), ["EC0Y"], [4e-6], 1) is None
        window = simulate(resolve_scenario(scenario), start_index=0, stop_index=2000)
        commands = {a: window.command[a] for a in machine.axis_order}
        whole = tables.correction(commands)
        batches = np.concatenate([tables.correction({a: q[i:i + 10] for a, q in
                                                     commands.items()})
                                  for i in range(0, 2000, 10)])
        np.testing.assert_array_equal(whole, batches)
        assert np.max(np.abs(whole)) > 1e-6   # the tables do something there


def test_loop_phases_split_a_run_and_judge_the_end_state():
    """Closed form: a constant error 4 um removed by a constant correction from t = 10 s."""
    from mt_accuracy_ros.core.workbench.closed_loop import loop_phases

    rng = np.random.default_rng(0)
    t = np.arange(0.0, 40.0, 0.5)
    machine = np.tile([4e-6, -6e-6, 2e-6], (t.size, 1))
    applied = np.where(t[:, None] >= 10.0, -machine, 0.0)
    noise = rng.normal(0.0, 0.5e-6, machine.shape)
    # The end state over the last 10 s: all of it compensated (the default window is 30 s).
    phases = loop_phases(t, machine + applied + noise, applied, [(10.0, "compensated")], 1e-6,
                         end_window_s=10.0)
    assert [p.label for p in phases] == ["whole run", "start", "compensated", "end state"]
    # Without compensation is the machine's own error (the noise on top).
    np.testing.assert_allclose([f.rms for f in phases[0].without], [4e-6, 6e-6, 2e-6], rtol=0.05)
    assert not phases[1].within(1e-6) and phases[-1].within(1e-6)
    np.testing.assert_allclose([f.rms for f in phases[2].with_compensation], 0.5e-6, rtol=0.25)
    assert phases[2].count == int((t >= 11.0).sum())  # 1 s settling left out


def test_a_five_axis_correction_holds_its_rotary_part_with_its_position_part():
    offset = RealtimeOffset(cycle_s=0.001, delay_s=0.0, max_age_s=1.0, rotary_axes=2)
    assert offset.offer(1 * MS, 1 * MS, [1e-6, 0, 0], 1, rotary_rad=[2e-5, -3e-5]) is None
    assert offset.offer(5 * MS, 5 * MS, [2e-6, 0, 0], 1) is None      # position only: zero turn
    values, versions = offset.at_with_rotary(np.array([0, 2, 6]) * MS)
    np.testing.assert_array_equal(values[:, 3:], [[0, 0], [2e-5, -3e-5], [0, 0]])
    np.testing.assert_array_equal(offset.at(np.array([2]) * MS)[0], [[1e-6, 0, 0]])
    assert "not finite" in offset.offer(6 * MS, 6 * MS, [0, 0, 0], 1, rotary_rad=[1e-5])
    assert "not finite" in offset.offer(7 * MS, 7 * MS, [0, 0, 0], 1, rotary_rad=[np.nan, 0])
    assert "degrees" in offset.offer(8 * MS, 8 * MS, [0, 0, 0], 1, rotary_rad=[0.5, 0.0])
    assert offset.statistics.refused == 3
