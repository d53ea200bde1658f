"""Issue 30 (item 4): the workbench names a five-axis machine's rotary errors from the
tool's direction - on R-test surveys made outside the package.

Surveys come from :mod:`studies.five_axis_rtest` (Khan & Chen's RPPPR written out with
its own rotations, no code shared with the package), zeroed at the work offset. Each
seed draws the machine's errors at random (tilts of both rotary axes, A's zero, an
eccentric A bearing, its once-per-revolution positioning error) and is diagnosed twice:
with the R-test's direction readings and with its tip alone. The effects named are
added to a model referred to the same datum and judged on new readings of the same
machine (another seed): what the compensated machine would show. Every trial is
reported, never the best of them; a machine with nothing wrong is surveyed as well.

    .venv/bin/python -m bench.five_axis_proof [--seeds 10] [--json FILE]
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from studies.five_axis_rtest import FiveAxisErrors, reading_fields, survey

DATUM = {"X": 0.3, "Y": 0.2, "Z": 0.2, "A": 0.0, "B": 0.0}


def drawn(seed: int) -> FiveAxisErrors:
    """Errors of the size a five-axis machine has: tilts 10-50 urad, a 3-8 um eccentric
    bearing with a 5-20 urad positioning error, random signs and phase."""
    rng = np.random.default_rng([30, seed])
    tilt = lambda: tuple(rng.choice([-1, 1], 3) * rng.uniform(10e-6, 50e-6, 3))  # noqa: E731
    b_tilt = tilt()
    return FiveAxisErrors(a_tilt=tilt(), b_tilt=(b_tilt[0], 0.0, b_tilt[2]),
                          a_radial_m=float(rng.uniform(3e-6, 8e-6)),
                          a_phase_rad=float(rng.uniform(0, 2 * np.pi)),
                          a_positioning_rad=float(rng.uniform(5e-6, 20e-6)))


def trial(errors: FiveAxisErrors, seed: int, with_direction: bool) -> dict:
    from mt_accuracy_ros.core.compensation.error_model import ErrorModel
    from mt_accuracy_ros.core.compensation.five_axis import tool_direction
    from mt_accuracy_ros.core.kinematics.machine import load_machine
    from mt_accuracy_ros.core.workbench.diagnosis import Observations, add_effects, diagnose

    obs = Observations(**reading_fields(survey(errors, readings=240, seed=seed, datum=DATUM),
                                        with_direction))
    model = ErrorModel(load_machine("khan_chen_rpppr"), datum=dict(DATUM))
    started = time.perf_counter()
    diagnosis = diagnose(model, obs, max_effects=5)
    seconds = time.perf_counter() - started
    fitted = add_effects(model, diagnosis.selected, obs)
    new = survey(errors, readings=200, seed=seed + 10_000, datum=DATUM)
    position, orientation = fitted.tcp_error(new.positions, work_point=new.work_point_m)
    axis = tool_direction(fitted.kinematics, new.positions)
    orientation = orientation - axis * np.einsum("ni,ni->n", orientation, axis)[:, None]
    before_position = np.sqrt(np.mean(new.position_error_m ** 2, axis=0))
    before_direction = np.sqrt(np.mean(new.direction_error_rad ** 2, axis=0))
    return {"named": [c.name for c in diagnosis.selected],
            "position_before_um": (before_position * 1e6).round(2).tolist(),
            "position_after_um": (np.sqrt(np.mean((new.position_error_m - position) ** 2,
                                                  axis=0)) * 1e6).round(2).tolist(),
            "direction_before_urad": (before_direction * 1e6).round(2).tolist(),
            "direction_after_urad": (np.sqrt(np.mean((new.direction_error_rad - orientation)
                                                     ** 2, axis=0)) * 1e6).round(2).tolist(),
            "diagnosis_s": round(seconds, 2)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, allow_abbrev=False)
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--json", default=None)
    args = parser.parse_args(argv)
    rows = []
    plan = [(seed, drawn(seed)) for seed in range(args.seeds)] + \
        [(-1 - seed, FiveAxisErrors()) for seed in range(max(1, args.seeds // 3))]
    for number, (seed, errors) in enumerate(plan, 1):
        for with_direction in (True, False):
            row = {"seed": seed, "nothing_wrong": seed < 0, "direction": with_direction,
                   **trial(errors, 1000 + abs(seed), with_direction)}
            rows.append(row)
            measured = 'tip+direction' if with_direction else 'tip only     '
            print(f"[{number}/{len(plan)}] seed {seed:3d} {measured}"
                  f" named {', '.join(row['named']) or '-'}; held out: tip "
                  f"{row['position_after_um']} um, direction {row['direction_after_urad']} urad",
                  file=sys.stderr, flush=True)

    def share(selected, test):
        return f"{sum(test(r) for r in selected)} of {len(selected)}"

    faulty = [r for r in rows if not r["nothing_wrong"]]
    figures = {}
    for with_direction in (True, False):
        chosen = [r for r in faulty if r["direction"] is with_direction]
        key = "tip_and_direction" if with_direction else "tip_only"
        figures[key] = {
            "rotary_location_AB_named_first": share(
                chosen, lambda r: bool(r["named"]) and r["named"][0] == "rotary_location:AB"),
            "A_positioning_named": share(chosen, lambda r: "rotary_error:EAA" in r["named"]),
            "tip_within_0.7_um": share(chosen, lambda r: max(r["position_after_um"]) <= 0.7),
            "direction_within_1.5_urad": share(
                chosen, lambda r: max(r["direction_after_urad"]) <= 1.5),
            "worst_direction_after_urad": max(max(r["direction_after_urad"]) for r in chosen),
            "median_diagnosis_s": float(np.median([r["diagnosis_s"] for r in chosen])),
        }
    nulls = [r for r in rows if r["nothing_wrong"]]
    figures["nothing_wrong_false_alarms"] = share(nulls, lambda r: bool(r["named"]))
    print(json.dumps(figures, indent=2))
    if args.json:
        Path(args.json).write_text(json.dumps({"figures": figures, "trials": rows}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
