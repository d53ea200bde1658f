"""Every HTML report of the package: one Jinja2 template, plots as PNG files beside it.

A report is a :class:`Report` of :class:`Section` s, each with paragraphs,
tables and figures; :func:`render` writes it through
``templates/report.html.j2`` (autoescaped, so no text of a bag or CSV can
inject markup). The builders turn what a command produced into sections:

* :func:`write_demo_report`  - the main job on the virtual machine tool;
* :func:`write_check_report` - ``mt-accuracy check`` on a bag or a CSV table.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

TEMPLATE = "report.html.j2"


@dataclass(frozen=True)
class Cell:
    text: str
    numeric: bool = False


@dataclass(frozen=True)
class Row:
    cells: list[Cell]
    css_class: str = ""


@dataclass
class Table:
    columns: list[str]
    rows: list[Row] = field(default_factory=list)
    caption: str = ""

    def add(self, *values, css_class: str = "") -> None:
        """Append a row; numbers are right-aligned, floats shown to 4 significant digits."""
        self.rows.append(Row([_cell(v) for v in values], css_class))


@dataclass(frozen=True)
class Figure:
    source: str  # relative to the report
    caption: str


@dataclass
class Section:
    title: str
    paragraphs: list[str] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)

    @property
    def anchor(self) -> str:
        return "-".join("".join(c if c.isalnum() else " " for c in self.title.lower()).split())


@dataclass
class Report:
    title: str
    subtitle: str = ""
    sections: list[Section] = field(default_factory=list)


def _cell(value) -> Cell:
    if isinstance(value, bool):
        return Cell(str(value).lower())
    if isinstance(value, (int, np.integer)):
        return Cell(str(value), numeric=True)
    if isinstance(value, (float, np.floating)):
        return Cell(f"{value:.4g}", numeric=True)
    return Cell(str(value))


def render(report: Report, path: Path) -> Path:
    """Write ``report`` as HTML to ``path`` (its figures must already be beside it)."""
    from jinja2 import Environment, PackageLoader, StrictUndefined, select_autoescape

    from . import __version__

    environment = Environment(loader=PackageLoader("mt_accuracy_ros", "templates"),
                              autoescape=select_autoescape(default=True),
                              undefined=StrictUndefined, trim_blocks=True, lstrip_blocks=True)
    page = environment.get_template(TEMPLATE).render(
        title=report.title, subtitle=report.subtitle, sections=report.sections,
        version=__version__)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(page, encoding="utf-8")
    return path


def save_figure(fig, directory: Path, name: str, caption: str) -> Figure:
    """Save a matplotlib figure as ``directory/name.png`` and close it."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    target = Path(directory) / f"{name}.png"
    fig.savefig(target, dpi=100)
    plt.close(fig)
    return Figure(target.name, caption)


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


# --- the main job -------------------------------------------------------------------


def write_demo_report(out: Path, checks, actions, alarms, compensation, summary: dict) -> Path:
    """The main job's report: the model against the reference, the compensation, the summary.

    ``checks`` are ``(scenario time [s], ModelCheck-like)`` pairs, ``actions``
    the effects the demo added (``time_s``, ``added``), ``alarms`` the
    deterioration alarms ``(time [s], axis)``, ``compensation`` the broadcast
    ``(stamp [ns], |TCP error| [m])`` pairs.
    """
    plt = _pyplot()
    out = Path(out)
    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=False)
    if checks:
        t = np.array([c[0] for c in checks])
        axes[0].plot(t, [c[1].rmse * 1e6 for c in checks], "k.-",
                     label="residual RMSE (reference - model)")
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
    figure = save_figure(fig, out, "report", "The model against the reference over the run, "
                         "and the broadcast compensation.")
    overview = Section("Model against reference", figures=[figure])
    values = Table(["quantity", "value"])
    for key, value in summary.items():
        values.add(key, value)
    results = Section("Summary", tables=[values])
    candidates = Section("Candidate effects at the end")
    if checks:
        ranking = Table(["effect", "CV RMSE after [µm]", "reduction", "why"])
        for score in checks[-1][1].ranking[:6]:
            ranking.add(score.effect, score.cv_rmse_after * 1e6,
                        f"{100 * score.error_reduction:.0f} %", score.explanation)
        candidates.tables.append(ranking)
    report = Report("mt_accuracy_ros - main job report",
                    "The virtual machine tool streamed through the live graph.",
                    [overview, results, candidates])
    return render(report, out / "report.html")


# --- mt-accuracy check ----------------------------------------------------------------


