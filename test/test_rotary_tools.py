"""``mt-accuracy ballbar|probe|export`` end to end: files in, numbers, report and JSON out;
every bad input a one-line error with exit 2 and nothing written half (issue 20)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from mt_accuracy_ros.cli import main
from mt_accuracy_ros.core.rotary.ballbar import ARCSEC


def _one_line_error(capsys, argv) -> str:
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in captured.err, captured.err
    return lines[0]


def test_ballbar_from_the_virtual_table_to_report_and_json(tmp_path, capsys):
    data = tmp_path / "bb.csv"
    assert main(["ballbar", str(data), "--simulate", "3", "--backlash", "--report",
                 str(tmp_path / "r" / "bb.html"), "--json", str(tmp_path / "bb.json")]) == 0
    out = capsys.readouterr().out
    assert "lost motion (backlash)" in out
    summary = json.loads((tmp_path / "bb.json").read_text())
    assert summary["positions"] == 37 and summary["repetitions"] == [3, 3]
    assert summary["l2"]["tilt_x_arcsec"] == pytest.approx(7.93, abs=0.6)
    assert summary["l2"]["axial_um"] == pytest.approx(2.68, abs=0.2)
    assert summary["linf"]["max_abs_residual_m2"] <= summary["l2"]["max_abs_residual_m2"]
    assert summary["l2"]["rms_residual_m2"] <= summary["linf"]["rms_residual_m2"]
    assert any(j["significant"] for j in summary["reversal_jumps"])
    html = (tmp_path / "r" / "bb.html").read_text()
    assert "Zhu Fig. 5.12" in html and "bb_ballbar_residuals.png" in html
    assert (tmp_path / "r" / "bb_ballbar_data.png").stat().st_size > 10_000


def test_ballbar_file_errors_are_one_line(tmp_path, capsys):
    assert main(["ballbar", str(tmp_path / "ok.csv"), "--simulate", "0"]) == 0
    capsys.readouterr()
    lines = (tmp_path / "ok.csv").read_text().splitlines()
    # a long-bar reading lost
    (tmp_path / "gap.csv").write_text("\n".join(lines[:-1]) + "\n")
    assert "no reading at 360 deg" in _one_line_error(capsys, ["ballbar",
                                                               str(tmp_path / "gap.csv")])
    (tmp_path / "nan.csv").write_text("\n".join(lines[:4] + [lines[4].rsplit(",", 1)[0] + ",nan"]
                                                + lines[5:]) + "\n")
    assert "line 5: change_um is nan" in _one_line_error(capsys, ["ballbar",
                                                                  str(tmp_path / "nan.csv")])
    assert "cannot reach" in _one_line_error(capsys, ["ballbar", str(tmp_path / "ok.csv"),
                                                      "--radius-mm", "95"])
    (tmp_path / "one.csv").write_text("\n".join(row for row in lines if not row.startswith("217"))
                                      + "\n")
    assert "needs a short and a long bar" in _one_line_error(
        capsys, ["ballbar", str(tmp_path / "one.csv")])
    assert "missing column(s) change_um" in _one_line_error(
        capsys, ["ballbar", str(_write(tmp_path / "cols.csv", "bar_mm,repetition,angle_deg\n"))])


def _write(path, text):
    path.write_text(text)
    return path


def test_probe_from_the_virtual_machine(tmp_path, capsys):
    data = tmp_path / "probe.csv"
    assert main(["probe", str(data), "--simulate", "4", "--json", str(tmp_path / "p.json"),
                 "--report", str(tmp_path / "p.html")]) == 0
    summary = json.loads((tmp_path / "p.json").read_text())
    truth = {"EY0A": 20e-6, "EZ0A": -15e-6, "EB0A": 30e-6, "EC0A": -25e-6, "EA0B": 15e-6,
             "EC0B": -20e-6}
    for name, value in truth.items():
        assert abs(summary["parameters"][name] - value) <= \
            3 * summary["uncertainties_k1"][name] + 1e-9, name
    assert summary["repeatability_m"] < 1e-6 and summary["dispersion_after_m"] < 3e-6
    # Both zero angles are taken out where the sphere and the probe were set up; B turns
    # the probe about its actual line, so its offsets are seen (none here), the one along
    # the probe being a probe length's twin - all said.
    assert summary["not_observable"] == ["EA0A", "EB0B"]
    for name in ("EX0B", "EZ0B"):
        assert abs(summary["parameters"][name]) <= 3 * summary["uncertainties_k1"][name]
    assert set(summary["probe_length_aliases"]) == {"EZ0B"}
    assert summary["identified_as"]["EZ0A"] == "EZ0A"
    assert "where the rotary axes really are" in (tmp_path / "p.html").read_text()


def test_probe_refuses_a_stray_touch_by_cycle(tmp_path, capsys):
    data = tmp_path / "probe.csv"
    assert main(["probe", str(data), "--simulate", "4"]) == 0
    capsys.readouterr()
    lines = data.read_text().splitlines()
    fields = lines[30].split(",")
    fields[-1] = f"{float(fields[-1]) + 3.0:.6f}"          # 3 mm off: touched the clamp
    lines[30] = ",".join(fields)
    data.write_text("\n".join(lines) + "\n")
    error = _one_line_error(capsys, ["probe", str(data)])
    assert f"cycle {fields[0]}: touch point" in error and "from the sphere" in error


def test_export_writes_reads_back_and_refuses_a_bad_spacing(tmp_path, capsys):
    machine = tmp_path / "machine.yaml"
    import yaml

    from conftest import REPO_ROOT

    data = yaml.safe_load((REPO_ROOT / "mt_accuracy_ros" / "machines" / "kidani_hmc.yaml")
                          .read_text())
    data["axes"]["X"]["errors"] = {"EXX": {"polynomial": [0.0, 2e-5, -4e-5]}}
    machine.write_text(yaml.safe_dump(data))
    model = tmp_path / "model.yaml"
    model.write_text(yaml.safe_dump({"machine": str(machine), "effects": {
        "reversal": {"backlash_m": 4e-6, "axes": ["X"]}}}))
    out = tmp_path / "tables"
    assert main(["export", str(model), "--spacing-mm", "10", "--out", str(out), "--json",
                 str(tmp_path / "e.json")]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["X_bilateral.csv", "Y_bilateral.csv",
                                                     "Z_bilateral.csv", "volumetric_isg.csv"]
    summary = json.loads((tmp_path / "e.json").read_text())
    assert summary["tcp_max_error_m"] <= summary["tcp_bound_m"]
    x = np.loadtxt(out / "X_bilateral.csv", delimiter=",", comments="#", skiprows=6)
    np.testing.assert_allclose(x[:, 2] - x[:, 1], 4e-3, atol=1e-9)   # mm: the backlash
    empty = tmp_path / "nothing"
    assert "exceeds the Z stroke" in _one_line_error(
        capsys, ["export", str(model), "--spacing-mm", "900", "--out", str(empty)])
    assert not empty.exists()


def test_export_carries_a_fitted_rotary_line_and_says_what_no_file_holds(tmp_path, capsys):
    """A C-centre offset the workbench named is in the volumetric file's location block; a
    rotary axis' own run-out (no table of a linear axis holds it) is said, with its size."""
    import yaml

    model = tmp_path / "model.yaml"
    model.write_text(yaml.safe_dump({"machine": "trunnion_ac", "effects": {
        "rotary_location:C": {"family": "rotary_location", "variant": "C", "setting": {},
                              "coefficients": {"EX0C": 20e-6, "EY0C": 0.0, "EA0C": 0.0,
                                               "EB0C": 0.0}},
        "rotary_error:EZA": {"family": "rotary_error", "variant": "EZA",
                             "setting": {"harmonics": 1},
                             "coefficients": {"cos1": 5e-6, "sin1": -3e-6}},
        # A's tilt EB0A folded into its offset EZ0A (poses that could not part them), and
        # the survey's own set-up: both said, neither judged as a machine error left out.
        "rotary_location:A": {"family": "rotary_location", "variant": "A",
                              "setting": {"inseparable": "EB0A=EZ0A*-0.1"},
                              "coefficients": {"EY0A": 0.0, "EZ0A": 5e-6, "EC0A": 0.0}},
        "setup_location:work": {"family": "setup_location", "variant": "work", "setting": {},
                                "coefficients": {"v_x": 1e-6, "v_y": 0.0, "v_z": 0.0}}}}))
    out = tmp_path / "tables"
    assert main(["export", str(model), "--spacing-mm", "10", "--out", str(out), "--json",
                 str(tmp_path / "e.json")]) == 0
    said = capsys.readouterr().out
    assert "does not hold rotary_error:EZA" in said and "in real time" in said
    assert "rotary_location:C" not in said
    assert "rotary_location:A: " in said and "EZ0A stands for" in said
    assert "setup_location:work is where the survey's work or tool was located" in said
    lines = (out / "volumetric_isg.csv").read_text().splitlines()
    block = lines.index("// location errors (constant)")
    assert dict(zip(lines[block + 1].split(), map(float, lines[block + 2].split())))[
        "EX0C"] == pytest.approx(0.020)                          # mm
    summary = json.loads((tmp_path / "e.json").read_text())
    assert list(summary["not_in_file"]) == ["rotary_error:EZA"]


