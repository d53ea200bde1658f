"""The main job end to end, and how it words losses."""
from __future__ import annotations

import json
import os

import numpy as np

import pytest

from mt_accuracy_ros.commands.demo import delivery_losses


def test_delivery_losses_are_plain_sentences():
    delivery = {"/yaw_estimator": {"scales.processed": "410", "scales.lost": "500",
                                   "scales.refused": "0", "temperatures.processed": "40",
                                   "temperatures.lost": "0", "temperatures.refused": "0"},
                "/model_monitor": {"reference/tcp_error.processed": "90",
                                   "reference/tcp_error.lost": "0",
                                   "reference/tcp_error.refused": "2"}}
    lines = delivery_losses(delivery)
    assert lines == [
        "/model_monitor lost 0 of 90 messages of 'reference/tcp_error' (0 %) and refused 2 "
        "messages: it could not keep up or the input was bad; the results above miss them",
        "/yaw_estimator lost 500 of 910 samples of 'scales' (55 %) and refused 0 messages: it "
        "could not keep up or the input was bad; the results above miss them"]
    assert delivery_losses({"/n": {"scales.processed": "5", "scales.lost": "0"}}) == []


def test_the_machine_and_controller_keep_their_wall_clock_pace_at_any_rate():
    from mt_accuracy_ros.commands.demo import paced

    real_time = paced(1.0)
    assert real_time == {"batch_period_s": 0.01, "controller_cycle_s": 0.001,
                         "compensation_delay_s": 0.02, "max_compensation_age_s": 0.5}
    fast = paced(3.0)
    assert fast["batch_period_s"] == pytest.approx(0.03)
    assert fast["compensation_delay_s"] == pytest.approx(0.06)
    assert fast["max_compensation_age_s"] == pytest.approx(1.5)
    assert fast["controller_cycle_s"] == 0.001
    # Slower than real time: never shorter deadlines than at rate 1.
    assert paced(0.5) == real_time


def test_dead_nodes_are_named_and_fail_the_run():
    """Issue 29: with the estimator and the monitor killed (-9) the demo exited 0 and named
    nobody; now each dead node is a failure line (and the exit status 1)."""
    from mt_accuracy_ros.commands.demo import _exit_text, demo_failures

    good = {"model_checks": 5, "bag_messages": 100, "compensation_applied": 10,
            "dead_nodes": []}
    assert demo_failures(good, {"end_state_within_band": True}) == []
    dead = dict(good, dead_nodes=[f"yaw_estimator (exit {_exit_text(-9)})",
                                  f"model_monitor (exit {_exit_text(1)})"])
    failure, = demo_failures(dead, {"end_state_within_band": True})
    assert failure == ("node(s) died during the run: yaw_estimator (exit signal 9), "
                       "model_monitor (exit 1)")


def test_a_failed_end_state_says_whether_the_host_or_the_model_failed():
    from mt_accuracy_ros.commands.demo import demo_failures

    base = {"model_checks": 5, "bag_messages": 10, "compensation_applied": 3383,
            "compensation_messages": 9000}
    outside = {"end_state_within_band": False}
    assert demo_failures(dict(base, compensation_stale=5231), {"end_state_within_band": True}) \
        == []
    late, = demo_failures(dict(base, compensation_stale=5231), outside)
    assert "5231 of 9000 corrections arrived too late to apply (58 %)" in late
    model, = demo_failures(dict(base, compensation_stale=400), outside)
    assert model == "the end state is outside the instrument's band (see the table above)"
    late_model, = demo_failures(dict(base, compensation_stale=0, added_version_live_at_s=84.0,
                                     run_data_s=90.0), outside)
    assert ("reached the machine at 84 s of 90 s: the monitor's diagnosis or the gates fell "
            "behind the data") in late_model
    never_live, = demo_failures(dict(base, compensation_stale=0, added_version_live_at_s=None,
                                     run_data_s=90.0), outside)
    assert "only after the run" in never_live
    in_time, = demo_failures(dict(base, compensation_stale=0, added_version_live_at_s=41.0,
                                  run_data_s=90.0), outside)
    assert "fell behind" not in in_time
    never, _ = demo_failures(dict(base, compensation_applied=0, compensation_stale=9000), outside)
    assert never.startswith("the loop never closed")


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory):
    """The main job, run once for the tests below (about 40 s)."""
    import contextlib
    import io

    from mt_accuracy_ros.commands.demo import run_demo

    out = tmp_path_factory.mktemp("demo") / "out"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = run_demo(out_dir=str(out), rate_factor=3.0)
    return code, out, printed.getvalue()