def write_check_report(result: dict, plot: dict, path: Path) -> Path:
    """``mt-accuracy check``'s report from its result dictionary and plot data."""
    plt = _pyplot()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    stem = path.with_suffix("").name
    figures = []
    if result["kind"] == "csv":
        fig, ax = plt.subplots(figsize=(10, 4))
        hours = (plot["time"] - plot["time"][0]) / 3600
        ax.plot(hours, plot["target"], "k-", lw=0.8, label="measured")
        ax.plot(hours, plot["before"], "b-", lw=0.8,
                label=f"model before ({result['baseline_rmse']:.3g} held out)")
        ax.plot(hours, plot["after"], "r-", lw=0.8,
                label=f"after adding {', '.join(result['added']) or 'nothing'} "
                      f"({result['final_rmse']:.3g})")
        split = hours[np.argmin(plot["train"])] if not plot["train"].all() else hours[-1]
        ax.axvline(split, color="0.5", ls="--")
        ax.set(xlabel="time [h] (trained left of the dashed line, judged right)",
               ylabel=result["target"], title="model vs measurement")
        ax.legend(fontsize=8)
        figures.append(save_figure(fig, path.parent, f"{stem}_fit",
                                   "Measured against the model before and after."))
    else:
        figures.append(_residual_figure(plt, result, plot, path.parent, stem))
    fig, ax = plt.subplots(figsize=(10, 4))
    top = result["ranking"][:10]
    ax.barh([r["effect"] for r in top][::-1],
            [max(0, r["error_reduction"]) * 100 for r in top][::-1],
            color=["tab:green" if r["significant"] else "0.6" for r in top][::-1])
    ax.set(xlabel="cross-validated error reduction [%]", title="candidate effects")
    figures.append(save_figure(fig, path.parent, f"{stem}_ranking",
                               "Candidate effects (green: significant)."))
    held_out = " (judged on held-out rows)" if result["kind"] == "csv" else ""
    headline = Section("Result", paragraphs=[
        f"Data: {result['data']}.",
        f"Baseline RMSE {result['baseline_rmse']:.4g}, final RMSE {result['final_rmse']:.4g} "
        f"after adding {', '.join(result['added']) or 'nothing'}{held_out}."], figures=figures)
    ranking = Table(["effect", "CV RMSE after", "reduction", "significant", "why"])
    for r in result["ranking"][:15]:
        ranking.add(r["effect"], r["cv_rmse_after"], f"{100 * r['error_reduction']:.1f} %",
                    r["significant"], r["explanation"],
                    css_class="accepted" if r["significant"] else "rejected")
    steps = Table(["model version"] + sorted({k for s in result["steps"] for k in s} - {"model_version"}))
    for s in result["steps"]:
        steps.add(s.get("model_version", ""), *[s.get(k, "") for k in steps.columns[1:]])
    report = Report("mt-accuracy check", f"Model against measurement: {result['data']}", [
        headline, Section("Candidates", tables=[ranking]), Section("Model versions", tables=[steps])])
    return render(report, path)


def _residual_figure(plt, result: dict, plot: dict, directory: Path, stem: str) -> Figure:
    residual_after = plot["residual_after"]
    fig, axes = plt.subplots(2, 2, figsize=(11, 7))
    band = result["band"] * 1e6
    for c, label in enumerate("xyz"):
        axes[0, 0].plot(plot["time"], residual_after[:, c] * 1e6, ".", ms=3, label=f"e_{label}")
    axes[0, 0].axhspan(-band, band, color="g", alpha=0.15, label="2u band")
    axes[0, 0].set(xlabel="time [s]", ylabel="residual after [µm]", title="where it fails: time")
    axes[0, 0].legend(fontsize=7)
    for axis, values in plot["positions"].items():
        axes[0, 1].plot(values * 1e3, np.linalg.norm(residual_after, axis=1) * 1e6, ".",
                        ms=3, label=axis)
    axes[0, 1].set(xlabel="position [mm]", ylabel="|residual| [µm]",
                   title="where it fails: position")
    axes[0, 1].legend(fontsize=7)
    for sensor in list(plot["temperatures"])[-4:]:
        values = plot["temperatures"][sensor]
        axes[1, 0].plot(values - values[0], np.linalg.norm(residual_after, axis=1) * 1e6, ".",
                        ms=3, label=sensor)
    axes[1, 0].set(xlabel="temperature rise [K]", ylabel="|residual| [µm]",
                   title="where it fails: temperature")
    axes[1, 0].legend(fontsize=7)
    rmse = [s["rmse"] * 1e6 for s in result["steps"]]
    axes[1, 1].bar(range(len(rmse)), rmse, color="tab:red")
    axes[1, 1].set_xticks(range(len(rmse)), [f"v{s['model_version']}" for s in result["steps"]])
    axes[1, 1].set(ylabel="residual RMSE [µm]", title="the error falling, model versions")
    return save_figure(fig, directory, f"{stem}_residuals",
                       "Where the model fails: residual against time, position and temperature; "
                       "the error falling over model versions.")
