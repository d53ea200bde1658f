"""The main job on the bundled vertical machining centre (issue 38): worn table ways that
the installation calibration did not see, named as tilts of the axes that carry the
workpiece, added, and the loop closed."""
from __future__ import annotations

import contextlib
import io
import json

import pytest


@pytest.fixture(scope="module")
def vmc_run(tmp_path_factory):
    from mt_accuracy_ros.commands.demo import run_demo

    out = tmp_path_factory.mktemp("vmc") / "out"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = run_demo(out_dir=str(out), rate_factor=3.0, scenario="demo_vmc")
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
