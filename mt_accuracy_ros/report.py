"""The demo's HTML report: model error over time, the effect added, the alarm."""
from __future__ import annotations

import html
from pathlib import Path

import numpy as np


def write_report(out: Path, checks, actions, alarms, compensation, summary: dict) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=False)
    if checks:
        t = np.array([c[0] for c in checks])
        axes[0].plot(t, [c[1].rmse * 1e6 for c in checks], "k.-", label="residual RMSE (reference - model)")
        axes[0].plot(t, [c[1].band * 1e6 for c in checks], "g--", label="instrument 2u")
        for action in actions:
            axes[0].axvline(action["time_s"], color="r", label=f"added {action['added']}")
        for when, axis in alarms:
            axes[0].axvline(when, color="orange", ls=":", label=f"deterioration alarm, {axis}")
        axes[0].set(xlabel="scenario time [s]", ylabel="µm", title="model vs reference")
        axes[0].legend(fontsize=8)
    if compensation:
        stamps = np.array([c[0] for c in compensation], dtype=float)
        axes[1].plot((stamps - stamps[0]) / 1e9, np.array([c[1] for c in compensation]) * 1e6,
                     ",", color="b")
        axes[1].set(xlabel="stamp time [s]", ylabel="|model TCP error| [µm]",
                    title="broadcast compensation (correction = -error)")
    fig.tight_layout()
    fig.savefig(out / "report.png", dpi=100)
    plt.close(fig)
    rows = "".join(f"<tr><td>{html.escape(str(k))}</td><td>{html.escape(str(v))}</td></tr>"
                   for k, v in summary.items())
    ranking = ""
    if checks:
        last = checks[-1][1]
        ranking = "".join(
            f"<tr><td>{html.escape(s.effect)}</td><td>{s.cv_rmse_after * 1e6:.2f}</td>"
            f"<td>{100 * s.error_reduction:.0f} %</td><td>{html.escape(s.explanation)}</td></tr>"
            for s in last.ranking[:6])
    page = (f"<html><head><meta charset='utf-8'><title>mt_accuracy_ros demo</title></head><body>"
            f"<h1>mt_accuracy_ros - main job report</h1><img src='report.png'>"
            f"<h2>Summary</h2><table border=1>{rows}</table>"
            f"<h2>Candidate effects at the end</h2><table border=1><tr><th>effect</th>"
            f"<th>CV RMSE after [µm]</th><th>reduction</th><th>why</th></tr>{ranking}</table>"
            f"</body></html>")
    path = out / "report.html"
    path.write_text(page)
    return path
