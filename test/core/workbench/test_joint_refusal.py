"""A term named after one it made physics refuse in the joint fit goes, and the earlier
one stands.

The survey is the CLI's golden one (``studies.foreign_machine``: the Kidani HMC with a
hidden ball-screw pitch, 400 readings, its logger CSV): the periodic pitch EBZ was named
first and accepted at its own step; a zero-mean straightness EXZ named after it made their
joint fit move x by more than the residual allows. The later term goes, said with the
reason, and EBZ without it is accepted (final RMSE 2.34 -> 2.05 um when the rule came).
"""
from __future__ import annotations

import json

from mt_accuracy_ros.cli import main
from studies.foreign_machine import make_trial
from studies.survey_files import write_logger_survey


def test_a_later_term_that_breaks_the_joint_fit_goes_and_the_earlier_stands(tmp_path):
    trial = make_trial("kidani_hmc", ("ballscrew_pitch",), 1000, readings=400)
    write_logger_survey(trial, tmp_path / "survey.csv", tmp_path / "map.yaml")
    out = tmp_path / "check.json"
    assert main(["check", str(tmp_path / "survey.csv"), "--columns", str(tmp_path / "map.yaml"),
                 "--machine", "kidani_hmc", "--auto", "3", "--json", str(out)]) == 0
    result = json.loads(out.read_text())
    names = [n["name"] for n in result["named"]]
    (said,) = [d for d in result["dropped"] if d["name"] == "straightness_periodic:EXZ"]
    assert said["by"] == "angular_periodic:EBZ", said
    assert "made physics refuse their joint fit" in said["sentence"]
    assert "angular_periodic:EBZ without it is accepted" in said["sentence"]
    assert "angular_periodic:EBZ" in names and "straightness_periodic:EXZ" not in names
    assert all(not n["refusal"] for n in result["named"]), result["named"]
