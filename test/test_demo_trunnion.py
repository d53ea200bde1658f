"""The main job on the five-axis trunnion VMC (``mt-accuracy demo --machine trunnion_ac``).

The demo_trunnion scenario in lockstep (data time: the host's speed changes only the wall
time): the virtual machine's C centre and A pivot are off and the pivot drifts as the
trunnion warms. Every rotary body of the virtual machine turns about its actual line
from the set-up pose (its own rigid-body code, not the model's chain). The monitor must
name where the rotary axes really are, the user adds it, the loop closes within the
R-test's band, and the summary and the report say which location errors were found and
which the set-up takes out.
"""
from __future__ import annotations

import json

import pytest
import yaml


@pytest.fixture(scope="module")
def trunnion_run(tmp_path_factory):
    from demo_outcome import run_bundled_main_job

    return run_bundled_main_job(tmp_path_factory.mktemp("trunnion"), "demo_trunnion")


def test_the_trunnion_job_finds_the_c_centre_and_the_a_pivot_and_judges_its_end_state(
        trunnion_run):
    from mt_accuracy_ros.nodes._scenario import resolve_scenario

    from demo_outcome import assert_the_verdict_follows_the_figures

    code, out, printed = trunnion_run
    summary = json.loads((out / "summary.json").read_text())
    # The end state's conformance is shown (RMS + U <= 1 um on every component, and the
    # tool's direction within its band; ISO 14253-1) and the job passes. The refit from
    # the datum corrects the model's error at the datum within the calibration's
    # uncertainty and takes as zero what the search could not tell from zero (the drift's
    # x gain, the lines' tilts): taken as exact and fitted freely, the datum's error and
    # the few early poses gave the drift an x gain of -0.59 um/K and e_x ended undecided
    # at 1.03 +- 0.17 um (docs/results.md).
    state = assert_the_verdict_follows_the_figures(code, summary)
    assert state == "within" and code == 0, (state, summary["failures"])
    assert "virtual trunnion_ac" in printed
    assert summary["missing_effects_found"][:2] == ["rotary_location:AC",
                                                    "structural_thermal_drift:column"], printed
    assert summary["effect_added_accepted"]
    assert summary["tool_direction"]["end_within_band"]
    assert all(summary["end_state_conformance_by_component"][f"direction about {c}"] == "within"
               for c in "xyz")
    truth = resolve_scenario("demo_trunnion").parameters("rotary_location")["errors"]
    found = yaml.safe_load((out / "model.yaml").read_text())["effects"][
        "rotary_location:AC"]["coefficients"]
    # The offsets within 1 um of the scenario's, the tilts (none) within 3 urad of zero.
    for name in ("EX0C", "EY0C", "EY0A", "EZ0A"):
        assert abs(found[name] - truth[name]) < 1e-6, (name, found)
    for name in ("EA0C", "EB0C", "EB0A", "EC0A"):
        assert abs(found[name]) < 3e-6, (name, found)
    # The trunnion's supports lift the pivot (y, z); no x gain, and the final model has
    # none: the search could not tell it from zero and no refit showed it.
    drift = yaml.safe_load((out / "model.yaml").read_text())["effects"][
        "structural_thermal_drift:column"]["coefficients"]
    beta = resolve_scenario("demo_trunnion").parameters("structural_thermal_drift")[
        "beta_m_per_k"]
    assert drift["bx"] == 0.0 and beta[0] == 0.0, drift
    for k, name in ((1, "by"), (2, "bz")):
        assert abs(drift[name] - beta[k]) < 0.25e-6, (name, drift)
    said = summary["rotary_location_identified"]
    assert "EX0C +" in said and "not identifiable: EA0A, EC0C" in said, said
    report = (out / "report.html").read_text()
    assert "location errors identified (ISO 230-7" in report and "EX0C +" in report


def test_the_jobs_model_exports_the_found_lines_to_the_cnc_file(trunnion_run, tmp_path,
                                                                 capsys):
    """The user's next step: `mt-accuracy export model.yaml`. The C centre and A pivot the
    job found are in the volumetric file's location block (mm), and nothing the model
    holds of the positions is said to be left out of it."""
    from mt_accuracy_ros.cli import main

    _, out, _ = trunnion_run
    found = yaml.safe_load((out / "model.yaml").read_text())["effects"][
        "rotary_location:AC"]["coefficients"]
    tables = tmp_path / "tables"
    assert main(["export", str(out / "model.yaml"), "--out", str(tables), "--json",
                 str(tmp_path / "e.json")]) == 0
    assert "does not hold" not in capsys.readouterr().out
    lines = (tables / "volumetric_isg.csv").read_text().splitlines()
    block = lines.index("// location errors (constant)")
    written = dict(zip(lines[block + 1].split(), map(float, lines[block + 2].split())))
    for name in ("EX0C", "EY0C", "EY0A", "EZ0A"):
        assert written[name] == pytest.approx(found[name] * 1e3, rel=1e-9), name
    assert json.loads((tmp_path / "e.json").read_text())["not_in_file"] == {}
