"""docs/figures/closed_loop.png from a demo run's summary.json (issue 18).

    .venv/bin/python docs/closed_loop_figure.py demo_output/summary.json

Per TCP component: the RMS error at the reference points without compensation
(the whole run) and with the compensation the virtual CNC applied in each
phase (starting model, after the effect was added, after the deterioration
alarm, the end state), each with its k = 2 uncertainty.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main(summary_path: str) -> int:
    summary = json.loads(Path(summary_path).read_text())
    phases = summary["closed_loop"]
    bars = [("without compensation", phases[0]["without_compensation"])]
    bars += [(p["label"], p["with_compensation"]) for p in phases[1:]
             if not p["label"].startswith("before the first")]
    fig, ax = plt.subplots(figsize=(10, 4.2))
    width = 0.8 / len(bars)
    for k, (label, figures) in enumerate(bars):
        x = np.arange(3) + (k - (len(bars) - 1) / 2) * width
        values = [figures[c]["rms_um"] for c in "xyz"]
        errors = [figures[c]["u_k2_um"] for c in "xyz"]
        ax.bar(x, values, width, yerr=errors, capsize=2, label=label)
    band = summary.get("instrument_band_um", 1.0)
    ax.axhline(band, color="tab:green", ls="--", label=f"instrument band U = {band:.1f} µm")
    ax.set_xticks(range(3), ["e_x", "e_y", "e_z"])
    ax.set_ylabel("RMS TCP error at the reference points [µm]")
    ax.set_title("The virtual CNC applies the broadcast compensation: the machine's error, "
                 "phase by phase (k = 2)", fontsize=9)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    out = Path(__file__).parent / "figures" / "closed_loop.png"
    out.parent.mkdir(exist_ok=True)
    fig.savefig(out, dpi=110)
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "demo_output/summary.json"))
