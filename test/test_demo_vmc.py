"""The main job on the bundled vertical machining centre (issue 38): worn table ways that
the installation calibration did not see, named as tilts of the axes that carry the
workpiece, added, and the loop closed - in lockstep (data time), so that every outcome is
asserted every run, on any host."""
from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest
import yaml

#: Corrections stamped in the run's last compensation delay and batch (20 + 10 ms at
#: 100 Hz): their time to apply (stamp + delay, at the controller's cycle) falls at or after
#: the machine's last sample, so they may never apply (8998-9000 of 9000 in every run).
LATE_AT_THE_END = 3


@pytest.fixture(scope="module")
def vmc_run(tmp_path_factory):
    from mt_accuracy_ros.commands.demo import run_demo

    out = tmp_path_factory.mktemp("vmc") / "out"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = run_demo(out_dir=str(out), lockstep=True, scenario="demo_vmc")
    return code, out, printed.getvalue()


def test_the_vmc_job_names_its_table_tilts_and_its_report_says_so(vmc_run):
    code, out, printed = vmc_run
    summary = json.loads((out / "summary.json").read_text())
    # The monitor names the scenario's two hidden tilts on the tables (X table pitch EBX,
    # Y saddle pitch EAY) among what it names at the user's look (data time, 30 s), and
    # nothing on the tool side stands in for them.
    tilts = summary["table_tilts_named"]
    assert "angular:EBX (the X table's pitch)" in tilts, summary["missing_effects_found"]
    assert "angular:EAY (the Y table's pitch)" in tilts, summary["missing_effects_found"]
    assert not any(name.endswith("Z") and name.startswith("angular")
                   for name in summary["missing_effects_found"])
    assert summary["effect_added_accepted"] is True
    report = (out / "report.html").read_text()
    assert "Tilts of the axes that carry the workpiece named: angular:EAY" in report
    # The loop closed: the CNC applied corrections, and the run names nobody dead.
    assert summary["loop_closed"] and summary["compensation_applied"] > 0
    whole = summary["closed_loop"][0]
    # The tilts act through the tool's height and place: without compensation the VMC is
    # several microns out on every component.
    assert all(whole["without_compensation"][c]["rms_um"] > 4.0 for c in "xyz")
    assert "the monitor names" in printed and "angular:EBX" in printed


def test_the_vmc_loop_closes_and_its_verdict_follows_the_bag(vmc_run):
    from demo_outcome import end_rows, first_live_s, read_references, rms

    from demo_outcome import assert_the_verdict_follows_the_figures

    code, out, printed = vmc_run
    summary = json.loads((out / "summary.json").read_text())
    # The end state's conformance is shown (RMS + U <= 1 um on every component, ISO
    # 14253-1) and the job passes: the refit from the datum keeps the drift's gains and
    # corrects the model's error at the datum within the calibration's uncertainty (a
    # refit taking the datum as exact put 0.5 um of calibration error into the gains,
    # and the end state was undecided: docs/results.md).
    state = assert_the_verdict_follows_the_figures(code, summary)
    assert state == "within" and code == 0, (state, summary["failures"])
    model = yaml.safe_load((out / "model.yaml").read_text())
    drift = model["effects"]["structural_thermal_drift:column"]["coefficients"]
    # The scenario's column drift (1, 2, 4 um/K) within 0.25 um/K per component.
    for name, truth in (("bx", 1e-6), ("by", 2e-6), ("bz", 4e-6)):
        assert abs(drift[name] - truth) < 0.25e-6, (name, drift)
    # The calibration's error at the datum, found within three standard uncertainties of
    # what the model states of it (U, k = 2).
    assert np.any(model["datum_correction_m"])
    assert np.all(np.abs(model["datum_correction_m"]) <= 1.5 * np.array(
        model["datum_uncertainty_m"]))
    assert summary["compensation_stale"] == 0 and \
        summary["compensation_applied"] >= \
        summary["compensation_messages"] - LATE_AT_THE_END > 8000
    readings = read_references(out / "bag")
    # The user's model live from its decision (the check at 32.9 s of data) to the end.
    live_s = first_live_s(readings, 2)
    assert live_s is not None and 32.0 < live_s < 35.0, live_s
    assert np.all(readings.version[readings.time_s >= live_s] >= 2)
    # The end state below the instrument's band (plain RMS) and far below the machine's
    # own error at the same readings; the summary's figures are these.
    end = end_rows(readings)
    compensated = rms(readings.measured_m[end])
    assert np.all(compensated < 1e-6), compensated
    assert np.all(rms(readings.measured_m[end] - readings.applied_m[end]) > 4 * compensated)
    figures = summary["closed_loop"][-1]["with_compensation"]
    assert [figures[c]["rms_um"] for c in "xyz"] == pytest.approx(compensated * 1e6, abs=1e-9)