def test_arcsec_is_the_unit_zhu_uses():
    assert 1 / ARCSEC == pytest.approx(206264.806247, rel=1e-9)


def test_the_instruments_measure_the_five_axis_scenarios_own_machine(tmp_path, capsys):
    """--scenario: the probe and the ball bar read the virtual machine the live graph runs
    (demo_5axis's rotary_location), not a truth of their own."""
    from mt_accuracy_ros.core.rotary.ballbar import ARCSEC
    from mt_accuracy_ros.nodes._scenario import resolve_scenario

    truth = resolve_scenario("demo_5axis").parameters("rotary_location")["errors"]
    assert main(["probe", str(tmp_path / "p.csv"), "--simulate", "2", "--scenario", "demo_5axis",
                 "--json", str(tmp_path / "p.json")]) == 0
    summary = json.loads((tmp_path / "p.json").read_text())
    for name in ("EB0A", "EC0A", "EA0B", "EC0B", "EY0A", "EZ0A"):
        # The offsets the scenario leaves at zero come out at zero.
        assert abs(summary["parameters"][name] - truth.get(name, 0.0)) <= \
            3 * summary["uncertainties_k1"][name] + 1e-9, name
    assert summary["not_observable"] == ["EA0A", "EB0B"]   # zero angles: said so
    assert main(["ballbar", str(tmp_path / "b.csv"), "--simulate", "2", "--scenario",
                 "demo_5axis", "--axis", "A", "--json", str(tmp_path / "b.json")]) == 0
    result = json.loads((tmp_path / "b.json").read_text())
    # A turns about X: Zhu's table frame is (Y, Z, X), so E_x = EB0A and E_y = EC0A.
    l2 = result["l2"]
    assert abs(l2["tilt_x_rad"] - truth["EB0A"]) < 0.5 * ARCSEC
    assert abs(l2["tilt_y_rad"] - truth["EC0A"]) < 0.5 * ARCSEC


