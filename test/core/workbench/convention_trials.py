"""One trial of ``studies.convention_surveys``, drawn as in a whole proof's set and checked as
a user runs it: shared by the tests that judge the workbench on the independent generator."""
from __future__ import annotations

import json

import numpy as np

from bench.convention_proof import linear_strokes, run_check
from studies import convention_surveys as cs


def drawn_trial(seed: int, index: int, only: set[str] | None = None,
                noise_m: float | None = None) -> tuple[dict, np.random.Generator]:
    """Trial ``index`` of ``seed``'s draw (the same as in a whole proof's set: one
    independent stream per trial), and the stream that writes it.

    ``only``: keep just these of the drawn effects (by ISO name); ``noise_m``: the
    readings' noise [m] instead of the drawn one (the direction's over the generator's
    sphere distance). Either way the generator's own rigid bodies make the readings."""
    stream = np.random.SeedSequence(seed).spawn(index + 1)[index]
    rng = np.random.default_rng(stream)
    trial = cs.draw_trial(rng, f"trial_{index:03d}")
    if only is not None or noise_m is not None:
        if only is not None:
            trial["effects"] = [e for e in trial["effects"] if e["iso_name"] in only]
        sigma = trial["sigma_m"] if noise_m is None else noise_m
        position, direction = cs.located_errors(trial["machine"],
                                                cs.errs_from_effects(trial["effects"]),
                                                trial["rows"])
        noise = np.random.default_rng([seed, index, 11])
        trial.update(sigma_m=sigma, sigma_dir=sigma / cs.DIR_LEVER,
                     uncertainty_m=max(2 * sigma, 1e-8), located_direction=direction,
                     errors_m=position + noise.normal(0.0, sigma, position.shape),
                     dir_errors=direction + noise.normal(0.0, sigma / cs.DIR_LEVER,
                                                         direction.shape))
    return trial, rng


def write_trial(folder, seed: int, index: int, only: set[str] | None = None,
                noise_m: float | None = None) -> dict:
    """Write :func:`drawn_trial` into ``folder``; its truth, with the strokes."""
    trial, rng = drawn_trial(seed, index, only, noise_m)
    cs.write_trial(trial, folder, rng)
    truth = json.loads((folder / "truth.json").read_text())
    truth["strokes_m"] = linear_strokes(folder / "machine.yaml")
    return truth


def checked(folder) -> dict:
    """``check survey.csv --columns map.yaml --auto 3 --json`` of the trial in ``folder``."""
    result, printed, _ = run_check(folder)
    assert result is not None, printed
    return result
