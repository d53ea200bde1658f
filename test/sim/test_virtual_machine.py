"""The virtual machine tool: determinism, scenario errors, and each effect's signature."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.scales.dual_scale import (parallelism_yaw_error, scale_expansion,
                                             thermal_yaw_error, timing_yaw_error, yaw_from_scales)
from mt_accuracy_ros.core.errors import ScenarioError
from mt_accuracy_ros.core.kinematics.chain import ErrorOverrides, KinematicModel
from mt_accuracy_ros.sim.effects import EFFECTS
from mt_accuracy_ros.sim.machine_tool import simulate
from mt_accuracy_ros.sim.scenario import scenario_from_yaml

QUIET = "noise: {scale_m: 0, resolution_m: 0, scale_accuracy_fraction: 0, thermocouple_k: 0, " \
        "thermocouple_resolution_k: 0}\n"


def _run(effects: str = "{}", program: str = "{type: back_and_forth, axes: [X, Y, Z], "
         "feed_m_per_min: 12}", duration: float = 20.0, rate: float = 500.0, extra: str = ""):
    return simulate(scenario_from_yaml(
        f"machine: kidani_hmc\nseed: 4\nduration_s: {duration}\nsample_rate_hz: {rate}\n"
        f"program: {program}\neffects: {effects}\n{QUIET}{extra}"))


def _apparent_yaw(result, axis):
    a = axis.lower()
    yaw = yaw_from_scales(result.channel(f"{a}1"), result.channel(f"{a}2"),
                          result.scale_distance_m[axis])
    return yaw - result.yaw_truth[axis]


def test_same_seed_same_data_new_noise_seed_same_machine():
    text = "machine: kidani_hmc\nseed: 9\nduration_s: 5\nsample_rate_hz: 1000\n"
    a, b = simulate(scenario_from_yaml(text)), simulate(scenario_from_yaml(text))
    np.testing.assert_array_equal(a.scale_readings, b.scale_readings)
    np.testing.assert_array_equal(a.temperatures_c, b.temperatures_c)
    c = simulate(scenario_from_yaml(text + "noise_seed: 10\n"))
    np.testing.assert_array_equal(a.yaw_truth["X"], c.yaw_truth["X"])  # same machine
    assert not np.array_equal(a.scale_readings, c.scale_readings)       # new noise


def test_effect_list_is_complete_and_documented():
    required = {"scale_thermal_expansion", "structural_thermal_drift",
                "position_dependent_thermal", "timing_skew", "scale_parallelism",
                "guideway_deterioration", "abbe_offset", "squareness",
                "spindle_thermal_growth", "reversal"}
    assert required <= set(EFFECTS)
    for spec in EFFECTS.values():
        assert spec.equation and spec.reference and spec.acts_on in ("scales", "tcp", "both")


@pytest.mark.parametrize("text, message", [
    ("machine: kidani_hmc\neffects:\n  warp_drive: true\n", "line 3: unknown effect 'warp_drive'"),
    ("machine: kidani_hmc\nsample_rate_hz: -5\n", "line 2: sample_rate_hz = -5 must be >= 100"),
    ("machine: kidani_hmc\nsample_rate_hz: 50000\n", "line 2: sample_rate_hz"),
    ("machine: kidani_hmc\nprogram:\n  type: back_and_forth\n  axes: [X]\n  end_m: 0.5\n",
     "line 5: end_m = 0.5 m is outside the X stroke"),
    ("machine: kidani_hmc\neffects:\n  timing_skew: {skew: 1}\n",
     "line 3: effect timing_skew has no parameter 'skew'"),
    ("machine: kidani_hmc\nduration_s: 10\nevents:\n  - {time_s: 20, enable: reversal}\n",
     "line 4: event at 20 s is after the end"),
    ("machine: kidani_hmc\nprogram: {type: teleport}\n", "line 2: unknown program 'teleport'"),
    ("machine: no_such_machine\n", "line 1"),
    ("seed: 3\n", "'machine' is required"),
    ("machine: kidani_hmc\ncolour: blue\n", "line 2: unknown key 'colour'"),
    ("machine: kidani_hmc\nprogram: {type: back_and_forth, feed_m_per_min: 90}\n",
     "exceeds the machine's 60 m/min"),
])
def test_bad_scenarios_name_the_line(text, message):
    with pytest.raises(ScenarioError, match=message.replace("(", r"\(").replace(")", r"\)")):
        scenario_from_yaml(text)


def test_geometric_yaw_is_seen_by_the_scales_exactly():
    result = _run()
    np.testing.assert_allclose(_apparent_yaw(result, "Y"), 0.0, atol=1e-15)
    assert np.ptp(result.yaw_truth["Y"]) > 2e-6


def test_scale_thermal_expansion_signature():
    """Apparent yaw = -(dL2 - dL1)/D, growing with (dT1 - dT2) x (eq. 3.17)."""
    result = _run("{scale_thermal_expansion: {time_constant_s: 5, rise_scale_1_k: 3, "
                  "rise_scale_2_k: 1}}", duration=30)
    apparent = _apparent_yaw(result, "Y")
    low, high = result.scenario.machine.axes["Y"].stroke
    travel = result.actual["Y"] - low
    idx = np.arange(0, travel.size, 97)
    t_index = np.minimum(np.searchsorted(result.temperature_time_s, result.time_s[idx]),
                         result.temperature_time_s.size - 1)
    sensors = result.thermocouple_positions_m["y1"]
    names = result.temperature_names
    expected = []
    for j, i in zip(t_index, idx):
        rises = [np.interp(result.time_s[i], result.temperature_time_s,
                           result.temperatures_true_c[:, names.index(f"y{s}_s{m}")]
                           - result.temperatures_true_c[0, names.index(f"y{s}_s{m}")])
                 for s in (1, 2) for m in range(sensors.size)]
        r1, r2 = np.array(rises[:sensors.size]), np.array(rises[sensors.size:])
        fine = np.linspace(0, high - low, 2001)
        dl1 = scale_expansion(travel[i:i + 1], np.interp(fine, sensors, r1), 12e-6,
                              sensor_positions_m=fine)
        dl2 = scale_expansion(travel[i:i + 1], np.interp(fine, sensors, r2), 12e-6,
                              sensor_positions_m=fine)
        expected.append(thermal_yaw_error(travel[i:i + 1], dl1, dl2, 0.6)[0])
    expected = np.array(expected)
    # The closed form and the thermocouple-interpolated integral agree to the interpolation error.
    np.testing.assert_allclose(apparent[idx], expected, atol=0.03 * np.abs(expected).max() + 1e-12)
    late = idx[result.time_s[idx] > 20]
    slope = np.polyfit(travel[late], apparent[late], 1)[0]
    # Scale 1 warmer reads shorter than scale 2: (x2 - x1)/D grows by C (dT1 - dT2) / D per
    # metre of travel, dT1 - dT2 between its smallest and largest along the scale.
    final = result.temperatures_true_c[-1]
    difference = [final[result.temperature_names.index(f"y1_s{m}")] -
                  final[result.temperature_names.index(f"y2_s{m}")] for m in range(sensors.size)]
    assert 12e-6 * min(difference) / 0.6 * 0.8 < slope < 12e-6 * max(difference) / 0.6 * 1.2
    assert min(difference) > 0


def test_timing_skew_signature():
    result = _run("{timing_skew: {skew_s: 1e-4}}")
    expected = timing_yaw_error(result.velocity["X"], 1e-4, result.scale_distance_m["X"])
    np.testing.assert_allclose(_apparent_yaw(result, "X"), expected, atol=1e-12)
    assert np.abs(expected).max() > 1e-5


def test_scale_parallelism_signature():
    result = _run("{scale_parallelism: {delta_rad: 2e-3}}")
    low = result.scenario.machine.axes["Z"].stroke[0]
    expected = parallelism_yaw_error(result.actual["Z"] - low, 2e-3, result.scale_distance_m["Z"])
    np.testing.assert_allclose(_apparent_yaw(result, "Z"), expected, atol=1e-13)


def _tcp_difference(effect_yaml: str, **kwargs):
    on = _run(effect_yaml, **kwargs)
    off = _run("{}", **kwargs)
    idx = np.arange(0, on.time_s.size, 50)
    return on, idx, on.tcp_error(idx) - off.tcp_error(idx)


def test_structural_drift_is_position_independent_and_follows_the_column():
    on, idx, diff = _tcp_difference("{structural_thermal_drift: {time_constant_s: 10, "
                                    "beta_m_per_k: [1e-6, 4e-6, 2e-6]}}", duration=30)
    column = on.thermal_at("column", idx)
    np.testing.assert_allclose(diff, np.outer(column, [1e-6, 4e-6, 2e-6]), atol=1e-12)
    assert column[-1] > 0.5


def test_position_dependent_thermal_grows_with_position_and_temperature():
    on, idx, diff = _tcp_difference("{position_dependent_thermal: {axis: X, time_constant_s: 10}}",
                                    duration=30)
    expected = 11e-6 * on.actual["X"][idx] * on.thermal_at("bed", idx)
    np.testing.assert_allclose(diff[:, 0], expected, atol=2e-9 + 1e-3 * np.abs(expected).max())
    assert np.abs(expected).max() > 1e-6


def test_abbe_offset_is_angular_error_times_offset():
    on, idx, diff = _tcp_difference("{abbe_offset: {offset_m: [0.1, 0.0, 0.2]}}")
    _, orientation = on.tcp_error(idx, with_orientation=True)
    np.testing.assert_allclose(diff, np.cross(orientation, [0.1, 0.0, 0.2]), atol=1e-15)
    assert np.abs(diff).max() > 1e-7


def test_squareness_is_linear_in_the_other_axis():
    on, idx, diff = _tcp_difference("{squareness: {errors_rad: {EC0Y: 50e-6}}}")
    model = KinematicModel(on.scenario.machine)
    positions = {a: on.actual[a][idx] for a in on.scenario.machine.axis_order}
    alone = model.tcp_error(positions, overrides=ErrorOverrides(
        location={"EC0Y": 50e-6}, use_description=False), check_stroke=False)["position"]
    np.testing.assert_allclose(diff, alone, atol=5e-9)  # second-order cross terms only
    slope = np.polyfit(on.actual["Y"][idx], diff[:, 0], 1)[0]
    assert slope == pytest.approx(-50e-6, rel=0.05)


def test_spindle_growth_is_a_first_order_response():
    spindle = "spindle: {speed_rpm: 15000, max_rpm: 15000, intervals_s: [[0, 100]]}\n"
    on, idx, diff = _tcp_difference("{spindle_thermal_growth: "
                                    "{time_constant_s: 10, growth_m: 2e-5}}",
                                    duration=40, extra=spindle)
    t = on.time_s[idx]
    expected = 2e-5 * (1 - np.exp(-t / 10))  # exact at the 1 Hz thermal steps, linear between
    np.testing.assert_allclose(diff[:, 2], expected, atol=2e-5 * (1 / 10) ** 2 / 8 * 1.5)
    assert diff[-1, 2] > 0.95 * 2e-5


@pytest.mark.parametrize("effect, expected", [
    ("{reversal: {backlash_m: 1e-5, axes: [X]}}", "reversal"),
    ("{servo_lag: {lag_s: 1e-3, axes: [X]}}", "lag"),
])
def test_drive_effects_move_the_axis_off_its_command(effect, expected):
    result = _run(effect)
    deviation = result.actual["X"] - result.command["X"]
    v = result.velocity["X"]
    moving = np.abs(v) > 1e-3
    if expected == "reversal":
        np.testing.assert_allclose(deviation[moving], -np.sign(v[moving]) * 5e-6, atol=1e-15)
    else:
        np.testing.assert_allclose(deviation, -v * 1e-3, atol=1e-15)
    idx = np.flatnonzero(moving)[::40]
    error = result.tcp_error(idx)
    reference = _run("{}").tcp_error(idx)
    # Equal up to the geometric errors' change over the deviation (<< 1e-3 of it).
    np.testing.assert_allclose(error[:, 0] - reference[:, 0], deviation[idx],
                               atol=1e-3 * np.abs(deviation).max())


def test_guideway_deterioration_changes_yaw_after_the_event_over_part_of_the_stroke():
    result = _run("{guideway_deterioration: {enabled: false, axis: Y, start_m: -0.16, end_m: 0.0}}",
                  extra="events:\n  - {time_s: 10, enable: guideway_deterioration}\n")
    off = _run("{}")
    change = result.yaw_truth["Y"] - off.yaw_truth["Y"]
    q = result.actual["Y"]
    assert np.all(change[result.time_s < 10] == 0.0)
    late = result.time_s >= 10
    assert np.all(change[late & (q < -0.16)] == 0.0)
    assert change[late].max() > 0
    idx = np.flatnonzero(late & (q > -0.001))[:5]
    tcp = result.tcp_error(idx) - off.tcp_error(idx)
    assert np.linalg.norm(tcp, axis=1) == pytest.approx(np.full(idx.size, 22e-6), rel=0.02)


def test_thermocouples_every_110_mm_and_structure_sensors():
    result = _run("{scale_thermal_expansion: {time_constant_s: 5}}", duration=10)
    positions = result.thermocouple_positions_m["y1"]
    np.testing.assert_allclose(np.diff(positions)[:-1], 0.11)
    assert positions[-1] == pytest.approx(0.44)
    assert {"column", "bed", "spindle", "ambient"} <= set(result.temperature_names)
    # The drive end (s = 0), where half the heat enters, is the warmest (FE field).
    final = result.temperatures_true_c[-1]
    along = [final[result.temperature_names.index(f"y1_s{m}")] for m in range(positions.size)]
    assert along[0] == max(along) and along[0] > along[-1]


def test_runs_at_20_khz_with_six_heads():
    result = _run(duration=2.0, rate=20000.0)
    assert result.scale_readings.shape == (40000, 6)
    assert np.all(np.isfinite(result.scale_readings))


@pytest.mark.parametrize("program, moving", [
    ("{type: diagonal, kind: body, steps: 4, dwell_s: 0.2, feed_m_per_min: 20}", "XYZ"),
    ("{type: diagonal, kind: face, steps: 4, dwell_s: 0.2, feed_m_per_min: 20}", "XY"),
])
def test_five_axis_grinder_runs_diagonals(program, moving):
    from mt_accuracy_ros.sim.scenario import scenario_from_yaml as parse

    result = simulate(parse("machine: khan_chen_rpppr\nseed: 1\nduration_s: 8\n"
                            "sample_rate_hz: 200\n"
                            f"program: {program}\neffects: {{squareness: true}}\n"))
    assert result.scale_readings.shape[1] == 6  # X, Y, Z pairs at the default distance
    for axis in "XYZ":
        assert (np.ptp(result.command[axis]) > 0.1) == (axis in moving)
    # Along a diagonal all moving axes travel in proportion (ISO 230-6).
    lows = {a: result.scenario.machine.axes[a].stroke[0] for a in moving}
    spans = {a: np.ptp(result.scenario.machine.axes[a].stroke) for a in moving}
    fractions = np.array([(result.command[a] - lows[a]) / spans[a] for a in moving])
    np.testing.assert_allclose(fractions, fractions[0][None, :].repeat(len(moving), 0), atol=1e-12)
    groups = result.dwell_groups(settle_s=0.05)
    assert len(groups) >= 5
    error = result.tcp_error(np.array([g[0] for g in groups]))
    assert np.all(np.isfinite(error)) and np.abs(error).max() > 1e-7


def test_a_window_of_a_run_equals_the_whole_run_there():
    from mt_accuracy_ros.sim.scenario import scenario_from_yaml as parse

    scenario = parse("machine: kidani_hmc\nseed: 5\nduration_s: 20\nsample_rate_hz: 5000\n"
                     "program: {type: back_and_forth, axes: [X, Y], feed_m_per_min: 20}\n"
                     "effects: {reversal: true, servo_lag: true, timing_skew: true, "
                     "scale_thermal_expansion: {time_constant_s: 30}}\n")
    whole = simulate(scenario)
    for start, stop in ((0, 1000), (65000, 70001), (99_000, 100_000)):
        part = simulate(scenario, start_index=start, stop_index=stop)
        assert part.first_index == start
        np.testing.assert_array_equal(part.scale_readings, whole.scale_readings[start:stop])
        np.testing.assert_array_equal(part.actual["X"], whole.actual["X"][start:stop])
        np.testing.assert_array_equal(part.temperatures_c, whole.temperatures_c)


def test_a_scenario_at_its_limits_runs_or_is_refused_naming_the_limit():
    """Issue 29: duration_s 1e7 at 20 kHz passed validation and then tried to allocate
    1.46 TiB. Now the scenario names its limit at load, and a whole-run simulation too
    large to hold is refused before anything is allocated - while the same run streamed
    in windows (as the nodes do) still works."""
    with pytest.raises(ScenarioError, match="thermal steps.*at most"):
        scenario_from_yaml("machine: kidani_hmc\nduration_s: 1.0e7\nsample_rate_hz: 20000\n")
    long_run = scenario_from_yaml("machine: kidani_hmc\nduration_s: 1.2e5\n"
                                  "sample_rate_hz: 20000\n")
    with pytest.raises(ScenarioError, match="samples at once.*simulate it in windows"):
        simulate(long_run)
    window = simulate(long_run, start_index=10**9, stop_index=10**9 + 2000)
    assert window.time_s.size == 2000 and np.all(np.isfinite(window.time_s))
    assert window.time_s[0] == pytest.approx(10**9 / 20000)
