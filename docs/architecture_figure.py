"""Draw docs/figures/architecture.png: the layers and the data flow.

``.venv/bin/python docs/architecture_figure.py``
"""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch  # noqa: E402

OUT = Path(__file__).resolve().parent / "figures" / "architecture.png"

#: name -> (x, y, width, height, colour, label)
BOXES = {
    "machine": (0.2, 7.6, 3.0, 1.1, "#f3e3c3", "scale heads, thermocouples,\nreference instrument\n"
                                                 "(real cell or virtual machine: sim/)"),
    "encoder": (0.2, 5.4, 3.0, 1.2, "#dbe8f6", "encoder_publisher\ntemperature_publisher\n"
                                                 "(virtual machine nodes)"),
    "yaw": (4.4, 6.9, 3.2, 1.1, "#dbe8f6", "yaw_estimator\ncore.scales: yaw, kNN, deterioration"),
    "monitor": (4.4, 4.3, 3.2, 1.1, "#dbe8f6", "model_monitor\ncore.workbench: residual, diagnosis"),
    "broadcaster": (8.8, 5.4, 3.2, 1.2, "#dbe8f6", "compensation_broadcaster\n"
                                                     "core.compensation: error model, tables"),
    "cnc": (8.8, 7.7, 3.2, 1.0, "#f3e3c3", "CNC / users\n(compensation input, Foxglove)"),
    "recorder": (4.4, 2.3, 3.2, 1.0, "#dbe8f6", "recorder -> MCAP bag (io)\nbag_player replays it"),
    "check": (8.8, 2.3, 3.2, 1.0, "#e4f2e1", "mt-accuracy check / demo\nreport.py + template -> HTML"),
    "core": (0.2, 0.2, 11.8, 1.1, "#eeeeee", "core/ (numpy, scipy; no ROS): scales | kinematics | "
                                             "thermal | compensation | workbench"),
}
#: (from, to, label)
ARROWS = [
    ("machine", "encoder", "hardware / simulation"),
    ("encoder", "yaw", "scales, temperatures"),
    ("encoder", "monitor", "reference/tcp_error"),
    ("yaw", "broadcaster", "systematic/<axis>"),
    ("monitor", "broadcaster", "model"),
    ("encoder", "broadcaster", "scales (command positions), temperatures"),
    ("broadcaster", "cnc", "compensation, compensation_table"),
    ("monitor", "recorder", "every topic"),
    ("recorder", "check", "bag"),
]


def centre(name: str) -> tuple[float, float]:
    x, y, w, h, *_ = BOXES[name]
    return x + w / 2, y + h / 2


def edge(name: str, towards: tuple[float, float]) -> tuple[float, float]:
    """Where the line from the box's centre towards a point leaves the box."""
    x, y, w, h, *_ = BOXES[name]
    cx, cy = centre(name)
    dx, dy = towards[0] - cx, towards[1] - cy
    scale = min((w / 2 + 0.08) / abs(dx) if dx else float("inf"),
                (h / 2 + 0.08) / abs(dy) if dy else float("inf"))
    return cx + dx * scale, cy + dy * scale


def main() -> Path:
    fig, ax = plt.subplots(figsize=(11, 8))
    for x, y, w, h, colour, label in BOXES.values():
        ax.add_patch(FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.05", fc=colour, ec="0.3"))
        ax.text(x + w / 2, y + h / 2, label, ha="center", va="center", fontsize=9)
    for start, end, label in ARROWS:
        x0, y0 = edge(start, centre(end))
        x1, y1 = edge(end, centre(start))
        ax.add_patch(FancyArrowPatch((x0, y0), (x1, y1), arrowstyle="-|>", mutation_scale=14,
                                     color="0.25"))
        if label:
            ax.text((x0 + x1) / 2, (y0 + y1) / 2 + 0.12, label, ha="center", fontsize=8,
                    color="#7a2e00", bbox=dict(fc="white", ec="none", alpha=0.8, pad=1))
    ax.text(6.1, 1.55, "every node calls the core; the core imports nothing above it",
            ha="center", fontsize=8, style="italic")
    ax.set(xlim=(0, 12.2), ylim=(0, 9), title="mt_accuracy_ros: nodes, topics and layers")
    ax.axis("off")
    fig.tight_layout()
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=90)
    plt.close(fig)
    return OUT


if __name__ == "__main__":
    print(main())