def test_demo_records_from_the_first_sample_and_accounts_for_every_stream(demo_run):
    from mt_accuracy_ros.io.bag_reader import decode, read_messages

    code, out, printed = demo_run
    summary = json.loads((out / "summary.json").read_text())
    # The exit code tells the truth (issue 26): 0 only when the loop closed and the end
    # state is within the band; otherwise the summary says why.
    from mt_accuracy_ros.commands.demo import demo_failures

    failures = demo_failures(summary, {"end_state_within_band":
                                       summary["end_state_within_band"]})
    assert (code == 0) == (not failures)
    assert all(f"FAILED: {failure}" in printed for failure in failures)
    # Everything the command printed as a warning or a failure is in summary.json, and the
    # dead nodes are (issue 39: they were written after it).
    printed_warnings = [line.split("  WARNING ", 1)[1] for line in printed.splitlines()
                        if line.startswith("  WARNING ")]
    assert summary["warnings"] == printed_warnings
    assert summary["failures"] == [line.split("  FAILED: ", 1)[1]
                                   for line in printed.splitlines()
                                   if line.startswith("  FAILED: ")]
    assert summary["dead_nodes"] == []
    # Feedback while it runs: a progress line at least every 5 s of wall time.
    progress = [line for line in printed.splitlines() if " s wall] " in line]
    assert len(progress) >= int(summary["wall_time_s"] // 5) - 3
    assert all("| checks " in line and "stale" in line for line in progress)
    # The recorder was subscribed before the machine streamed: the bag starts at sample 0
    # and at the first temperature reading.
    first_scales = next(m for m in read_messages(out / "bag", ["/scales"]))
    first_temperatures = next(m for m in read_messages(out / "bag", ["/temperatures"]))
    assert decode(first_scales).first_sample_index == 0
    assert decode(first_temperatures).sequence == 0
    # Losses, if the machine was too loaded to keep up, are said in words - never silent;
    # so is a share of corrections too late to apply above the warning threshold.
    from mt_accuracy_ros.commands.demo import LATE_WARNING_SHARE

    late = summary["compensation_stale"] > \
        LATE_WARNING_SHARE * max(summary["compensation_messages"], 1)
    assert ("arrived too late to apply (warning above" in printed) == late
    if summary["stream_losses"].startswith("none") and not late:
        assert "WARNING" not in printed
    elif not summary["stream_losses"].startswith("none"):
        assert "WARNING" in printed and "could not keep up" in printed
    # How many checks the monitor gets through depends on the host (it judges every
    # reading it receives; a loaded host delays it); at least one, and the summary
    # counts what the bag holds.
    checks = sum(1 for _ in read_messages(out / "bag", ["/model_check"]))
    assert 1 <= summary["model_checks"] <= checks
    # The compensation path's nodes say what they ran at: the demo's niceness, or why not.
    from mt_accuracy_ros.commands.demo import PATH_NICENESS

    scheduling = summary["path_scheduling"]
    assert set(scheduling) == {"encoder_publisher", "yaw_estimator", "compensation_broadcaster"}
    expected = f"niceness {PATH_NICENESS} (" if os.geteuid() == 0 else "not permitted"
    assert all(expected in text for text in scheduling.values()), scheduling
    assert "path_scheduling" in printed


REPORT_SECTIONS = ["Machine, data and instruments", "Headline: TCP error per component",
                   "The run", "Closed loop: the machine's error with the compensation applied",
                   "Where the model fails", "Where the residual lives",
                   "The effect found and its evidence",
                   "Model versions", "Axes: dual-scale yaw, systematic profile, deterioration",
                   "Temperatures", "ISO 230-2 positioning", "Compensation table"]


def test_demo_report_renders_in_a_browser_with_every_section_and_image(demo_run):
    from browser import chromium, page_facts, validate_html

    _, out, _ = demo_run
    page = out / "report.html"
    validate_html(page)
    summary = json.loads((out / "summary.json").read_text())
    # The JSON summary carries the same sections.
    assert [s["title"] for s in summary["report"]["sections"]] == REPORT_SECTIONS
    headline = summary["report"]["sections"][1]["tables"][0]["rows"]
    assert headline[0]["state"].startswith("without compensation")
    assert all("(k = 2)" in row["RMS e_x"] for row in headline)
    # The headline is the measurement (issue 26): the report's first table equals the
    # summary's closed-loop phases, number for number; the offline residual is second and
    # labelled as such.
    from mt_accuracy_ros.core.workbench.statistics import format_with_uncertainty

    phases = summary["closed_loop"]
    expected = [[phases[0]["without_compensation"][c] for c in "xyz"]] + \
        [[p["with_compensation"][c] for c in "xyz"] for p in phases[1:]]
    assert len(headline) == len(expected)
    for row, figures in zip(headline, expected):
        assert [row[f"RMS e_{c}"] for c in "xyz"] == [
            format_with_uncertainty(f["rms_um"], f["u_k2_um"], "µm") for f in figures]
    offline = summary["report"]["sections"][1]["tables"][1]
    assert offline["caption"].startswith("Offline (a second figure")
    assert not any(r["state"].startswith("without compensation") for r in offline["rows"])
    if chromium() is None:
        pytest.skip("chromium not installed (make setup installs it where it can)")
    facts = page_facts(page)
    assert facts["sections"] == REPORT_SECTIONS
    assert len(facts["images"]) >= 5
    assert all(image["loaded"] for image in facts["images"]), facts["images"]
    assert facts["rejected"] >= 1  # rejected candidates are marked as such
    assert facts["width"] <= 1300  # readable on a laptop: no sideways scrolling


def test_demo_bag_decodes_with_the_mcap_ros2_decoder_foxglove_uses(demo_run):
    """Schemas as stored (ros2msg), no installed types needed: what Foxglove reads."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    _, out, _ = demo_run
    seen = {}
    for path in sorted((out / "bag").glob("*.mcap")):
        with open(path, "rb") as stream:
            reader = make_reader(stream, decoder_factories=[DecoderFactory()])
            assert reader.get_header().profile == "ros2"
            for schema, channel, _, decoded in reader.iter_decoded_messages(
                    topics=["/temperatures", "/compensation", "/systematic/y", "/model_check"]):
                assert schema.encoding == "ros2msg" and channel.message_encoding == "cdr"
                seen.setdefault(channel.topic, decoded)
    assert set(seen) == {"/temperatures", "/compensation", "/systematic/y", "/model_check"}
    assert len(seen["/temperatures"].sensor_names) == len(seen["/temperatures"].temperatures)
    assert seen["/systematic/y"].unit == "rad" and seen["/compensation"].model_version >= 1


def test_demo_closes_the_loop_and_tells_the_end_state(demo_run):
    """The CNC applied the compensation; the summary tells each phase and the end state,
    the saved model is the final one, every model version is in the bag."""
    import yaml

    from mt_accuracy_ros.io.bag_reader import decode, read_messages

    code, out, printed = demo_run
    summary = json.loads((out / "summary.json").read_text())
    # The headline says whether the loop closed (issue 29: at --rate 10 it did not, and
    # the "compensated" figure read as if it had).
    assert summary["loop_closed"] is (summary["compensation_applied"] > 0)
    assert ("did NOT close" in summary["headline"]) is (not summary["loop_closed"])
    phases = summary["closed_loop"]
    assert phases[0]["label"] == "whole run" and phases[-1]["label"] == "end state"
    for phase in phases:
        for kind in ("without_compensation", "with_compensation"):
            assert set(phase[kind]) == {"x", "y", "z"}
            assert all(v["u_k2_um"] > 0 for v in phase[kind].values())
    assert "closed loop: the CNC applies the compensation (hybrid)" in printed
    assert "end of the run" in printed
    # The effects the user added are in the saved (final) model with their fitted
    # parameters; the starting model is kept beside it. Which effects the monitor named
    # depends on the readings it had when the user looked - in a closed loop on a busy
    # host that varies (the corrections the CNC applied are part of what it judges) - so
    # the naming of the demo's hidden pitch error is asserted where the data are fixed:
    # test/core/workbench/test_diagnosis.py and test/test_check_cli.py.
    final = yaml.safe_load((out / "model.yaml").read_text())
    start = yaml.safe_load((out / "model_start.yaml").read_text())
    added = summary["missing_effects_found"] if summary["effect_added_accepted"] else []
    for name in added:
        assert name in final["effects"] and name not in start["effects"]
        assert final["effects"][name]["coefficients"]
    if added:
        assert final["version"] >= 2
    # Every model version is a message in the bag, in order, with its reason.
    versions = [decode(m) for m in read_messages(out / "bag", ["/model"])]
    assert [v.version for v in versions] == sorted({v.version for v in versions})
    assert versions[0].reason == "start"
    # The report's model versions are those the graph published; its last is model.yaml.
    rows = summary["report"]["sections"][REPORT_SECTIONS.index("Model versions")][
        "tables"][0]["rows"]
    assert [int(r["model version"]) for r in rows] == [v.version for v in versions]
    assert final["version"] == versions[-1].version
    for name, entry in final["effects"].items():
        for key, value in (entry or {}).get("coefficients", {}).items():
            assert f"{key} = {value:.4g}" in rows[-1]["effects and fitted coefficients"]
    if added:
        assert any(f"added {summary['missing_effect_found']}" in v.reason for v in versions)
    # The whole story: the machine's error fell to the instrument's band by the end,
    # the deterioration included (absorbed through the live profile).
    whole, end = phases[0], phases[-1]
    band = summary["instrument_band_um"]
    # How close to the band the end state comes depends on the host keeping up: a
    # correction that reaches the CNC too late is dropped as stale (counted in the
    # summary), and the demo runs 3x faster than real time here; the closed loop's
    # accuracy itself is tested without a race in test/nodes/test_closed_loop.py. What
    # does not depend on the host: the CNC received corrections, and the verdict says
    # what the numbers say.
    # The CNC received corrections (applied, or dropped as stale when the host lagged).
    assert summary["compensation_applied"] + summary["compensation_stale"] > 0
    assert summary["end_state_within_band"] == all(
        end["with_compensation"][c]["rms_um"] - end["with_compensation"][c]["u_k2_um"] <= band
        for c in "xyz")
    # Without compensation the same run is far outside: the loop did the work.
    assert all(whole["without_compensation"][c]["rms_um"] > 5 * band for c in "xyz")
    assert summary["deterioration_alarm_axis"] == "y"
