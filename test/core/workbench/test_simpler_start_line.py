"""A C line's offset named where the work's set-up error and the A line's offset together
stand for it.

Seed 89's trial 39 of ``studies.convention_surveys`` (imported by nothing of the package):
a trunnion ``[w C A X Y b Z t]``, an R-test sphere located at A = 0, C = 45 deg, A swept
from -110 to +30 deg and C through a turn; C's line is offset in y by 6.1 um (EY0C) and Y
pitches along its travel (EAY). Located at the set-up, the offset moves the work by
R_A (I - R(C - C0)) d, which is the work's located set-up error -d turning with the table
plus an offset -d of the A line: three terms fit what two explain. The first step's
leader is the set-up error, and C's line ranks fifth; the simpler start now looks that far.
"""
from __future__ import annotations

from bench.convention_proof import score
from convention_trials import checked, write_trial


def test_the_c_lines_offset_and_the_pitch_are_named_not_three_stand_ins(tmp_path):
    truth = write_trial(tmp_path, 89, 39)
    offset = next(e for e in truth["effects"] if e["iso_name"] == "EY0C")
    result = checked(tmp_path)
    names = [n["name"] for n in result["named"]]
    assert sorted(names) == ["angular:EAY", "rotary_location:C"], names
    (line,) = [n for n in result["named"] if n["name"] == "rotary_location:C"]
    value = line["parameters"]["EY0C"]
    u = line["parameter_uncertainties"]["EY0C"]
    assert abs(value - offset["value_si"]) <= 3 * 2 * u, (value, u, offset["value_si"])
    assert score(truth, result)["right"], score(truth, result)