def test_export_writes_what_a_control_loads_and_refuses_what_cannot_hold_the_model(
        tmp_path, capsys):
    """Issue 30: the default spacing holds a 10 mm pitch (8 points a period, within the
    band); a spacing that cannot is refused with one that can; a typo's 100 MB is refused;
    the SINUMERIK and FANUC files say what the control's point limit leaves."""
    from mt_accuracy_ros.cli import main

    model = tmp_path / "model.yaml"
    model.write_text(
        "machine: kidani_hmc\neffects:\n  positioning_periodic:EXX:\n"
        "    family: positioning_periodic\n    variant: EXX\n    setting: {period_m: 0.01}\n"
        "    coefficients: {cos1: 2.0e-06, sin1: 1.0e-06, cos2: 0.0, sin2: 0.0}\n")
    assert main(["export", str(model), "--out", str(tmp_path / "t")]) == 0
    out = capsys.readouterr().out
    assert "spacing 1.25 mm, chosen for a band of 1 um" in out
    tcp = float(out.split("at most ")[1].split(" um")[0])
    assert tcp <= 1.0
    for flags, words in ((["--spacing-mm", "5"], "a spacing that holds it: 1.25 mm"),
                         (["--spacing-mm", "0.001"], "refused above 100000")):
        assert main(["export", str(model), "--out", str(tmp_path / "u"), *flags]) == 2
        err = capsys.readouterr().err.strip()
        assert words in err and "\n" not in err
    assert not (tmp_path / "u").exists()
    assert main(["export", str(model), "--out", str(tmp_path / "s"), "--controller",
                 "siemens", "--json", str(tmp_path / "s.json")]) == 0
    out = capsys.readouterr().out
    assert (tmp_path / "s" / "AX_EEC.INI").read_text().startswith("%_N_AX_EEC_INI")
    assert "the control holds 200 points per axis" in out
    assert main(["export", str(model), "--out", str(tmp_path / "f"), "--controller",
                 "fanuc"]) == 0
    assert (tmp_path / "f" / "PITCH_ERROR.TXT").read_text().splitlines()[2].startswith("N3620")
    assert main(["export", str(model), "--out", str(tmp_path / "i"), "--controller",
                 "twincat", "--unilateral"]) == 0
    lists = sorted(p.name for p in (tmp_path / "i").iterdir())
    assert lists == ["achskw1.lis", "achskw2.lis", "achskw3.lis"]
    text = (tmp_path / "i" / "achskw1.lis").read_text()
    assert "kw.ssfk.bilateral           0" in text and ".neg" not in text
    assert main(["export", str(model), "--out", str(tmp_path / "l"), "--controller",
                 "linuxcnc", "--comp-file-type", "1"]) == 0
    out = capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / "l").iterdir()) == ["X.comp", "Y.comp", "Z.comp"]
    assert "[JOINT_0] COMP_FILE = X.comp COMP_FILE_TYPE = 1" in out
    assert all(len(line.split()) == 3 for line in
               (tmp_path / "l" / "X.comp").read_text().splitlines())


