"""A panel of regime-changing thermal logs from :mod:`studies.regime_logs`.

The first six logs of a panel are the cases every reader must face; the rest are drawn freely:

0. ``hdc``: one run of heating, dwell and cooling;
1. ``train_split``: the training part (first 50-70 % of the rows) holds one regime;
2. ``hot_run``: several runs, one where the spindle ran a larger share of the run;
3. ``unit_slip``: several runs, one where one sensor was logged in K or degF;
4. ``dead_sensor``: a dead thermocouple reading -180;
5. ``clock_jump``: several days marked only by a jump of the clock (no run column).

Usage: ``python -m studies.regime_logs_panel --seed 1 --n 8 --out /tmp/panel``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from studies.regime_logs import LogTruth, make_log

REQUIRED = (
    ("hdc", {"scenario": "hdc"}),
    ("train_split", {"scenario": "train_split"}),
    ("hot_run", {"scenario": "multi_run", "hot_run": True, "unit_slip": None}),
    ("unit_slip", {"scenario": "multi_run", "hot_run": False, "unit_slip": "K"}),
    ("dead_sensor", {"faults": ("dead",)}),
    ("clock_jump", {"scenario": "multi_run", "run_marking": "clock_jump",
                    "time_resets_per_run": False, "gap_kind": "days"}),
)


def _forced(tag: str, base: dict, index: int) -> dict:
    """Forced choices for a required case (the others follow from them when drawn); the unit
    slip is in K for even panel seeds, degF for odd ones."""
    forced = dict(base)
    if tag == "unit_slip" and index % 2:
        forced["unit_slip"] = "degF"
    return forced


def make_panel(seed: int, n: int, out_dir: Path, **common) -> list[LogTruth]:
    """Write ``n`` logs (the six required cases first, then free draws) into ``out_dir``.

    Parameters
    ----------
    seed : int
        Panel seed; log ``i`` uses seed ``1000 * seed + i``.
    n : int
        Number of logs (>= 1); with ``n < 6`` only the first ``n`` required cases.
    out_dir : Path
        Directory, created if missing.
    **common
        Choices forced on every log (for example ``max_rows``).

    Returns
    -------
    list of LogTruth
        The truths in panel order; each is also written beside its CSV.

    Raises
    ------
    ValueError
        ``n < 1``, or choices that contradict a required case.
    """
    if n < 1:
        raise ValueError(f"a panel needs n >= 1 logs, got {n}")
    truths = []
    for i in range(n):
        log_seed = 1000 * seed + i
        if i < len(REQUIRED):
            tag, base = REQUIRED[i]
            forced = {**common, **_forced(tag, base, seed)}
        else:
            tag, forced = "free", dict(common)
        name = f"panel{seed}_{i:02d}_{tag}"
        truths.append(make_log(log_seed, out_dir, name=name, **forced))
    return truths


def main(argv: list[str] | None = None) -> int:
    """Command line: write a panel and list its logs."""
    parser = argparse.ArgumentParser(description="write a panel of regime-changing logs")
    parser.add_argument("--seed", type=int, required=True)
    parser.add_argument("--n", type=int, default=8)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--max-rows", type=int, default=20000)
    args = parser.parse_args(argv)
    for truth in make_panel(args.seed, args.n, args.out, max_rows=args.max_rows):
        print(f"{truth.file}: {truth.choices.scenario}, {truth.format.n_rows} rows, "
              f"{len(truth.runs)} run(s), {len(truth.regimes)} regimes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
