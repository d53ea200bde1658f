"""Issue 28's proof: the workbench on surveys of machines it has never seen.

Surveys come from :mod:`studies.cartesian_surveys` (three Cartesian machines of
different travel and layout, closed-form errors, no code shared with the package)
and go through ``mt-accuracy check`` exactly as a user's logger CSV would: a column
map, no machine, no model. Every trial is reported, never the best of them.

* single effects: the right effect named first; a spurious extra effect named beside
  it; nothing named when nothing is hidden (false alarm);
* a low-SNR series: one straightness of one component whose coefficient is 5, 7 or
  10 standard errors, and how often it is named;
* a thermal log that leaves its training range: never silently worse than a constant.

    .venv/bin/python -m bench.independent_proof [--seeds 3] [--nulls 8] [--weak 10]
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from studies.cartesian_surveys import (KINDS, LAYOUTS, NotDrawn, accepted, judged,
                                       log_leaving_range, single_effect_trial, weak_bow_trial)


def check(csv: Path, column_map: Path, out: Path) -> dict:
    from mt_accuracy_ros.cli import main

    code = main(["check", str(csv), "--columns", str(column_map), "--auto", "3",
                 "--json", str(out)])
    if code != 0:
        raise RuntimeError(f"check exited {code} on {csv}")
    return json.loads(out.read_text())


def main(argv: list[str] | None = None) -> int:
    import contextlib
    import io

    parser = argparse.ArgumentParser(description=__doc__, allow_abbrev=False)
    parser.add_argument("--seeds", type=int, default=1, help="trials per machine and kind")
    parser.add_argument("--nulls", type=int, default=7, help="null trials per machine")
    parser.add_argument("--weak", type=int, default=10, help="trials per low-SNR level")
    parser.add_argument("--json", default=None, help="write every trial here")
    args = parser.parse_args(argv)
    trials, started = [], time.monotonic()
    quiet = contextlib.redirect_stdout(io.StringIO())
    with tempfile.TemporaryDirectory() as scratch:
        plan = [(m, k, 1000 * s + 17 * i + j, True) for s in range(args.seeds)
                for i, m in enumerate(LAYOUTS) for j, k in enumerate(KINDS)]
        plan += [(m, None, 50_000 + 100 * i + s, True) for i, m in enumerate(LAYOUTS)
                 for s in range(args.nulls)]
        # Table tilts on surveys whose map does not give the tool offset (the VMC).
        plan += [("vmc_500", k, 80_000 + 100 * j + s, False) for s in range(args.seeds)
                 for j, k in enumerate(("angular_table", "angular_tables"))]
        for number, (machine, kind, seed, tool_given) in enumerate(plan, 1):
            where = Path(scratch) / f"t{number}"
            label = (kind or "nothing") + ("" if tool_given else " (no tool offset)")
            try:
                csv, column_map, fair = single_effect_trial(machine, kind, seed, where,
                                                            give_tool_offset=tool_given)
            except NotDrawn as why:
                print(f"[{number}/{len(plan)}] {machine:12s} {label:9s} not drawn: {why}",
                      file=sys.stderr, flush=True)
                trials.append({"machine": machine, "kind": label, "seed": seed,
                               "not_drawn": str(why)})
                continue
            with quiet:
                result = check(csv, column_map, where / "s.json")
            named = [entry["name"] for entry in result["named"]]
            right, extra = judged(kind, named, fair)
            trials.append({"machine": machine, "kind": label, "seed": seed,
                           "named": named, "fair": sorted(fair), "right_first": right,
                           "spurious": extra, "notes": result.get("warnings", [])})
            print(f"[{number}/{len(plan)}] {machine:12s} {label:9s} named "
                  f"{', '.join(named) or '-'}: {'ok' if right and not extra else 'WRONG'}"
                  f"{' (extra: ' + ', '.join(extra) + ')' if extra and kind else ''}",
                  file=sys.stderr, flush=True)
        weak = {}
        for level in (5.0, 7.0, 10.0):
            hits = 0
            for seed in range(args.weak):
                where = Path(scratch) / f"w{level}_{seed}"
                csv, column_map, fair = weak_bow_trial(level, 7000 + seed, where)
                with quiet:
                    result = check(csv, column_map, where / "s.json")
                named = [entry["name"] for entry in result["named"]]
                hits += bool(named) and accepted(named[0], fair)
            weak[level] = hits / args.weak
            print(f"low SNR {level:g} sigma: named {hits} of {args.weak}", file=sys.stderr,
                  flush=True)
        log = log_leaving_range(3, Path(scratch) / "log.csv")
        from mt_accuracy_ros.commands.check_log import check_csv

        with quiet:
            result = check_csv(log, "growth_um", "time_s", ["t*_C"], [], [], 3, 0.5, 0.05,
                               [])
    drawn = [t for t in trials if "not_drawn" not in t]
    table_tilts = [t for t in drawn if t["kind"].startswith("angular_table")]
    effects = [t for t in drawn if t["kind"] != "nothing"]
    nulls = [t for t in drawn if t["kind"] == "nothing"]
    figures = {
        "single_effect_trials": len(effects),
        "right_named_first": sum(t["right_first"] for t in effects) / len(effects),
        "spurious_extra": sum(bool(t["spurious"]) for t in effects) / len(effects),
        "null_trials": len(nulls),
        "false_alarms": sum(bool(t["named"]) for t in nulls) / max(1, len(nulls)),
        "low_snr_named": weak,
        "right_named_first_count": f"{sum(t['right_first'] for t in effects)} of "
                                   f"{len(effects)}",
        "workpiece_side_tilts_named": f"{sum(t['right_first'] for t in table_tilts)} of "
                                      f"{len(table_tilts)}",
        "not_drawn": [f"{t['machine']} {t['kind']}" for t in trials if "not_drawn" in t],
        "log_added": result["added"], "log_not_added": result["not_added"],
        "log_held_out_um": result["final_rmse"] * 1e6,
        "log_constant_um": result["constant_held_out_rmse"] * 1e6,
        "log_warnings": result["warnings"],
        "wall_s": time.monotonic() - started,
    }
    print(json.dumps(figures, indent=2))
    print("\n| machine | kind | named | right first | spurious extra |")
    print("| --- | --- | --- | --- | --- |")
    for t in drawn:
        print(f"| {t['machine']} | {t['kind']} | {', '.join(t['named']) or '-'} | "
              f"{'yes' if t['right_first'] else 'no'} | {', '.join(t['spurious']) or '-'} |")
    if args.json:
        Path(args.json).write_text(json.dumps({"figures": figures, "trials": trials},
                                              indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
