"""The report's walk-forward section: each period's error over time, per method."""
from __future__ import annotations

from pathlib import Path

from . import Figure, Section, Table, pyplot, save_figure

#: Each method's line in the figure: (colour, style).
STYLES = {"workbench": ("r", "-"), "constant": ("0.4", "--"),
          "least squares on every input": ("b", "-."), "no model": ("0.7", ":")}


def walk_forward_figure(walk, unit: str, scale: float, directory: Path, stem: str) -> Figure:
    """Each period's RMS error against its time, one step line per method."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(10, 4))
    for method in walk.methods:
        colour, style = STYLES.get(method, ("k", "-"))
        times, values = [], []
        for figures in walk.periods:
            period = figures.period
            times += [period.time_start_s / 3600, period.time_stop_s / 3600]
            values += [figures.rmse_m[method] * scale] * 2
        ax.plot(times, values, color=colour, ls=style, lw=1.2,
                label=f"{method} (pooled {walk.pooled_m[method] * scale:.3g} {unit})")
    ax.set(xlabel="time, the log's [h]", ylabel=f"RMS error of the period [{unit}]",
           title=f"each {walk.period_text} predicted by a fit on every row before it")
    ax.legend(loc="best", fontsize=8)
    return save_figure(fig, directory, f"{stem}_walk",
                       "Walk-forward: at each period's end every method is fitted again on "
                       "every row so far and predicts the next period, as the package does "
                       "live with new reference readings.")


def walk_forward_section(walk, unit: str, scale: float, directory: Path, stem: str
                         ) -> Section:
    """The walk-forward's figure, its table per period and the pooled figures."""
    table = Table(["period", "rows", "fitted on"] + [f"{m} [{unit}]" for m in walk.methods]
                  + ["workbench model"],
                  caption="RMS error of each period, predicted by a fit on every row "
                          "before it; the last row pools every predicted row.")
    for figures in walk.periods:
        period = figures.period
        table.add(period.label, period.stop - period.start, figures.trained_rows,
                  *[figures.rmse_m[m] * scale for m in walk.methods],
                  figures.described.get("workbench", ""))
    table.add("pooled", walk.judged_rows, "", *[walk.pooled_m[m] * scale
                                               for m in walk.methods], "")
    better = walk.wins_over("workbench", ["constant", "least squares on every input"])
    return Section("Walk-forward", figures=[walk_forward_figure(walk, unit, scale, directory,
                                                                stem)],
                   tables=[table], paragraphs=[
        f"The log replayed in time: the figure a user running the package live gets. The "
        f"workbench {'beats' if better else 'does not beat'} both a constant and least "
        f"squares on every input, pooled over {walk.judged_rows} rows "
        f"({walk.pooled_m['workbench'] * scale:.4g} {unit} against "
        f"{walk.pooled_m['constant'] * scale:.4g} and "
        f"{walk.pooled_m['least squares on every input'] * scale:.4g} {unit}). The one split "
        "above is its worst case: one fit, never refreshed."])
