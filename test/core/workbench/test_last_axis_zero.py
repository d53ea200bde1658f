"""The zero of the last rotary axis, seen through the tool's measured direction.

Seed 53's trial 21 of ``studies.convention_surveys`` (imported by nothing of the package):
a trunnion ``[w C B X Y b Z t]``, a two-sphere R-test located at B = 30, C = 45 deg, C's
zero off by 13.1 urad (EC0C) and X's pitch. The zero turns the work about C's line: the
sphere's located position takes out its move (no position reading sees it), but the tool's
direction against the work turns by it, and at B = 30 deg C's line is not the tool's, so the
located direction does not take it out. Before, the zero was never a parameter and B's
line tilt about z stood in (EC0B -12.9 urad).
"""
from __future__ import annotations

import pytest

from bench.convention_proof import score
from convention_trials import checked, write_trial
from mt_accuracy_ros.core.compensation.error_model import model_from_dict
from mt_accuracy_ros.core.errors import ParameterError


def test_the_last_axis_zero_is_named_where_the_direction_was_measured(tmp_path):
    truth = write_trial(tmp_path, 53, 21)
    zero = next(e for e in truth["effects"] if e["iso_name"] == "EC0C")
    assert zero["signature_max_um"] == 0.0 and zero["signature_max_dir_urad"] > 10
    result = checked(tmp_path)
    (line,) = [n for n in result["named"] if n["name"] == "rotary_location:C"]
    assert line["setting"]["zeros"] == "EC0C"
    value, u = line["parameters"]["EC0C"], line["parameter_uncertainties"]["EC0C"]
    assert abs(value - zero["value_si"]) <= 3 * 2 * u, (value, u, zero["value_si"])
    assert "rotary_location:B" not in [n["name"] for n in result["named"]]
    assert score(truth, result)["right"], score(truth, result)


def test_without_the_direction_no_zero_is_a_parameter(tmp_path):
    """The same survey with its direction columns left out of the column map: the zero
    moves no position, so no rotary line holds it."""
    write_trial(tmp_path, 53, 21)
    map_path = tmp_path / "map.yaml"
    lines = map_path.read_text().splitlines()
    start = lines.index("direction_errors:")
    map_path.write_text("\n".join(lines[:start] + lines[start + 4:]) + "\n")
    result = checked(tmp_path)
    for named in result["named"] + result["ranking"]:
        if named["name"].startswith("rotary_location"):
            assert "zeros" not in (named.get("setting") or {}), named["name"]
            assert not any(k[1] == k[3] and k[2] == "0" for k in named["parameters"])


def test_a_model_holds_a_zero_only_where_its_setting_lists_it():
    effect = {"family": "rotary_location", "variant": "C",
              "coefficients": {"EX0C": 0.0, "EY0C": 0.0, "EA0C": 0.0, "EB0C": 0.0,
                               "EC0C": 1.3e-5}}
    listed = dict(effect, setting={"inseparable": "", "zeros": "EC0C"})
    model = model_from_dict({"machine": "trunnion_ac", "effects": {"line": listed}})
    assert model.effects["line"]["coefficients"]["EC0C"] == 1.3e-5
    with pytest.raises(ParameterError, match="EC0C is a zero-angle error"):
        model_from_dict({"machine": "trunnion_ac",
                         "effects": {"line": dict(effect, setting={"inseparable": ""})}})
