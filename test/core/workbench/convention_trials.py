"""One trial of ``studies.convention_surveys``, drawn as in a whole proof's set and checked as
a user runs it: shared by the tests that judge the workbench on the independent generator."""
from __future__ import annotations

import json

import numpy as np

from bench.convention_proof import linear_strokes, run_check
from studies import convention_surveys as cs


def write_trial(folder, seed: int, index: int) -> dict:
    """Write trial ``index`` of ``seed``'s draw (the same as in a whole proof's set: one
    independent stream per trial) into ``folder``; its truth, with the strokes."""
    stream = np.random.SeedSequence(seed).spawn(index + 1)[index]
    rng = np.random.default_rng(stream)
    cs.write_trial(cs.draw_trial(rng, f"trial_{index:03d}"), folder, rng)
    truth = json.loads((folder / "truth.json").read_text())
    truth["strokes_m"] = linear_strokes(folder / "machine.yaml")
    return truth


def checked(folder) -> dict:
    """``check survey.csv --columns map.yaml --auto 3 --json`` of the trial in ``folder``."""
    result, printed, _ = run_check(folder)
    assert result is not None, printed
    return result
