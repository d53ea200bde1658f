"""The best candidate by held-out error is tested when Occam's simpler choice among the
tied fails the acceptance rule.

Seed 47's trial 34 of ``studies.convention_surveys`` (imported by nothing of the package):
a trunnion ``[w C A X Y b Z t]``, a two-sphere R-test located at A = 20 deg, X's yaw ECX
with a constant part. With the tool's direction measured, C's line holds its zero too,
which brings the lines of A and C within the Occam tie of the yaw; simpler, they were
tested first, did not pass, and the step ended with nothing named. The yaw (and the X-Y
squareness its constant part is, ISO 230-1) is named as before the lines held the zero.
"""
from __future__ import annotations

from bench.convention_proof import score
from convention_trials import checked, write_trial


def test_the_yaw_is_named_when_the_simpler_tied_lines_do_not_pass(tmp_path):
    truth = write_trial(tmp_path, 47, 34)
    assert [e["iso_name"] for e in truth["effects"]] == ["ECX"]
    result = checked(tmp_path)
    names = [n["name"] for n in result["named"]]
    assert names and names[0] == "angular:ECX", names
    assert not any(n.startswith("rotary_location") for n in names), names
    assert score(truth, result)["right"], score(truth, result)
