"""Fuzz every loader and message handler: ``python -m bench.fuzz [--cases 10000]``.

Each target of :mod:`studies.fuzz_targets` runs ``--cases`` generated inputs
(hypothesis, fixed seed); the property is that only the package's own errors
escape. Prints one JSON line per target (cases run, uncaught exceptions, time)
and exits 1 if any target found one - with the falsifying input printed.
"""
from __future__ import annotations

import argparse
import json
import sys
import time

from hypothesis import HealthCheck, given, seed, settings
from tqdm import tqdm

from studies import fuzz_targets


def run_target(name: str, strategy, check, cases: int, random_seed: int) -> dict:
    count = {"n": 0}
    progress = tqdm(total=cases, desc=name, unit="case", leave=False, file=sys.stderr)

    def counted(value):
        count["n"] += 1
        progress.update(1)
        check(value)

    test = seed(random_seed)(settings(max_examples=cases, deadline=None, database=None,
                                      suppress_health_check=list(HealthCheck))(
        given(strategy)(counted)))
    started = time.perf_counter()
    failure = ""
    try:
        test()
    except Exception as exc:  # noqa: BLE001 - the report is the point
        import traceback

        failure = f"{type(exc).__name__}: {exc} | " + traceback.format_exc()[-1500:]
    progress.close()
    return {"target": name, "cases": count["n"], "uncaught": 1 if failure else 0,
            "seconds": round(time.perf_counter() - started, 1), "failure": failure}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cases", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=20261122)
    parser.add_argument("--only", nargs="*", help="target names (default all)")
    args = parser.parse_args(argv)
    targets = [(t.name, t.strategy, t.check) for t in fuzz_targets.loader_targets()]
    harness = fuzz_targets.NodeHarness()
    targets += [(name, strategy, check) for name, (strategy, check)
                in fuzz_targets.message_targets(harness).items()]
    failed = 0
    try:
        for name, strategy, check in targets:
            if args.only and name not in args.only:
                continue
            result = run_target(name, strategy, check, args.cases, args.seed)
            failed += result["uncaught"]
            print(json.dumps(result), flush=True)
    finally:
        harness.close()
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
