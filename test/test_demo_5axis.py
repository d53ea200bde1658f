"""The main job on the five-axis machine (``mt-accuracy demo --machine khan_chen_rpppr``).

The whole demo_5axis scenario in lockstep (data time: each batch goes out once every
node of the loop has caught up, so the host's speed changes only the wall time, about
70 s). In real time, at 1.5x with two CPU burners beside it, the diagnosis fell so far
behind that the added model reached the machine only after the run. Every outcome is
asserted every run, none skipped: the rotary encoders stream, the compensation turns the
rotary axes, the R-test measures the tool's direction, the monitor names the rotary axes'
location, the added model goes live within a second of the user's decision, the end
state (position and tool direction within the R-test's band, absolutely: issue 30,
recomputed from the bag here), the refit and the datum.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

#: Corrections stamped in the run's last compensation delay and batch (20 + 10 ms at
#: 100 Hz): their time to apply (stamp + delay, at the controller's cycle) falls at or after
#: the machine's last sample, so they may never apply (8998-9000 of 9000 in every run).
LATE_AT_THE_END = 3


@pytest.fixture(scope="module")
def five_axis_run(tmp_path_factory):
    from demo_outcome import run_bundled_main_job

    return run_bundled_main_job(tmp_path_factory.mktemp("demo5"), "demo_5axis")


def test_the_five_axis_graph_streams_encoders_and_compensates_the_tool_direction(five_axis_run):
    from mt_accuracy_ros.io.bag_reader import decode, read_messages

    code, out, printed = five_axis_run
    summary = json.loads((out / "summary.json").read_text())
    assert code == 0 and summary["failures"] == [], (summary["failures"], printed)
    assert summary["compensation_stale"] == 0 and \
        summary["compensation_applied"] >= \
        summary["compensation_messages"] - LATE_AT_THE_END > 8000
    assert "virtual khan_chen_rpppr" in printed
    first = decode(next(read_messages(out / "bag", ["/scales"])))
    assert list(first.encoder_names) == ["a", "b"]
    angles = np.asarray(first.encoder_angles).reshape(-1, 2)
    commands = np.asarray(first.command_positions).reshape(-1, len(first.command_axes))
    assert np.max(np.abs(angles[:, 0] - commands[:, list(first.command_axes).index("a")])) < 1e-3
    # The broadcaster turns the rotary axes for the tool's direction (tens of urad at most).
    turns = np.array([list(decode(m).rotary_corrections) for m in
                      read_messages(out / "bag", ["/compensation"])])
    assert turns.shape[1] == 2 and 1e-7 < np.max(np.abs(turns)) < 1e-3
    references = [decode(m) for m in read_messages(out / "bag", ["/reference/tcp_error"])]
    assert all(r.instrument == "r_test_two_sphere" and r.orientation_measured for r in references)
    # The machine's own tool-direction error is there to be seen (the tilted rotary axes).
    direction = np.array([(r.orientation_error.x - r.applied_orientation_correction.x,
                           r.orientation_error.y - r.applied_orientation_correction.y,
                           r.orientation_error.z - r.applied_orientation_correction.z)
                          for r in references])
    assert np.sqrt(np.mean(np.sum(direction ** 2, axis=1))) > 10e-6
    checks = [decode(m) for m in read_messages(out / "bag", ["/model_check/tool_direction"])]
    assert checks and all(c.quantity == "tool_direction" and c.unit == "rad" for c in checks)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["tool_direction"]["phases"]
    assert "tool direction error at the same readings" in printed
    assert summary["compensation_messages"] > 0 and summary["model_checks"] >= 1


def test_the_five_axis_job_names_the_rotary_axes_from_the_direction_and_ends_in_the_band(
        five_axis_run):
    code, out, printed = five_axis_run
    summary = json.loads((out / "summary.json").read_text())
    # The tilts of both rotary axes, named from the tool's direction.
    assert "rotary_location:AB" in summary["missing_effects_found"], printed
    assert summary["effect_added_accepted"]
    final = yaml.safe_load((out / "model.yaml").read_text())
    start = yaml.safe_load((out / "model_start.yaml").read_text())
    # The model is referred to the R-test's zero at the work offset.
    assert start["datum"] == final["datum"] == {"X": 0.3, "Y": 0.2, "Z": 0.2, "A": 0.0,
                                                "B": 0.0}
    tilts = final["effects"]["rotary_location:AB"]["coefficients"]
    # Each body turns about its tilted line from the set-up pose, so the tip and the
    # direction part every tilt (the scenario: EB0A 40, EC0A -30, EA0B 30, EC0B -20 urad);
    # A's zero error (EA0A 25 urad) is the set-up's: no parameter carries it.
    for name, truth in (("EB0A", 40e-6), ("EC0A", -30e-6), ("EA0B", 30e-6), ("EC0B", -20e-6)):
        assert abs(tilts[name] - truth) < 5e-6, (name, tilts)
    assert "EA0A" not in tilts and "EB0B" not in tilts
    direction = summary["tool_direction"]
    assert code == 0 and summary["end_state_within_band"], (summary["failures"], printed)
    assert direction["end_within_band"], direction
    # ISO 14253-1: conformance shown for the tip and the direction, each component.
    assert summary["end_state_conformance"] == "within"
    assert set(summary["end_state_conformance_by_component"]) == {
        "e_x", "e_y", "e_z", "direction about x", "direction about y", "direction about z"}
    assert set(summary["end_state_conformance_by_component"].values()) == {"within"}
    # The outcome recomputed from the bag (independent decoder, plain RMS): the user's
    # model live from its decision (32.9 s of data) to the end; the end state's position
    # and tool direction below the R-test's bands, far below the machine's own error.
    from demo_outcome import end_rows, first_live_s, read_references, rms

    readings = read_references(out / "bag")
    live_s = first_live_s(readings, 2)
    assert live_s is not None and 32.0 < live_s < 35.0, live_s
    assert summary["added_version_live_at_s"] == pytest.approx(live_s, abs=0.051)
    end = end_rows(readings)
    position = rms(readings.measured_m[end])
    assert np.all(position < 1e-6), position
    assert np.all(rms(readings.measured_m[end] - readings.applied_m[end]) > 3 * position)
    tool = rms(readings.direction_rad[end])
    assert np.all(tool < readings.direction_uncertainty_rad[0]), tool
    figures = summary["closed_loop"][-1]
    assert figures["label"] == "end state"
    assert [figures["with_compensation"][c]["rms_um"] for c in "xyz"] == pytest.approx(
        position * 1e6, abs=1e-9)


def test_the_monitor_renews_the_drift_from_the_datum_and_the_part_stays_put(five_axis_run):
    """The column drift named over the first 2 K of warming (bx 1.29 um/K, true 1) left
    the compensated machine 0.8 um off its datum at 2.8 K. The monitor refits the added
    effects from the datum (the R-test is zeroed there), says it is worth a version,
    and makes it live by itself: the part's datum stays put to well within the band."""
    from mt_accuracy_ros.io.bag_reader import decode, read_messages

    code, out, printed = five_axis_run
    summary = json.loads((out / "summary.json").read_text())
    assert summary["added_version_live_at_s"] is not None, summary["failures"]
    said = [{v.key: v.value for v in s.values}.get("refit", "")
            for m in read_messages(out / "bag", ["/diagnostics"])
            for s in decode(m).status if s.name.endswith("model_monitor: model")]
    assert any("from the datum" in s and ": worth a new version" in s for s in said), said
    versions = [decode(m) for m in read_messages(out / "bag", ["/model"])]
    refits = [v for v in versions if v.reason.startswith("refitted") and "(monitor)" in v.reason]
    assert refits, [v.reason for v in versions]
    drift = yaml.safe_load(refits[0].model_yaml)["effects"]["structural_thermal_drift:column"]
    assert abs(drift["coefficients"]["bx"] - 1e-6) < 0.2e-6, drift
    # The compensated machine under the refit (its first 2 readings settling): its mean
    # error is the datum's shift (the scenario's R-test zero is the work offset).
    references = [decode(m) for m in read_messages(out / "bag", ["/reference/tcp_error"])]
    under = [r for r in references if r.compensation_model_version >= refits[0].version][2:]
    assert len(under) >= 10, f"the refit was live at only {len(under)} readings"
    mean = np.mean([(r.error.x, r.error.y, r.error.z) for r in under], axis=0)
    assert np.all(np.abs(mean) < 0.5e-6), mean
