"""The main job end to end, and how it words losses."""
from __future__ import annotations

import json
import os

import numpy as np

import pytest

from mt_accuracy_ros.commands.demo import delivery_losses

#: Corrections stamped in the run's last compensation delay and batch (20 + 10 ms at
#: 100 Hz): their time to apply (stamp + delay, at the controller's cycle) falls at or after
#: the machine's last sample, so they may never apply (8998-9000 of 9000 in every run).
LATE_AT_THE_END = 3


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


#: A story whose end state showed conformance (ISO 14253-1).
WITHIN = {"end_state_conformance": "within", "end_state_verdicts": []}


def test_an_undecided_end_state_fails_the_main_job():
    """The end state passed unless proven outside: e_y 0.79 ± 0.28 µm against a 1 µm band
    (RMS + U = 1.07 µm) was "within". Now only conformance shown passes, and the failure
    says which component and why."""
    from mt_accuracy_ros.commands.demo import demo_failures

    good = {"model_checks": 5, "bag_messages": 100, "compensation_applied": 10,
            "dead_nodes": []}
    undecided = {"end_state_conformance": "undecided", "end_state_verdicts": [
        {"name": "e_y", "conformance": "undecided", "sentence": "e_y 0.79 ± 0.28 µm: ..."}]}
    failure, = demo_failures(good, undecided)
    assert failure.startswith("the end state's conformance to the instrument's band is not "
                              "shown: it is undecided") and "e_y 0.79 ± 0.28 µm" in failure
    # A story without a verdict shows nothing: it fails too.
    assert demo_failures(good, {"end_state_within_band": True})


def test_dead_nodes_are_named_and_fail_the_run():
    """Issue 29: with the estimator and the monitor killed (-9) the demo exited 0 and named
    nobody; now each dead node is a failure line (and the exit status 1)."""
    from mt_accuracy_ros.commands.demo import _exit_text, demo_failures

    good = {"model_checks": 5, "bag_messages": 100, "compensation_applied": 10,
            "dead_nodes": []}
    assert demo_failures(good, WITHIN) == []
    dead = dict(good, dead_nodes=[f"yaw_estimator (exit {_exit_text(-9)})",
                                  f"model_monitor (exit {_exit_text(1)})"])
    failure, = demo_failures(dead, WITHIN)
    assert failure == ("node(s) died during the run: yaw_estimator (exit signal 9), "
                       "model_monitor (exit 1)")


def test_a_failed_end_state_says_whether_the_host_or_the_model_failed():
    from mt_accuracy_ros.commands.demo import demo_failures

    base = {"model_checks": 5, "bag_messages": 10, "compensation_applied": 3383,
            "compensation_messages": 9000}
    outside = {"end_state_conformance": "outside", "end_state_verdicts": [
        {"name": "e_y", "conformance": "outside",
         "sentence": "e_y 1.60 ± 0.20 µm: RMS - U = 1.40 µm > 1 µm band: nonconformance shown "
                     "(ISO 14253-1)"}]}
    assert demo_failures(dict(base, compensation_stale=5231), WITHIN) == []
    late, = demo_failures(dict(base, compensation_stale=5231), outside)
    assert "5231 of 9000 corrections arrived too late to apply (58 %)" in late
    model, = demo_failures(dict(base, compensation_stale=400), outside)
    assert model == ("the end state's conformance to the instrument's band is not shown: it "
                     "is outside (ISO 14253-1: RMS + U must not exceed the band): e_y 1.60 ± "
                     "0.20 µm: RMS - U = 1.40 µm > 1 µm band: nonconformance shown "
                     "(ISO 14253-1)")
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
    """The main job in lockstep (data time: the host's speed changes only the wall time,
    60-83 s idle, 114-129 s beside two CPU burners), run once for the tests below."""
    import contextlib
    import io

    from mt_accuracy_ros.commands.demo import run_demo

    out = tmp_path_factory.mktemp("demo") / "out"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = run_demo(out_dir=str(out), lockstep=True)
    return code, out, printed.getvalue()


