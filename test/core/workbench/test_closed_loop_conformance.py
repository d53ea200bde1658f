"""The ISO 14253-1 decision rule (within / outside / undecided) and the main job's end
state told with it: the figures, the sentence, and a missing tool direction as a warning."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.core.workbench.conformance import Conformance, conformance, judge, overall


@pytest.mark.parametrize("rms, u, limit, expected", [
    (0.60, 0.20, 1.0, Conformance.WITHIN),       # 0.80 <= 1: conformance shown
    (0.80, 0.20, 1.0, Conformance.WITHIN),       # exactly at the band: shown
    (0.79, 0.28, 1.0, Conformance.UNDECIDED),    # 1.07 > 1, 0.51 <= 1: nothing shown
    (1.20, 0.20, 1.0, Conformance.UNDECIDED),    # RMS - U = 1.0 is not > 1
    (1.30, 0.20, 1.0, Conformance.OUTSIDE),      # 1.10 > 1: nonconformance shown
])
def test_three_states(rms, u, limit, expected):
    assert conformance(rms, u, limit) is expected


def test_the_old_rule_s_within_is_undecided_now_and_the_sentence_says_why():
    """The main job's end state e_y 0.79 ± 0.28 µm against a 1 µm band was "within"
    (RMS - U <= band); RMS + U = 1.07 µm shows no conformance."""
    verdict = judge("e_y", 0.79, 0.28, 1.0, "µm")
    assert verdict.state is Conformance.UNDECIDED
    assert verdict.sentence().startswith("e_y 0.79 ± 0.28 µm: RMS + U = 1.07 µm > 1 µm band: "
                                         "conformance not shown")
    assert verdict.sentence().endswith("(ISO 14253-1)")
    assert judge("e_x", 0.5, 0.2, 1.0, "µm").sentence() == \
        "e_x 0.50 ± 0.20 µm: RMS + U = 0.70 µm <= 1 µm band: conformance shown (ISO 14253-1)"
    assert "nonconformance shown" in judge("e_z", 2.0, 0.2, 1.0, "µm").sentence()
    assert verdict.as_dict()["conformance"] == "undecided"


def test_components_together():
    within, undecided, outside = Conformance.WITHIN, Conformance.UNDECIDED, Conformance.OUTSIDE
    assert overall([within, within]) is within
    assert overall([within, undecided]) is undecided
    assert overall([undecided, outside, within]) is outside
    assert overall([]) is undecided     # nothing judged: nothing shown


@pytest.mark.parametrize("rms, u, limit", [(float("nan"), 0.1, 1.0), (0.5, -0.1, 1.0),
                                           (0.5, 0.1, 0.0)])
def test_figures_nothing_can_be_decided_from_are_refused(rms, u, limit):
    with pytest.raises(ParameterError, match="conformance"):
        conformance(rms, u, limit)


def test_a_phase_is_within_only_when_conformance_is_shown():
    from mt_accuracy_ros.core.workbench.closed_loop import END_WINDOW_S, loop_phases

    rng = np.random.default_rng(1)
    t = np.arange(250) * 0.37
    # 0.79 um RMS on y, the instrument of U = 1 um: over 10 s (27 readings) undecided,
    # over the end window (~80 readings) still undecided at 0.9 um, within at 0.6 um.
    for sigma, expected in ((0.9e-6, Conformance.UNDECIDED), (0.6e-6, Conformance.WITHIN),
                            (3e-6, Conformance.OUTSIDE)):
        measured = rng.normal(0, sigma, (t.size, 3))
        end = loop_phases(t, measured, np.zeros_like(measured), [], 1e-6)[-1]
        assert end.end_s - end.start_s == pytest.approx(END_WINDOW_S, abs=0.4)
        assert end.conformance(1e-6) is expected, [v.sentence() for v in end.verdicts(1e-6)]
        assert end.within(1e-6) is (expected is Conformance.WITHIN)


def _readings(n: int, sigma_m: float, *, direction: bool = True, seed: int = 3):
    """n reference readings 0.37 s apart, compensated error of ``sigma_m`` per component,
    as the demo holds them (and a tool direction of 1 urad spread when ``direction``)."""
    rng = np.random.default_rng(seed)
    references, orientations = [], []
    for k in range(n):
        references.append((0.37 * k, rng.normal(0, sigma_m, 3), np.zeros(3), 1, 1e-6))
        orientations.append((rng.normal(0, 1e-6, 3), np.zeros(3), 5e-6) if direction else None)
    return references, orientations


def test_the_end_state_is_told_in_three_states_with_the_figures():
    from mt_accuracy_ros.commands.demo import loop_story

    references, _ = _readings(250, 0.5e-6)
    story = loop_story(references, [], [], compensation_mode="hybrid")
    assert story["end_state_conformance"] == "within" and story["end_state_within_band"]
    assert any("RMS + U = " in line and "conformance shown (ISO 14253-1)" in line
               for line in story["lines"])
    # RMS 0.9 um over the end window's ~80 readings: U (~0.17 um) straddles the band.
    noisy, _ = _readings(250, 0.9e-6)
    story = loop_story(noisy, [], [], compensation_mode="hybrid")
    assert story["end_state_conformance"] == "undecided"
    assert story["end_state_within_band"] is False
    assert any("conformance not shown" in v["sentence"] for v in story["end_state_verdicts"])
    far, _ = _readings(250, 3e-6)
    assert loop_story(far, [], [], compensation_mode="hybrid")["end_state_conformance"] == \
        "outside"


def test_a_reading_without_a_tool_direction_is_a_warning_not_a_silent_fallback():
    from mt_accuracy_ros.commands.demo import loop_story

    references, orientations = _readings(250, 0.4e-6)
    orientations[7] = None
    story = loop_story(references, [], [], compensation_mode="hybrid",
                       orientations=orientations, five_axis=True)
    assert story["warnings"] == ["1 of 250 reference readings carry no tool direction: the "
                                 "direction is judged on the 249 that do"]
    names = [v["name"] for v in story["end_state_verdicts"]]
    assert names == ["e_x", "e_y", "e_z", "direction about x", "direction about y",
                     "direction about z"]
    assert story["end_state_conformance"] == "within"
    # A five-axis run with no direction at all: not judged, so conformance is not shown.
    story = loop_story(references, [], [], compensation_mode="hybrid", orientations=None,
                       five_axis=True)
    assert story["warnings"][0].startswith("250 of 250 reference readings carry no tool "
                                           "direction")
    assert story["end_state_conformance"] == "undecided"


