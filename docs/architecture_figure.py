"""Draw docs/figures/architecture.png: the data's path through the layers.

``.venv/bin/python docs/architecture_figure.py``

Five columns, left to right: where the readings come from, ``io/`` that reads and
writes them, the ROS-free ``core/`` by domain, the two ways the core is driven (the
live nodes, the ``mt-accuracy`` commands), and what comes out. The italic lines under
it are the import rules ``test/test_architecture.py`` checks.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 - the backend is chosen before pyplot loads
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch  # noqa: E402

OUT = Path(__file__).resolve().parent / "figures" / "architecture.png"

SOURCE, IO, CORE, DRIVER, OUTPUT = "#f3e3c3", "#e8e0f3", "#eeeeee", "#dbe8f6", "#e4f2e1"

#: name -> (x, y, width, height, colour, label)
BOXES = {
    # where the readings come from
    "cell": (0.1, 6.9, 2.5, 1.3, SOURCE, "machine tool\nscales, thermocouples,\n"
                                           "reference instrument, CNC"),
    "sim": (0.1, 5.1, 2.5, 1.3, SOURCE, "virtual machine sim/\n(own rigid bodies:\n"
                                          "the truth to judge by)"),
    "bag": (0.1, 3.3, 2.5, 1.2, SOURCE, "MCAP bag\n(recorded or simulated)"),
    "survey": (0.1, 1.3, 2.5, 1.5, SOURCE, "survey / log CSV\n+ column map YAML\n"
                                             "(laser, R-test, ball bar,\nthermal log)"),
    # io/
    "io": (3.2, 1.3, 2.3, 6.9, IO, "io/\n\nbag_reader\nbag_writer\nplayback\n\ncnc (OPC UA)\n\n"
                                   "column_map\ncsv_table\ncsv_dialect\nlaser_run\nrotary_csv\n"
                                   "fleet_inputs\n\nfields\noutput_paths"),
    # core/
    "core": (6.1, 1.3, 3.1, 6.9, CORE, "core/  (numpy, scipy;\nno ROS, no sim/)\n\n"
                                       "inputs: units, plausibility\nscales: yaw, kNN, ISO 230-2\n"
                                       "kinematics: HTMs, chain\nthermal: FE modes, regression\n"
                                       "effects: the catalogue\ncompensation: error model,\n"
                                       "   controller, CNC tables\nrotary: ball bar, probing\n"
                                       "workbench: diagnosis,\n   selection, refit\n"
                                       "fleet: trends\n\nerrors, validation"),
    # drivers
    "nodes": (9.8, 4.9, 2.9, 3.3, DRIVER, "nodes/  (rclpy)\n\nyaw_estimator\n"
                                          "compensation_broadcaster\nmodel_monitor\ncnc_bridge\n"
                                          "recorder, player\n\nencoder_ / temperature_publisher\n"
                                          "(the virtual machine)"),
    "commands": (9.8, 1.3, 2.9, 3.1, DRIVER,
                 "cli.py assembles commands/\n(add_parser + handler)\n\n"
                 "check, check_log, fleet\nsimulate, demo, record, play\n"
                 "iso230-2, ballbar, probe,\nexport, model, topic, info"),
    # what comes out
    "topics": (13.3, 5.9, 2.6, 2.3, OUTPUT, "topics\nscales, temperatures\nsystematic/<axis>\n"
                                            "compensation(_table)\nmodel_check, model\n"
                                            "/diagnostics\n\nrecorder -> MCAP bag"),
    "report": (13.3, 1.3, 2.6, 3.6, OUTPUT, "report/ + template\n-> HTML report\n\n"
                                            "CheckResult\n-> lines, JSON\n\n"
                                            "CNC tables,\nmodels (YAML)"),
}
#: (from, to, label)
ARROWS = [
    ("cell", "io", ""), ("bag", "io", ""), ("survey", "io", ""),
    ("sim", "io", "bag export"),
    ("io", "core", "arrays in SI,\nrefused if unit\nor shape unknown"),
    ("core", "nodes", "called"), ("core", "commands", "called"),
    ("nodes", "topics", "publish"), ("commands", "report", "render"),
]


def centre(name: str) -> tuple[float, float]:
    """The centre of box ``name`` in figure units."""
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


def _arrow(ax, start, end, label, **style) -> None:
    x0, y0 = edge(start, centre(end))
    x1, y1 = edge(end, centre(start))
    ax.add_patch(FancyArrowPatch((x0, y0), (x1, y1), arrowstyle="-|>", mutation_scale=14,
                                 color="0.25", **style))
    if label:
        ax.text((x0 + x1) / 2, (y0 + y1) / 2 + 0.15, label, ha="center", fontsize=7.5,
                color="#7a2e00", bbox=dict(fc="white", ec="none", alpha=0.85, pad=1))


def main() -> Path:
    """Draw the figure and return the path it was written to."""
    fig, ax = plt.subplots(figsize=(13.5, 7.2))
    for x, y, w, h, colour, label in BOXES.values():
        ax.add_patch(FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.05", fc=colour, ec="0.3"))
        ax.text(x + w / 2, y + h / 2, label, ha="center", va="center", fontsize=8.5,
                linespacing=1.25)
    for start, end, label in ARROWS:
        _arrow(ax, start, end, label)
    ax.text(7.65, 0.75, "core imports nothing above it (no rclpy, sim/, nodes/, io/, commands/);"
            " sim/ shares no physics with the core's model;",
            ha="center", fontsize=8, style="italic")
    ax.text(7.65, 0.4, "only the virtual machine's nodes import sim/; no node imports a command"
            " - test/test_architecture.py", ha="center", fontsize=8, style="italic")
    for x, text in ((1.35, "sources"), (4.35, "io/"), (7.65, "core/"),
                    (11.25, "nodes/ and commands/"), (14.6, "out")):
        ax.text(x, 8.5, text, ha="center", fontsize=10, weight="bold")
    ax.set(xlim=(0, 16), ylim=(0.2, 8.9))
    ax.set_title("mt_accuracy_ros: the data's path through the layers")
    ax.axis("off")
    fig.tight_layout()
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=90)
    plt.close(fig)
    return OUT


if __name__ == "__main__":
    print(main())
