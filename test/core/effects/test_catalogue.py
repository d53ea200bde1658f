"""The effect catalogue: designs against closed forms and the kinematic chain's second
formulation, user effects, plugins through a real entry point."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from conftest import REPO_ROOT
from mt_accuracy_ros.core.compensation.error_model import ErrorModel, model_from_dict, \
    model_to_dict
from mt_accuracy_ros.core.effects import Context, families, family_named
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.core.kinematics.chain import ErrorOverrides, KinematicModel
from mt_accuracy_ros.core.kinematics.machine import load_machine


def _context(machine_name="kidani_hmc", n=50, seed=0, **kwargs):
    machine = load_machine(machine_name)
    rng = np.random.default_rng(seed)
    positions = {a: rng.uniform(*machine.axes[a].stroke, n) for a in machine.axis_order}
    t = np.arange(n) * 10.0
    variables = Variables(positions, t, {a: rng.normal(0, 0.1, n) for a in positions},
                          temperatures={"column": 20 + 0.01 * t, "bed": 20 + 0.004 * t},
                          **kwargs)
    return Context(machine, variables)


def test_every_family_has_physics_a_name_and_designs_of_the_right_shape():
    ctx = _context()
    seen = set()
    for family in families(plugins=False):
        assert family.name not in seen and family.summary and family.group
        seen.add(family.name)
        for variant in family.variants(ctx)[:2]:
            setting = family.settings(ctx, variant)[0]
            design = family.design(ctx, variant, setting)
            assert design.shape == (ctx.n, 3, len(family.parameter_names(variant, setting)))
            assert np.all(np.isfinite(design))
    assert {"positioning", "positioning_periodic", "straightness", "angular", "squareness",
            "thermal_lag", "thermal_gradient", "heat_source", "thermal_squareness", "reversal",
            "servo_lag", "acceleration", "cross_axis", "rotary_error",
            "rotary_location"} <= seen


def test_angular_error_reaches_the_tcp_through_its_abbe_arm():
    """The design of EBX (pitch of X) equals the first-order chain formulation (a sum of
    joint twists with lever arms, no matrix product) of the same error function."""
    ctx = _context()
    family = family_named("angular")
    setting = {"order": 3}
    coefficients = np.array([2e-6, -1e-6, 0.5e-6])
    error = family.design(ctx, "EBX", setting) @ coefficients
    q = ctx.variables.positions
    pitch = family.motion_error(ctx.machine, "EBX", setting, coefficients, q["X"])
    linear = KinematicModel(ctx.machine).tcp_error_linear(
        q, overrides=ErrorOverrides(motion={"EBX": pitch}, use_description=False))["position"]
    np.testing.assert_allclose(error, linear, atol=1e-12)
    # A pure pitch moves the TCP along x and z but not y, and more with a longer arm.
    assert np.max(np.abs(error[:, 1])) < 1e-12 and np.max(np.abs(error[:, [0, 2]])) > 1e-7


def test_positioning_design_is_the_axis_direction():
    ctx = _context()
    design = family_named("positioning").design(ctx, "EXX", {"order": 1})
    u = ctx.normalised_position("X")
    np.testing.assert_allclose(design[:, 0, 0], u, atol=1e-9)       # tool branch: +x
    np.testing.assert_allclose(design[:, 1:, 0], 0.0, atol=1e-9)
    z = family_named("positioning").design(ctx, "EZZ", {"order": 1})
    np.testing.assert_allclose(z[:, 2, 0], -ctx.normalised_position("Z"), atol=1e-9)  # work


def test_a_fitted_catalogue_effect_round_trips_through_the_model_yaml():
    import yaml

    model = ErrorModel(load_machine("kidani_hmc"), {"positioning_periodic:EXX": {
        "family": "positioning_periodic", "variant": "EXX", "setting": {"period_m": 0.01},
        "coefficients": {"cos1": 1e-6, "sin1": 3e-6, "cos2": 0.0, "sin2": 0.5e-6}},
        "thermal_lag:column": {"family": "thermal_lag", "variant": "column",
                               "setting": {"tau_s": 600.0},
                               "coefficients": {"bx": 1e-6, "by": 0.0, "bz": 2e-6}}})
    ctx = _context()
    v = ctx.variables
    inputs = {"temperatures": v.temperatures, "time_s": v.time_s}
    before = model.tcp_error(v.positions, **inputs, fresh=True)[0]
    again = model_from_dict(yaml.safe_load(yaml.safe_dump(model_to_dict(model))))
    np.testing.assert_allclose(again.tcp_error(v.positions, **inputs, fresh=True)[0], before,
                               atol=1e-15)
    expected_x = 1e-6 * np.cos(2 * np.pi * v.positions["X"] / 0.01) + \
        3e-6 * np.sin(2 * np.pi * v.positions["X"] / 0.01) + \
        0.5e-6 * np.sin(4 * np.pi * v.positions["X"] / 0.01)
    lagged = v.lag("x", v.rise("column"), 600.0)
    np.testing.assert_allclose(before[:, 0], expected_x + 1e-6 * lagged, atol=1e-12)
    # The CNC's per-axis table carries the pitch error itself.
    grid = np.linspace(0, 0.39, 7)
    np.testing.assert_allclose(model.table_motion_errors("X", grid)["EXX"],
                               1e-6 * np.cos(2 * np.pi * grid / 0.01) + 3e-6 * np.sin(
                                   2 * np.pi * grid / 0.01) + 0.5e-6 * np.sin(4 * np.pi * grid /
                                                                            0.01), atol=1e-15)


def test_bad_catalogue_entries_are_refused_at_load():
    machine = load_machine("kidani_hmc")
    with pytest.raises(ParameterError, match="unknown effect family 'wobble'"):
        ErrorModel(machine, {"w": {"family": "wobble", "coefficients": {}}})
    with pytest.raises(ParameterError, match="'coefficients' must give P1, P2"):
        ErrorModel(machine, {"p": {"family": "positioning", "variant": "EXX",
                                   "setting": {"order": 2}, "coefficients": {"P1": 1.0}}})


def test_user_effect_from_yaml_acts_like_a_built_in():
    model = model_from_dict({"machine": "kidani_hmc", "effects": {"twist": {
        "expression": "k * x * y + m * lag(T_column, 300)", "parameters": ["k", "m"],
        "acts_on": ["z", "X"], "values": {"k_z": 2e-5, "m_z": 1e-6, "k_X": 0.0,
                                          "m_X": -3e-7}}}})
    ctx = _context()
    v = ctx.variables
    error = model.tcp_error(v.positions, v.temperatures, time_s=v.time_s, fresh=True)[0]
    lagged = Variables(v.positions, v.time_s).lag("T", v.rise("column"), 300.0)
    np.testing.assert_allclose(error[:, 2], 2e-5 * v.positions["X"] * v.positions["Y"] +
                               1e-6 * lagged, atol=1e-15)
    np.testing.assert_allclose(error[:, 0], -3e-7 * lagged, atol=1e-15)  # along X (tool: +x)


@pytest.mark.parametrize("spec, message", [
    ({"expression": "k * x + 1e-6", "parameters": ["k"], "values": {"k": 0.0}},
     "not linear in its parameters"),
    ({"expression": "k * k * x", "parameters": ["k"], "values": {"k": 0.0}}, "not linear"),
    ({"expression": "k * q", "parameters": ["k"], "values": {"k": 0.0}}, "unknown variable 'q'"),
    ({"expression": "k * x", "parameters": ["j"]}, "do not appear"),
    ({"expression": "k * x", "parameters": ["k"], "acts_on": "w"}, "acts_on 'w'"),
    ({"expression": "k * x.real", "parameters": ["k"]}, "attribute access"),
])
def test_bad_user_effects_name_themselves(spec, message):
    with pytest.raises(ParameterError, match=message) as caught:
        model = model_from_dict({"machine": "kidani_hmc", "effects": {"mine": spec}})
        ctx = _context()
        model.tcp_error(ctx.variables.positions, ctx.variables.temperatures,
                        time_s=ctx.variables.time_s, fresh=True)
    assert "mine" in str(caught.value)


def test_an_installed_plugin_is_a_candidate_everywhere(tmp_path):
    """A real distribution (dist-info with entry_points.txt) on the path: the workbench
    offers its family, the model evaluates it, and a broken plugin is named."""
    site = tmp_path / "site"
    package = site / "my_effects"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text(textwrap.dedent('''
        import numpy as np
        from mt_accuracy_ros.core.effects import EffectFamily, per_component

        class Sag(EffectFamily):
            name = "gantry_sag"
            group = "user"
            summary = "the beam sags with the carriage's distance from its middle"
            def variants(self, ctx):
                return ["Y"]
            def parameter_names(self, variant, setting):
                return ["sz"]
            def design(self, ctx, variant, setting):
                q = ctx.normalised_position(variant)
                return per_component(1.0 - q ** 4)[:, :, 2:]
        '''))
    info = site / "my_effects-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: my-effects\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[mt_accuracy_ros.effects]\nsag = my_effects:Sag\n")
    script = textwrap.dedent('''
        import numpy as np
        from mt_accuracy_ros.core.compensation.error_model import ErrorModel
        from mt_accuracy_ros.core.kinematics.machine import load_machine
        from mt_accuracy_ros.core.workbench.diagnosis import Observations, diagnose
        machine = load_machine("kidani_hmc")
        rng = np.random.default_rng(1)
        n = 300
        pos = {a: rng.uniform(*machine.axes[a].stroke, n) for a in "XYZ"}
        u = (2 * pos["Y"] + 0.44) / 0.44
        truth = np.outer(1 - u ** 4, [0.0, 0.0, 5e-6])
        obs = Observations(pos, truth + rng.normal(0, 0.5e-6, truth.shape),
                           np.ones((n, 3), bool), np.arange(n) * 10.0, uncertainty_m=1e-6)
        d = diagnose(ErrorModel(machine, {}), obs, localise_residual=False)
        print("FOUND", d.found.name)
        model = ErrorModel(machine, {"sag": {"family": "gantry_sag", "variant": "Y",
                                             "coefficients": {"sz": 5e-6}}})
        print("MAX", float(np.max(np.abs(model.tcp_error(pos)[0] - truth))))
        ''')
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), str(REPO_ROOT)])}
    done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "FOUND gantry_sag:Y" in done.stdout
    assert float(done.stdout.split("MAX")[1]) < 1e-15
    (info / "entry_points.txt").write_text("[mt_accuracy_ros.effects]\nsag = my_effects:Nope\n")
    broken = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                            text=True, timeout=120)
    assert broken.returncode != 0
    assert "effect plugin 'sag' (my_effects:Nope): cannot be loaded" in broken.stderr


def test_the_quick_look_for_plugins_misses_none(tmp_path, monkeypatch):
    """Without any entry_points.txt naming the group the catalogue skips the slow scan;
    one that names it, or a zip on the path, leaves the answer to importlib.metadata."""
    from mt_accuracy_ros.core.effects.user import _entry_point_files_may_name

    assert not _entry_point_files_may_name("no.such.group.anywhere")
    info = tmp_path / "other-1.0.dist-info"
    info.mkdir()
    (info / "entry_points.txt").write_text("[no.such.group.anywhere]\nx = y:z\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert _entry_point_files_may_name("no.such.group.anywhere")
    monkeypatch.syspath_prepend(str(tmp_path / "archive.zip"))
    (tmp_path / "archive.zip").write_bytes(b"PK")
    assert _entry_point_files_may_name("another.group")
