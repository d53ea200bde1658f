"""The main job end to end, and how it words losses."""
from __future__ import annotations

import json

from mt_accuracy_ros.demo import delivery_losses


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


def test_demo_records_from_the_first_sample_and_accounts_for_every_stream(tmp_path, capsys):
    from mt_accuracy_ros.demo import run_demo
    from mt_accuracy_ros.io.bag_reader import decode, read_messages

    assert run_demo(out_dir=str(tmp_path / "out"), rate_factor=3.0) == 0
    printed = capsys.readouterr().out
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    # The recorder was subscribed before the machine streamed: the bag starts at sample 0
    # and at the first temperature reading.
    first_scales = next(m for m in read_messages(tmp_path / "out" / "bag", ["/scales"]))
    first_temperatures = next(m for m in read_messages(tmp_path / "out" / "bag",
                                                       ["/temperatures"]))
    assert decode(first_scales).first_sample_index == 0
    assert decode(first_temperatures).sequence == 0
    # Losses, if the machine was too loaded to keep up, are said in words - never silent.
    if summary["stream_losses"].startswith("none"):
        assert "WARNING" not in printed
    else:
        assert "WARNING" in printed and "could not keep up" in printed
    assert (tmp_path / "out" / "report.html").is_file()
    assert summary["missing_effect_found"] and summary["model_checks"] > 5