def _rewrite(path, column, change):
    """The CSV at ``path`` with ``change(value)`` applied to every cell of ``column``."""
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    j = header.index(column)
    out = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        cells[j] = f"{change(float(cells[j])):.9g}"
        out.append(",".join(cells))
    path.write_text("\n".join(out) + "\n")


def test_rotary_tools_judge_their_own_fits(tmp_path, capsys):
    """Issue 30: radians in a degree column, a 5 degree arc, every reading at one angle
    and a tool 20 um longer than assumed gave confident nonsense; now each is refused or
    flagged, and the repeatability is printed."""
    import math

    from mt_accuracy_ros.cli import main

    data = tmp_path / "bb.csv"
    assert main(["ballbar", str(data), "--simulate", "1"]) == 0
    out = capsys.readouterr().out
    assert "repeatability" in out and "misfit" not in out
    for change, words in ((math.radians, "radians in the angle_deg column"),
                          (lambda a: a / 72.0, "span only 5 deg"),
                          (lambda a: 30.0, "every reading is at 30.000 deg")):
        broken = tmp_path / "broken.csv"
        broken.write_text(data.read_text())
        _rewrite(broken, "angle_deg", change)
        assert main(["ballbar", str(broken)]) == 2
        err = capsys.readouterr().err.strip()
        assert words in err and "\n" not in err
    # A unit slip in R_x scales the design: the fit is as close, its tilts ten times too
    # large - said, with what to check.
    assert main(["ballbar", str(data), "--radius-mm", "7.1842"]) == 0
    assert "implausible: a tilt of 9" in capsys.readouterr().out

    probe = tmp_path / "p.csv"
    assert main(["probe", str(probe), "--simulate", "4"]) == 0
    out = capsys.readouterr().out
    assert "repeatability of repeated cycles" in out and "condition number" in out
    assert "misfit" not in out
    radians = tmp_path / "p_rad.csv"
    radians.write_text(probe.read_text())
    _rewrite(radians, "A_deg", math.radians)
    assert main(["probe", str(radians)]) == 2
    assert "radians in the A_deg column" in capsys.readouterr().err
    # A tool 20 um longer than the cycle assumed: every centre off by what the longer
    # tool moves the tip at that configuration (the tilting head turns it).
    from dataclasses import replace

    import numpy as np

    from mt_accuracy_ros.core.kinematics.chain import KinematicModel
    from mt_accuracy_ros.core.kinematics.machine import load_machine
    from mt_accuracy_ros.io.rotary_csv import probing_csv_text
    from mt_accuracy_ros.sim.rotary_instruments import ProbingPlan, probe_sphere

    machine = load_machine("khan_chen_rpppr")
    rotary = {a for a in machine.axis_order if machine.axes[a].is_rotary}
    plan = ProbingPlan({a: list(np.arange(-60.0, 61.0, 20.0)) for a in sorted(rotary)},
                       {a: float(np.mean(machine.axes[a].stroke)) for a in machine.axis_order
                        if a not in rotary}, sphere_m=(0.05, 0.08, 0.06),
                       sphere_radius_m=12.5e-3, repeats=2)
    data = probe_sphere(machine, plan, {"EY0A": 20e-6, "EZ0A": -15e-6}, seed=3)
    longer_tool = replace(machine, tool=np.asarray(machine.tool) + [0.0, 0.0, 20e-6])
    shift = KinematicModel(longer_tool).nominal_relative(data["positions"]) - \
        KinematicModel(machine).nominal_relative(data["positions"])
    longer = tmp_path / "p_long.csv"
    longer.write_text(probing_csv_text(data["positions"],
                                       data["touch_points_m"] + shift[:, None, :], rotary))
    code = main(["probe", str(longer)])
    out, err = capsys.readouterr()
    # The probe turns with B about B's line: a longer probe is B's line offset along the
    # probe (the tip circles about the line alike). Named as that, with its twin said.
    assert code == 0, err
    import re

    said = re.search(r"EZ0B moves the centres as a probe (\d+\.\d) um longer would", out)
    assert said and abs(float(said.group(1)) - 20.0) <= 0.5, out


def test_a_badly_conditioned_arc_is_said(tmp_path, capsys):
    """A 100 degree arc passes the 90 degree floor but barely separates the tilts: the
    condition number is named."""
    from mt_accuracy_ros.cli import main

    data = tmp_path / "bb.csv"
    assert main(["ballbar", str(data), "--simulate", "1"]) == 0
    capsys.readouterr()
    lines = data.read_text().splitlines()
    keep = [lines[0]] + [line for line in lines[1:] if float(line.split(",")[2]) <= 100.0]
    data.write_text("\n".join(keep) + "\n")
    assert main(["ballbar", str(data)]) == 0
    out = capsys.readouterr().out
    assert "warning: a badly conditioned design (cond(J)" in out
