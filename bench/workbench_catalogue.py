"""Proof of the open effect catalogue on hidden effects made outside the package.

``python -m bench.workbench_catalogue --seeds 5 --nulls 40 --pairs 30`` runs,
on both bundled machines (the 3-axis HMC and the 5-axis RPPPR grinder):

* every hidden-effect kind of :mod:`studies.foreign_machine` (16 kinds on
  both machines, 2 rotary kinds on the 5-axis one) at magnitudes drawn from
  2-20 um RMS at the TCP, ``--seeds`` seeds each;
* ``--nulls`` surveys per machine with nothing hidden (false alarms);
* ``--pairs`` surveys per machine with two different hidden effects at once.

Figures: named first, right variable localised, median error removed, false
alarms, both of a pair named; the per-kind table goes to docs/results.md.
"""
from __future__ import annotations

import argparse
import json
import os
from concurrent.futures import ProcessPoolExecutor

# One BLAS thread per worker: the fits are small, and two workers each spinning two
# threads on two cores spend their time waiting for each other.
for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")
from dataclasses import asdict

import numpy as np
from tqdm import tqdm

from studies.catalogue_trials import Outcome, run_trial
from studies.foreign_machine import KINDS_3AXIS, KINDS_ROTARY

MACHINES = {"kidani_hmc": KINDS_3AXIS, "khan_chen_rpppr": KINDS_3AXIS + KINDS_ROTARY}


def _run(job) -> Outcome:
    machine, kinds, seed = job
    return run_trial(machine, kinds, seed)


def jobs(seeds: int, nulls: int, pairs: int) -> list[tuple]:
    out = []
    for machine, kinds in MACHINES.items():
        out += [(machine, (kind,), 1000 + s) for kind in kinds for s in range(seeds)]
        out += [(machine, (), 5000 + s) for s in range(nulls)]
        rng = np.random.default_rng(7)
        for s in range(pairs):
            pair = tuple(str(k) for k in rng.choice(kinds, 2, replace=False))
            out.append((machine, pair, 9000 + s))
    return out


def summarise(outcomes: list[Outcome]) -> dict:
    singles = [o for o in outcomes if len(o.kinds) == 1]
    nulls = [o for o in outcomes if not o.kinds]
    pairs = [o for o in outcomes if len(o.kinds) == 2]
    per_kind = {}
    for o in singles:
        row = per_kind.setdefault(f"{o.machine}:{o.kinds[0]}", [])
        row.append(o)
    return {
        "single_trials": len(singles),
        "named_first": float(np.mean([o.named_first for o in singles])),
        "localised": float(np.mean([o.localised for o in singles])),
        "localised_by_the_top_variable_alone": float(np.mean([o.top_right for o in singles])),
        "median_tied_variables": float(np.median([o.tied_variables for o in singles])),
        "median_removed": float(np.median([o.removed for o in singles])),
        "null_trials": len(nulls),
        "false_alarms": float(np.mean([o.false_alarm for o in nulls])) if nulls else None,
        "pair_trials": len(pairs),
        "both_named": float(np.mean([o.all_named for o in pairs])) if pairs else None,
        "pair_median_removed": float(np.median([o.removed for o in pairs])) if pairs else None,
        "per_kind": {k: {"trials": len(v), "named_first": sum(o.named_first for o in v),
                         "localised": sum(o.localised for o in v),
                         "median_removed": float(np.median([o.removed for o in v])),
                         "magnitudes_um": [round(o.magnitudes_um[0], 1) for o in v],
                         "found_first": [o.found[0] if o.found else "-" for o in v]}
                     for k, v in sorted(per_kind.items())},
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--nulls", type=int, default=40)
    parser.add_argument("--pairs", type=int, default=30)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default="", help="write every outcome and the summary (JSON)")
    args = parser.parse_args()
    work = jobs(args.seeds, args.nulls, args.pairs)
    with ProcessPoolExecutor(args.jobs) as pool:
        outcomes = list(tqdm(pool.map(_run, work, chunksize=2), total=len(work),
                             desc="hidden-effect trials"))
    summary = summarise(outcomes)
    if args.out:
        with open(args.out, "w") as handle:
            json.dump({"summary": summary, "outcomes": [asdict(o) for o in outcomes]}, handle,
                      indent=1, default=float)
    print(json.dumps({k: v for k, v in summary.items() if k != "per_kind"}, indent=2))
    print("\n| machine: hidden kind | trials | named first | localised | median removed | "
          "first named (each trial) |\n| --- | --- | --- | --- | --- | --- |")
    for name, row in summary["per_kind"].items():
        print(f"| {name} | {row['trials']} | {row['named_first']} | {row['localised']} | "
              f"{row['median_removed']:.0%} | {', '.join(row['found_first'])} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
