"""The fleet report: every machine's error over time with its named effects, the effects
many machines share, the machines that drift ranked, and the data refused."""
from __future__ import annotations

from pathlib import Path


from . import Report, Section, Table, pyplot, render, save_figure

UM = 1e6


def _dates(days: list[dict]):
    import datetime as dt

    return [dt.date.fromordinal(int(d["day_number"])) if d["day_number"] is not None else None
            for d in days]


def _over_time_figure(summary: dict, directory: Path, stem: str):
    """Each machine's model error per day (solid) and what its named effects leave
    (dashed), one colour per machine; drifting machines drawn thick."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(9, 4.2))
    drifting = {item["machine"] for item in summary["drift_ranking"] if item["drifting"]}
    for k, (name, entry) in enumerate(summary["machines"].items()):
        days = entry["days"]
        if not days:
            continue
        dates = _dates(days)
        x = [d if d is not None else i for i, d in enumerate(dates)]
        colour = f"C{k % 10}"
        width = 2.6 if name in drifting else 1.3
        ax.plot(x, [d["rmse_m"] * UM for d in days], "o-", color=colour, linewidth=width,
                label=f"{name}{' (drifts)' if name in drifting else ''}")
        ax.plot(x, [d["final_rmse_m"] * UM for d in days], "x--", color=colour, linewidth=1.0,
                label=f"{name}, with its named effects")
    dated = [d for e in summary["machines"].values() for d in _dates(e["days"]) if d]
    if dated:
        from matplotlib.dates import DateFormatter, DayLocator

        # Whole days on the axis, never hours: at most about ten ticks.
        span = (max(dated) - min(dated)).days
        ax.xaxis.set_major_locator(DayLocator(interval=max(1, -(-span // 10))))
        ax.xaxis.set_major_formatter(DateFormatter("%Y-%m-%d"))
    ax.set_xlabel("day (UTC)")
    ax.set_ylabel("RMS error of the model [um]")
    ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    fig.autofmt_xdate()
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    return save_figure(fig, directory, f"{stem}_over_time",
                       "Each machine's model against its reference readings, day by day "
                       "(solid), and what remains once the effects named that day are "
                       "added (dashed).")


def _fleet_section(summary: dict, directory: Path, stem: str) -> Section:
    ran = summary["ran_on"]
    section = Section("The fleet", [
        f"{summary['machine_count']} machines, {summary['tasks']} machine-days diagnosed on "
        f"{ran['workers']} Dask workers ({ran['scheduler']}) in {summary['wall_s']:.1f} s. "
        f"{len(summary['refused'])} files were refused (below, with their reasons); every "
        "other file was checked by mt-accuracy check's engine, its effects named by "
        "time-blocked cross-validation."])
    table = Table(["machine", "days", "first day [um]", "last day [um]",
                   "trend [um/day]", "drifts", "effects named"],
                  caption="Each machine: its model's RMS error on its first and last day, "
                          "the least-squares trend over its days (± one standard error), and "
                          "every effect named on any day.")
    for name, entry in summary["machines"].items():
        trend = entry.get("trend")
        if trend is None:
            table.add(name, 0, "-", "-", "-", "-", "no day could be read", css_class="warn")
            continue
        spread = trend["slope_standard_error_m_per_day"]
        table.add(name, trend["days"], trend["first_m"] * UM, trend["last_m"] * UM,
                  f"{trend['slope_m_per_day'] * UM:+.3g}"
                  + (f" ± {spread * UM:.2g}" if spread is not None else ""),
                  trend["drifting"], ", ".join(entry.get("named_effects", [])) or "nothing",
                  css_class="warn" if trend["drifting"] else "")
    section.tables.append(table)
    section.figures.append(_over_time_figure(summary, directory, stem))
    return section


def _machine_section(name: str, entry: dict) -> Section:
    section = Section(f"Machine {name}")
    table = Table(["day", "readings", "model [um]", "with named effects [um]",
                   "effects named (U, k = 2)"])
    for day in entry["days"]:
        effects = "; ".join(
            f"{e['name']}" + (f" ({', '.join(f'{k} = {v}' for k, v in e['display'].items())})"
                              if e.get("display") else "") for e in day["effects"])
        table.add(day["day"], day["readings"], day["rmse_m"] * UM, day["final_rmse_m"] * UM,
                  effects or "nothing")
    section.tables.append(table)
    if entry["refused"]:
        section.paragraphs.append(f"{len(entry['refused'])} of its files were refused: see "
                                  "'Refused data'.")
    return section


def _listing(title: str, items: list, empty: str, columns: list[str], row, css_class: str = ""
             ) -> Section:
    """A section of one table, a row per item (``row(item)`` -> cells), or ``empty``."""
    section = Section(title)
    if not items:
        section.paragraphs.append(empty)
        return section
    table = Table(columns)
    for item in items:
        table.add(*row(item), css_class=css_class)
    section.tables.append(table)
    return section


def _common_section(summary: dict) -> Section:
    return _listing("Effects common to many machines", summary["common_effects"],
                    "No effect was named on more than one machine.",
                    ["effect", "machines", "which"],
                    lambda item: (item["effect"], len(item["machines"]),
                                  ", ".join(item["machines"])))


def _drift_section(summary: dict) -> Section:
    section = Section("Machines that drift, ranked", [
        "A machine drifts when its model's error grows from day to day by more than the "
        "day-to-day scatter explains: the trend is positive and at least two standard "
        "errors from zero (three days or more), or on two days the error grew by half."])
    table = Table(["rank", "machine", "trend [um/day]", "days", "first [um]", "last [um]",
                   "drifts"])
    for rank, item in enumerate(summary["drift_ranking"], 1):
        table.add(rank, item["machine"], item["slope_m_per_day"] * UM, item["days"],
                  item["first_m"] * UM, item["last_m"] * UM, item["drifting"],
                  css_class="warn" if item["drifting"] else "")
    section.tables.append(table)
    return section


def _refused_section(summary: dict) -> Section:
    return _listing("Refused data", summary["refused"], "Every file was read and checked.",
                    ["machine", "day", "file", "reason"],
                    lambda item: (item["machine"], item["day"], Path(item["file"]).name,
                                  item["reason"]), css_class="fail")


def write_fleet_report(summary: dict, path: Path) -> Report:
    """The fleet report at ``path`` (its figure beside it); returns the :class:`Report`."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    stem = path.with_suffix("").name
    sections = [_fleet_section(summary, path.parent, stem), _drift_section(summary),
                _common_section(summary), _refused_section(summary)]
    sections += [_machine_section(name, entry) for name, entry in summary["machines"].items()
                 if entry["days"]]
    report = Report("mt-accuracy fleet", f"{summary['machine_count']} machines from "
                    f"{', '.join(summary['inputs'])}", sections)
    render(report, path)
    return report
