"""The main job run again and again, as a new user would: idle and with CPU burners.

Every run is reported - never the best of them: exit code, the effects the user
added, the end state per component against the instrument's band, the model
versions (roll-backs included), stale corrections and the latency p99. The
markdown table goes to stdout (for docs/closed_loop.md).

    .venv/bin/python -m bench.demo_runs --runs 5 --burners 0
    .venv/bin/python -m bench.demo_runs --runs 3 --burners 2 --rate 1
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _burners(count: int) -> list[subprocess.Popen]:
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)]


def _from_bag(bag: Path) -> tuple[list[str], list[float]]:
    """The model versions' reasons after the start, and the compensated machine's mean
    error over the run's last 10 s [um] (its offset from the instrument's zero)."""
    import numpy as np

    from mt_accuracy_ros.io.bag_reader import decode, read_messages

    try:
        versions = [decode(m).reason for m in read_messages(bag, ["/model"])][1:]
        readings = [decode(m) for m in read_messages(bag, ["/reference/tcp_error"])]
    except Exception:  # noqa: BLE001 - a run that left no readable bag: said as "-"
        return [], [float("nan")] * 3
    if not readings:
        return versions, [float("nan")] * 3
    stamps = np.array([r.header.stamp.sec + r.header.stamp.nanosec * 1e-9 for r in readings])
    last = [r for r, t in zip(readings, stamps) if t >= stamps[-1] - 10.0]
    mean = np.mean([(r.error.x, r.error.y, r.error.z) for r in last], axis=0) * 1e6
    return versions, [float(v) for v in mean]


def run_once(out: Path, rate: float | None, machine: str, lockstep: bool = False) -> dict:
    command = [sys.executable, "-m", "mt_accuracy_ros.cli", "demo", "--out", str(out),
               "--machine", machine] + (["--lockstep"] if lockstep else [])
    if rate is not None:
        command += ["--rate", str(rate)]
    started = time.monotonic()
    done = subprocess.run(command, capture_output=True, text=True)
    wall = time.monotonic() - started
    summary_path = out / "summary.json"
    summary = json.loads(summary_path.read_text()) if summary_path.is_file() else {}
    end = (summary.get("closed_loop") or [{}])[-1].get("with_compensation", {})
    versions, mean = _from_bag(out / "bag")
    refits = [reason for reason in versions if reason.startswith("refitted")]
    return {"refits": "; ".join(r.split(" on ")[1] if " on " in r else r for r in refits) or "-",
            "end_mean_um": mean,
"code": done.returncode, "wall_s": wall,
            "added": ", ".join(summary.get("missing_effects_found", [])) or "-",
            "accepted": summary.get("effect_added_accepted"),
            "end_um": [end.get(c, {}).get("rms_um", float("nan")) for c in "xyz"],
            "within": summary.get("end_state_within_band"),
            "stale": summary.get("compensation_stale"),
            # When (data time) the stale ones were stamped, and the oldest one's age.
            "stale_window": (f" (at {summary['stale_between_s'][0]:.1f}-"
                             f"{summary['stale_between_s'][1]:.1f} s, up to "
                             f"{summary.get('worst_stale_age_ms', 0):.0f} ms late)"
                             if summary.get("stale_between_s") else ""),
            "applied": summary.get("compensation_applied"),
            "lost": summary.get("compensation_lost"),
            "p99_ms": summary.get("compensation_latency_p99_ms"),
            "rolled_back": sum("rolled back" in a for a in summary.get("model_alarms", [])),
            # Each check's latency [s of data] against the next one's due time (paced runs).
            "checks": summary.get("check_timing"),
            "failed": [line.strip()[len("FAILED: "):] for line in done.stdout.splitlines()
                       if line.strip().startswith("FAILED: ")]}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, allow_abbrev=False)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--burners", type=int, default=0,
                        help="CPU-burning processes alongside")
    parser.add_argument("--rate", type=float, default=None, help="the demo's --rate")
    parser.add_argument("--machine", default="kidani_hmc")
    parser.add_argument("--lockstep", action="store_true", help="the demo's --lockstep")
    args = parser.parse_args(argv)
    burners = _burners(args.burners)
    rows = []
    try:
        with tempfile.TemporaryDirectory() as scratch:
            for k in range(args.runs):
                result = run_once(Path(scratch) / f"run{k}", args.rate, args.machine,
                                  args.lockstep)
                rows.append(result)
                print(f"run {k + 1}/{args.runs}: exit {result['code']}, end state "
                      + "/".join(f"{v:.2f}" for v in result["end_um"])
                      + " um (mean " + "/".join(f"{v:+.2f}" for v in result["end_mean_um"])
                      + f"), refits: {result['refits']}, "
                      + f"stale {result['stale']}{result['stale_window']}, lost {result['lost']}, "
                      + (f"checks late {result['checks']['late']} of {result['checks']['checks']} "
                         f"(max {result['checks']['latency_max_s']:.1f} s), "
                         if result["checks"] else "")
                      + f"{result['wall_s']:.0f} s",
                      file=sys.stderr, flush=True)
    finally:
        for process in burners:
            process.kill()
    rate = args.rate if args.rate is not None else "default"
    print(f"\n`python -m bench.demo_runs --runs {args.runs} --burners {args.burners}"
          + (f" --rate {args.rate}" if args.rate is not None else "")
          + (" --lockstep" if args.lockstep else "") + f" --machine {args.machine}`"
          f" ({args.machine}, " + ("lockstep" if args.lockstep else f"rate {rate}")
          + f", {args.burners} CPU burners)\n")
    print("| run | exit | effects the user added | end state e_x / e_y / e_z [um] | its mean "
          "(off the instrument's zero) [um] | refits (the monitor's) | within "
          "band | roll-backs | corrections applied / stale / lost | p99 [ms] | checks late / "
          "made, each one's latency [s of data] | wall [s] | why not 0 |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for k, r in enumerate(rows, 1):
        print(f"| {k} | {r['code']} | {r['added']} | "
              + " / ".join(f"{v:.2f}" for v in r["end_um"]) + " | "
              + " / ".join(f"{v:+.2f}" for v in r["end_mean_um"])
              + f" | {r['refits']} | {'yes' if r['within'] else 'no'} | {r['rolled_back']}"
              + f" | {r['applied']} / "
              f"{r['stale']}{r['stale_window']} / {r['lost']} | {r['p99_ms']:.0f} | "
              + (f"{r['checks']['late']} / {r['checks']['checks']}: "
                 + ", ".join(f"{v:.1f}" for v in r["checks"]["latency_s"])
                 + f" (due after {r['checks']['period_s']:.1f}); search CPU [s] "
                 + ", ".join(f"{v:.2f}" for v in r["checks"].get("search_cpu_s", []))
                 if r["checks"] else "-")
              + f" | {r['wall_s']:.0f} | "
              f"{'; '.join(r['failed']) or '-'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