def test_demo_records_from_the_first_sample_and_accounts_for_every_stream(demo_run):
    from mt_accuracy_ros.io.bag_reader import decode, read_messages

    code, out, printed = demo_run
    summary = json.loads((out / "summary.json").read_text())
    # The run succeeds, every run, idle or loaded: in lockstep the host's speed cannot
    # change the outcome (issue 39).
    assert code == 0 and summary["failures"] == [], (summary["failures"], printed)
    assert "FAILED" not in printed
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
    # The lockstep pacing reports are run control, not data: the bag holds what a
    # real-time run's holds (the recorder's exclude_topics).
    assert not list(read_messages(out / "bag", ["/lockstep", "/lockstep/stream"]))
    # In lockstep nothing is lost and no correction is late, on any host; nothing to warn.
    assert summary["stream_losses"].startswith("none"), summary["stream_losses"]
    assert summary["compensation_stale"] == 0
    assert "WARNING" not in printed
    # One check every 30 readings (check_every), none skipped for want of time: the bag
    # holds them all and the summary counts them.
    checks = sum(1 for _ in read_messages(out / "bag", ["/model_check"]))
    readings = sum(1 for _ in read_messages(out / "bag", ["/reference/tcp_error"]))
    assert summary["model_checks"] == checks >= readings // 30
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
    # In lockstep the user looks at the same readings on any host: the monitor names the
    # scenario's two hidden effects (the column drift, the 10 mm X screw pitch) and the
    # user's addition is accepted.
    added = summary["missing_effects_found"]
    assert added == ["structural_thermal_drift:column", "positioning_periodic:EXX"], added
    assert summary["effect_added_accepted"] is True
    for name in added:
        assert name in final["effects"] and name not in start["effects"]
        assert final["effects"][name]["coefficients"]
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
    added_version = next(v.version for v in versions
                         if f"added {summary['missing_effect_found']}" in v.reason)
    # The outcome, recomputed from the bag with an independent decoder and arithmetic.
    from demo_outcome import end_rows, first_live_s, read_references, rms

    readings = read_references(out / "bag")
    band_m = 1e-6
    assert np.all(readings.uncertainty_m == band_m)
    # Corrections applied: every one the broadcaster sent, but those stamped in the run's
    # last compensation delay, whose time to apply never comes.
    assert summary["compensation_applied"] >= \
        summary["compensation_messages"] - LATE_AT_THE_END > 8000
    assert np.all(readings.version[readings.time_s > 1.0] >= 1)
    # The added model live at the machine, at the same data time on any host: within a
    # second of the check the user acted on (32.9 s), and to the end of the run.
    live_s = first_live_s(readings, added_version)
    assert live_s is not None and 32.0 < live_s < 35.0, live_s
    assert np.all(readings.version[readings.time_s >= live_s] >= added_version)
    assert summary["added_version_live_at_s"] == pytest.approx(live_s, abs=0.051)
    # The end state (the last 30 s of data) within the band by ISO 14253-1 - RMS + U at
    # most the band, U no smaller than its instrument part - and far below the machine's
    # own error there.
    from demo_outcome import least_u_of_rms

    end = end_rows(readings)
    compensated = rms(readings.measured_m[end])
    own = rms(readings.measured_m[end] - readings.applied_m[end])
    assert np.all(compensated + least_u_of_rms(band_m, int(end.sum())) <= band_m), compensated
    assert summary["end_state_conformance"] == "within"
    assert summary["end_state_conformance_by_component"] == {
        "e_x": "within", "e_y": "within", "e_z": "within"}
    for sentence in summary["end_state_verdicts"]:
        assert sentence.endswith("conformance shown (ISO 14253-1)") and sentence in printed
    assert np.all(own > 4 * compensated), (own, compensated)
    # The whole run without compensation is far outside the band: the loop did the work.
    assert np.all(rms(readings.measured_m - readings.applied_m) > 5 * band_m)
    # The summary's figures are these numbers (its verdict's inputs, checked here).
    figures = phases[-1]["with_compensation"]
    assert [figures[c]["rms_um"] for c in "xyz"] == pytest.approx(compensated * 1e6, abs=1e-9)
    assert [phases[0]["without_compensation"][c]["rms_um"] for c in "xyz"] == pytest.approx(
        rms(readings.measured_m - readings.applied_m) * 1e6, abs=1e-9)
    assert summary["end_state_within_band"] is True
    assert summary["deterioration_alarm_axis"] == "y"
