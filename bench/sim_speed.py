"""Simulator throughput (issue 6: >= 1,000,000 samples/s offline).

Generates 2,000,000 synchronous samples of all six scale heads (100 s at
20 kHz, three axes moving, thermal expansion, timing skew, parallelism,
reversal and noise on) and reports samples/s, every run. Baseline in the same
run, alternated with it: the same samples made as the encoder publisher makes
them, one call per 2 s window - the same work, checked sample for sample. (The
per-sample Python loop that used to stand here computed simpler equations than
the simulator's, so its ratio said nothing: dropped, issue 39.)
"""
from __future__ import annotations

import json
import time

import numpy as np

from mt_accuracy_ros.sim.machine_tool import simulate
from mt_accuracy_ros.sim.scenario import scenario_from_yaml

SCENARIO = """machine: kidani_hmc
seed: 1
duration_s: 100
sample_rate_hz: 20000
program: {type: back_and_forth, axes: [X, Y, Z], feed_m_per_min: 30}
effects: {scale_thermal_expansion: true, timing_skew: true, scale_parallelism: true, reversal: true}
"""


def windowed(scenario, window_s: float = 2.0) -> np.ndarray:
    """The same run as the encoder publisher makes it: one ``simulate`` per 2 s window."""
    size = int(window_s * scenario.sample_rate_hz)
    return np.concatenate([simulate(scenario, start_index=first,
                                    stop_index=min(first + size, scenario.n_samples)
                                    ).scale_readings
                           for first in range(0, scenario.n_samples, size)])


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    scenario = scenario_from_yaml(SCENARIO)
    whole_s, windowed_s = [], []
    for _ in range(args.repeats):   # alternated, so that both meet the same host state
        start = time.perf_counter()
        result = simulate(scenario)
        whole_s.append(time.perf_counter() - start)
        start = time.perf_counter()
        chunks = windowed(scenario)
        windowed_s.append(time.perf_counter() - start)
    # The same work: the windowed run gives the one call's readings, sample for sample.
    if not np.array_equal(chunks, result.scale_readings):
        raise SystemExit("the windowed run differs from the one call: not the same work")
    samples = result.scale_readings.shape[0]
    print(json.dumps({"samples": samples, "channels": result.scale_readings.shape[1],
                      "one_call_s_every_run": whole_s, "windowed_s_every_run": windowed_s,
                      "samples_per_s_median": samples / float(np.median(whole_s)),
                      "windowed_samples_per_s_median": samples / float(np.median(windowed_s)),
                      "ratio_of_medians": float(np.median(windowed_s) / np.median(whole_s))},
                     indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
