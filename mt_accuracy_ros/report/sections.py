"""The sections of a report, each with its plots: what a metrologist reads at a glance.

Every plot of a bag report uses one time base, "time since start [s]" (the
first sample of the data), puts its legend outside the axes, and draws the
reference instrument's k = 2 band where a residual is shown.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from ..commands.check_result import CheckResult, as_paragraph, readings_text, weights_sentence
from ..core.effects.display import display_parameters
from ..core.scales.repeatability import iso230_2, positioning_runs
from ..core.workbench.statistics import format_with_uncertainty, rms_with_uncertainty
from . import Figure, Section, Table, pyplot, save_figure
from .bag_data import BagData

TIME_LABEL = "time since start [s]"
COMPONENTS = "xyz"
UM = 1e6


def _legend(ax) -> None:
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)


# ----------------------------------------------------------------------- the bag
def bag_report_sections(data: BagData, check: CheckResult | None, directory: Path, stem: str
                        ) -> list[Section]:
    """A bag's sections, with the workbench's ``check`` of it when there is one."""
    sections = [_source_section(data, check), _headline_section(data, check)]
    if data.references:
        sections.append(closed_loop_section(data, directory, stem))
    if check is not None:
        sections += [_where_section(data, check, directory, stem),
                     localisation_section(check, directory, stem),
                     _evidence_section(check),
                     _recorded_versions_section(data) if data.models else
                     _versions_section(check)]
    else:
        sections.append(Section("Where the model fails", paragraphs=[
            "This data has no reference measurements (reference/tcp_error): the model cannot "
            "be judged against it."]))
    sections += [_axes_section(data, directory, stem), _temperature_section(data, directory, stem),
                 _iso_section(data, directory, stem), _table_section(data, directory, stem)]
    return sections


def _source_section(data: BagData, check: CheckResult | None) -> Section:
    from .. import __version__

    section = Section("Machine, data and instruments")
    info = data.info
    ends = [s for s in ([data.references[-1][0]] if data.references else []) +
            ([data.temperatures[-1][0]] if data.temperatures else [])]
    span = (max(ends) - data.start_ns) / 1e9 if ends else float("nan")
    section.paragraphs.append(
        f"Data: {data.path} - {info['message_count']} messages on {len(info['topics'])} topics, "
        f"{span:.1f} s of data time recorded in {info['duration_s']:.1f} s of wall time. "
        f"Software: mt_accuracy_ros {__version__}.")
    if data.models:
        model = yaml.safe_load(data.models[-1][1]) or {}
        section.paragraphs.append(f"Machine: {model.get('machine', '?')}; model versions "
                                  f"recorded: {len(data.models)}.")
    elif check is not None:
        section.paragraphs.append(f"Machine: {check.machine or '?'}.")
    sensors = Table(["sensor", "what", "rate", "uncertainty / resolution"])
    if data.scales is not None:
        period = float(data.scales.sample_period)
        sensors.add(", ".join(data.scales.channel_names), "linear scale heads (dual scales)",
                    f"{1 / period:.0f} Hz in {data.batch_count} batches", "see the yaw budget")
    instruments = {}
    for _, reading in data.references:
        instruments.setdefault(reading.instrument or "reference", []).append(reading.uncertainty)
    for name, values in instruments.items():
        span = (data.references[-1][0] - data.references[0][0]) / 1e9
        rate = (len(values) - 1) / span if span > 0 else 0.0
        sensors.add(name, "reference instrument (TCP error)", f"{rate:.2f} Hz",
                    f"{np.median(values) * UM:.2g} µm (k = 2)")
    if data.temperatures:
        names = data.temperatures[-1][1]
        span = (data.temperatures[-1][0] - data.temperatures[0][0]) / 1e9
        rate = (len(data.temperatures) - 1) / span if span > 0 else 0.0
        sensors.add(f"{len(names)} thermocouples ({', '.join(names[:6])}"
                    f"{', ...' if len(names) > 6 else ''})", "temperatures [°C]",
                    f"{rate:.2f} Hz", "")
    section.tables.append(sensors)
    return section


def _component_figures(values: np.ndarray, mask: np.ndarray, u_k2: float) -> list[str]:
    out = []
    for c in range(3):
        picked = values[mask[:, c], c]
        if picked.size == 0:
            out.append("not measured")
            continue
        figure = rms_with_uncertainty(picked * UM, u_k2 * UM)
        out.append(format_with_uncertainty(figure.rms, figure.rms_u_k2, "µm"))
    return out


def _band(data: BagData) -> tuple[float, str]:
    """The reference instrument's k = 2 band [m], and the sentence saying the documented
    default was taken when the readings state none."""
    from ..core.workbench.statistics import DEFAULT_POSITION_UNCERTAINTY_M, stated_uncertainty

    return stated_uncertainty([r.uncertainty for _, r in data.references],
                              DEFAULT_POSITION_UNCERTAINTY_M, "reference readings", "m")


def _measured_headline(data: BagData) -> tuple[Table, str] | None:
    """The instrument's measurement of the compensated machine per phase (None when the
    machine applied no compensation)."""
    from ..core.workbench.closed_loop import loop_phases
    from ..io.fields import machine_error

    if data is None or not data.references:
        return None
    measured = np.array([(r.error.x, r.error.y, r.error.z) for _, r in data.references])
    raw = np.array([machine_error(r) for _, r in data.references])
    if not np.any(measured - raw):
        return None
    band, note = _band(data)
    phases = loop_phases(data.seconds([s for s, _ in data.references]), measured,
                         measured - raw, loop_events(data), band)
    table = Table(["state", "readings"] + [f"RMS e_{c}" for c in COMPONENTS],
                  caption="Measured: RMS of the TCP error the reference instrument read on the "
                          "machine, per component, with its k = 2 uncertainty; 'without "
                          "compensation' is what it read minus what the CNC had added, at "
                          "every reading of the run" + (f" ({note})" if note else ""))
    table.add("without compensation (whole run)", phases[0].count,
              *[format_with_uncertainty(f.rms * UM, f.rms_u_k2 * UM, "µm")
                for f in phases[0].without])
    for phase in phases[1:]:
        table.add(f"{phase.label} [{phase.start_s:.0f}-{phase.end_s:.0f} s]", phase.count,
                  *[format_with_uncertainty(f.rms * UM, f.rms_u_k2 * UM, "µm")
                    for f in phase.with_compensation],
                  css_class="best" if phase.label == "end state" and phase.within(band) else "")
    end = phases[-1]
    verdict = (f"End of the run (last {end.end_s - end.start_s:.0f} s, the instrument's "
               f"band ± {band * UM:.2g} µm, k = 2): {_conformance_words(end.conformance(band))} "
               + "; ".join(v.sentence() for v in end.verdicts(band)) + ".")
    return table, verdict


def _headline_section(data: BagData | None, check: CheckResult | None) -> Section:
    section = Section("Headline: TCP error per component")
    measured = _measured_headline(data)
    if measured is not None:
        section.tables.append(measured[0])
        section.paragraphs.append("The headline is the measurement: the reference instrument "
                                  "on the compensated machine, phase by phase. " + measured[1])
    if check is None:
        if measured is None:
            section.paragraphs.append("No reference measurements: no TCP error to report.")
        return section
    plot = check.plot
    mask, band = plot["mask"], check.band
    offline = "Offline (a second figure, not a measurement of the compensated machine): " \
        if measured is not None else ""
    table = Table(["state", "model version"] + [f"RMS e_{c}" for c in COMPONENTS],
                  caption=offline + "RMS of reference minus model at the reference points, per "
                          "component, each component's mean removed (an instrument's own "
                          "zero), with its k = 2 uncertainty (sampling and instrument)")
    measured_error = plot["measured"] - np.nanmean(np.where(mask, plot["measured"], np.nan),
                                                   axis=0)
    table.add("no model: the machine's error, mean removed", "-",
              *_component_figures(np.nan_to_num(measured_error), mask, band))
    steps = check.steps
    for k, (step, residual) in enumerate(zip(steps, plot["step_residuals"])):
        label = "the model as given" if k == 0 else \
            f"after adding {', '.join(steps[k - 1].added)}"
        table.add(label, step.model_version, *_component_figures(residual, mask, band))
    section.tables.append(table)
    section.paragraphs.append(
        f"{check.readings} reference readings; the instrument's band is ± "
        f"{band * UM:.2g} µm (k = 2). " + (
            "The offline table is the model's residual (reference minus model) at the same "
            "readings: what the model explains, not what the machine did."
            if measured is not None else
            "'Reference minus model' is the error that would remain if the model's correction "
            "were applied at the reference points."))
    section.paragraphs.append(f"Offline diagnosis of the final model: {check.final_diagnosis}.")
    return section


def loop_events(data: BagData) -> list[tuple[float, str]]:
    """Where each compensation model version went live at the machine [s], and its reason."""
    reasons = {version: reason for _, _, version, reason in data.models if version is not None}
    events, seen = [], set()
    if data.references and not int(getattr(data.references[0][1],
                                           "compensation_model_version", 0)):
        events.append((float(data.seconds([data.references[0][0]])[0]),
                       "before the first compensation arrived"))
    for stamp, reading in data.references:
        version = int(getattr(reading, "compensation_model_version", 0))
        if version and version not in seen:
            seen.add(version)
            label = f"starting model's compensation (v{version})" if len(seen) == 1 else \
                f"v{version}: {reasons.get(version, 'model change')}"
            events.append((float(data.seconds([stamp])[0]), label))
    # The estimator's deterioration alarms cut the run as the demo's story does.
    for axis in sorted(data.axes):
        alarm = next((p for p in data.axes[axis].profiles if getattr(p, "deterioration", False)),
                     None)
        if alarm is not None:
            from ..io.fields import stamp_to_nanoseconds

            events.append((float(data.seconds([stamp_to_nanoseconds(alarm.header.stamp)])[0]),
                           f"after the {axis.upper()} deterioration alarm"))
    return events


def _conformance_words(state) -> str:
    """An end state's conformance to the band in words (ISO 14253-1)."""
    return {"within": "within the instrument's band, conformance shown for every component "
                      "(ISO 14253-1: RMS + U <= band).",
            "outside": "outside the instrument's band, nonconformance shown (RMS - U > band): "
                       "an effect the model lacks remains.",
            "undecided": "undecided: conformance to the instrument's band not shown for "
                         "every component, nonconformance for none (the uncertainty "
                         "straddles the band)."}[state.value]


def closed_loop_section(data: BagData, directory: Path, stem: str) -> Section:
    """The machine's error with and without the compensation the CNC applied."""
    from ..core.workbench.closed_loop import loop_phases
    from ..io.fields import machine_error

    section = Section("Closed loop: the machine's error with the compensation applied")
    times = data.seconds([s for s, _ in data.references])
    measured = np.array([(r.error.x, r.error.y, r.error.z) for _, r in data.references])
    raw = np.array([machine_error(r) for _, r in data.references])
    applied = measured - raw
    band, note = _band(data)
    if note:
        section.paragraphs.append(f"The instrument's band: {note}.")
    if not np.any(applied):
        section.paragraphs.append(
            "The machine applied no compensation during this recording (open loop): the "
            "headline's 'with compensation' rows are the model's residual at the reference "
            "points, not a measured compensated machine.")
        return section
    events = loop_events(data)
    phases = loop_phases(times, measured, applied, events, band)
    table = Table(["phase", "from-to [s]", "readings"] +
                  [f"{kind} e_{c}" for kind in ("without", "with") for c in COMPONENTS],
                  caption="RMS of the TCP error the reference instrument measured, per "
                          "component, without the compensation (measured minus what the CNC "
                          "applied) and with it, at the same readings; k = 2 uncertainties")
    for phase in phases:
        table.add(phase.label, f"{phase.start_s:.0f}-{phase.end_s:.0f}", phase.count,
                  *[format_with_uncertainty(f.rms * UM, f.rms_u_k2 * UM, "µm")
                    for f in phase.without + phase.with_compensation],
                  css_class="best" if phase.label == "end state" and phase.within(band) else "")
    section.tables.append(table)
    end = phases[-1]
    section.paragraphs.append(
        f"The CNC added the broadcast correction to its command; the reference instrument "
        f"(U = {band * UM:.2g} µm, k = 2) measured the compensated machine. End of the run "
        f"(last {end.end_s - end.start_s:.0f} s): "
        + ", ".join(f"e_{c} {f.rms * UM:.2f} µm" for c, f in zip(COMPONENTS,
                                                               end.with_compensation))
        + f": {_conformance_words(end.conformance(band))} "
        + "; ".join(v.sentence() for v in end.verdicts(band)) + ".")
    plt = pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(10, 6.4), sharex=True)
    for c, ax in enumerate(axes):
        ax.plot(times, raw[:, c] * UM, ".", color="0.6", ms=3, label="without compensation")
        ax.plot(times, measured[:, c] * UM, ".", color="tab:blue", ms=3,
                label="with compensation (measured)")
        ax.axhspan(-band * UM, band * UM, color="tab:green", alpha=0.12,
                   label="instrument band (k = 2)")
        for when, label in events:
            ax.axvline(when, color="tab:red", lw=0.8)
        ax.set_ylabel(f"e_{COMPONENTS[c]} [µm]")
    for when, label in events:
        axes[0].annotate(label, (when, 1.0), xycoords=("data", "axes fraction"), fontsize=6,
                         rotation=90, va="top", ha="right")
    axes[-1].set_xlabel(TIME_LABEL)
    _legend(axes[0])
    section.figures.append(save_figure(
        fig, directory, f"{stem}_closed_loop",
        "TCP error per component at the reference points: grey without compensation, blue "
        "as measured on the compensated machine; red lines where a model version went live at "
        "the machine; the instrument's band in green."))
    return section


def _where_section(data: BagData | None, check: CheckResult, directory: Path, stem: str
                   ) -> Section:
    plt = pyplot()
    plot = check.plot
    residual, mask = plot["residual_after"], plot["mask"]
    band = check.band * UM
    offset = (data.references[0][0] - data.start_ns) / 1e9 if data is not None and \
        data.references else 0.0
    time = plot["time"] + offset
    variables = [(f"{axis} position [mm]", values * 1e3)
                 for axis, values in plot["positions"].items() if np.ptp(values) > 0]
    rising = sorted(plot["temperatures"], key=lambda s: -np.ptp(plot["temperatures"][s]))[:2]
    variables += [(f"{s} rise [K]", plot["temperatures"][s] - plot["temperatures"][s][0])
                  for s in rising]
    variables.append((TIME_LABEL, time))
    fig, axes = plt.subplots(3, len(variables), figsize=(2.6 * len(variables) + 1.5, 7),
                             sharey="row", squeeze=False)
    for row, component in enumerate(COMPONENTS):
        for col, (label, values) in enumerate(variables):
            ax = axes[row, col]
            picked = mask[:, row]
            ax.axhspan(-band, band, color="tab:green", alpha=0.15,
                       label="instrument band (k = 2)" if row == 0 and col == len(variables) - 1
                       else None)
            ax.plot(values[picked], residual[picked, row] * UM, ".", ms=2.5, color="tab:blue",
                    label="residual" if row == 0 and col == len(variables) - 1 else None)
            if row == 2:
                ax.set_xlabel(label, fontsize=8)
            if col == 0:
                ax.set_ylabel(f"e_{component} residual [µm]", fontsize=8)
            ax.tick_params(labelsize=7)
    _legend(axes[0, -1])
    figure = save_figure(fig, directory, f"{stem}_where",
                         "Residual (reference - final model) per component against each axis "
                         "position, the temperatures that changed most, and time; green: the "
                         "instrument's band.")
    section = Section("Where the model fails", figures=[figure])
    outside = [float(np.mean(np.abs(residual[mask[:, c], c] * UM) > band))
               for c in range(3) if mask[:, c].any()]
    section.paragraphs.append(
        f"With the final model, {100 * max(outside, default=0):.0f} % of the readings of the "
        "worst component lie outside the instrument's band.")
    return section


def localisation_section(check: CheckResult, directory: Path, stem: str) -> Section:
    """Where the residual lives: variance shares per variable, the periodic peak, the verdict."""
    plt = pyplot()
    where = check.localisation or {}
    section = Section("Where the residual lives")
    # Per component the variables that differ; temperatures that explain alike are one bar.
    shares = where.get("chart") or [{"label": s["variable"], "component": s["component"],
                                     "share": s["share"]}
                                    for s in where.get("shares", []) if s["share"] > 0][:12]
    if shares:
        fig, ax = plt.subplots(figsize=(7.5, 0.32 * len(shares) + 1.2))
        labels = [f"{s['label']}  (e_{s['component']})" for s in shares][::-1]
        values = [100 * s["share"] for s in shares][::-1]
        ax.barh(labels, values, color="tab:blue")
        ax.set_xlabel("share of the component's residual variance explained, cross-validated [%]")
        ax.set_xlim(0, 100)
        ax.tick_params(labelsize=7)
        section.figures.append(save_figure(
            fig, directory, f"{stem}_localisation",
            "Each variable alone, smoothed by k-nearest neighbours with k chosen by 5-fold "
            "cross-validation: how much of each component's residual it explains (a variable "
            "that only fits noise scores about 0)."))
    peaks = Table(["along", "component", "period [mm]", "amplitude [µm]", "share"],
                  caption="Strongest periodic residual along each axis (2-50 mm periods)")
    for peak in where.get("peaks", [])[:6]:
        peaks.add(peak["axis"], f"e_{peak['component']}", peak["period_m"] * 1e3,
                  peak["amplitude_m"] * UM, f"{100 * peak['share']:.0f} %")
    if where.get("peaks"):
        section.tables.append(peaks)
    section.paragraphs.append(
        "Where it lives: "
        f"{where.get('sentence') or 'nowhere in particular (no variable explains a tenth of it)'}.")
    named = check.named
    if named:
        table = Table(["effect named", "setting", "confidence", "share of the excess removed",
                       "parameters (± U, k = 2)", "physical reading"])
        for entry in named:
            table.add(entry["name"], entry.get("setting_display") or ", ".join(
                f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}"
                for k, v in entry["setting"].items()),
                      f"{100 * entry['confidence']:.0f} %",
                      f"{100 * entry['share_of_excess']:.0f} %",
                      readings_text(entry),
                      entry["explanation"], css_class="accepted")
        section.tables.append(table)
    verdict = check.verdict
    section.paragraphs.append(f"Verdict: {verdict}." if verdict else
                              "Verdict: what the named effects leave is within the "
                              "instrument's noise." if named else
                              "Verdict: the residual is within the instrument's noise.")
    return section


def survey_report_sections(check: CheckResult, directory: Path, stem: str) -> list[Section]:
    """A reference survey read from a data logger's CSV (no bag): the same workbench story."""
    source = Section("Machine, data and instruments", paragraphs=[
        f"Data: {check.data} ({check.source.rows_note or ''}); machine "
        f"{check.machine}; instrument band ± {check.band * UM:.2g} µm (k = 2)."])
    headline = _headline_section(None, check)
    return [source, headline, _where_section(None, check, directory, stem),
            localisation_section(check, directory, stem), _evidence_section(check),
            _versions_section(check)]


def _evidence_section(check: CheckResult) -> Section:
    section = Section("The effect found and its evidence")
    baseline = check.baseline_cv_rmse
    section.paragraphs.append(
        f"Every effect of the catalogue (geometric, rotary, thermal, motion, cross-axis and the "
        f"user's own) is fitted to the residual of the starting model and judged by "
        f"time-blocked 5-fold cross-validation, its period, order or time constant chosen "
        f"inside each fold; without any candidate the cross-validated error is "
        f"{baseline * UM:.3g} µm. The best is accepted when, on readings its fit did not see, "
        "it removes error in block after block (a t-test on the components it moves, its "
        "p-value adjusted for every candidate tried by Westfall-Young max-T), cuts the error "
        "by the minimum reduction, removes at least a "
        "quarter of what stands above the instrument's noise, and carries a parameter above 3 "
        "standard errors; then the search repeats with it in the model. "
        "Confidence = 1 - that adjusted p-value.")
    table = Table(["candidate", "status", "CV error after [µm]", "reduction", "confidence",
                   "parameters (± U, k = 2)", "physical reading"])
    for entry in check.ranking[:12]:
        accepted = entry["significant"]
        parameters = readings_text(entry)
        refusal = entry.get("refusal", "")
        status = "accepted" if accepted else ("refused by physics" if refusal else "rejected")
        table.add(entry.get("name", entry["effect"]), status, entry["cv_rmse_after"] * UM,
                  f"{100 * entry['error_reduction']:.1f} %",
                  # A rejected candidate has no confidence: it did not pass the test.
                  f"{100 * entry.get('confidence', 0.0):.0f} %" if accepted else "—",
                  parameters,
                  entry["explanation"] if accepted else
                  f"({status}{': ' + refusal if refusal else ''}) {entry['explanation']}",
                  css_class="accepted" if accepted else "rejected")
    section.tables.append(table)
    added = [s for s in check.steps if s.added is not None]
    for step in added:
        for effect in step.added:
            uncertainties = (step.parameter_uncertainties or {}).get(effect, {})
            family, _, variant = effect.partition(":")
            shown = display_parameters(family, variant, step.parameters[effect],
                                       uncertainties)
            section.paragraphs.append(
                f"Added {effect}: " + ", ".join(f"{name} = {text}" for name, text in
                                                shown.items()) + " (U, k = 2).")
    if not added:
        section.paragraphs.append("No effect was added.")
    return section


def _recorded_versions_section(data: BagData) -> Section:
    """The model versions as the graph published them (the bag's ``model`` topic): the
    same versions, reasons and coefficients as the saved model.yaml."""
    table = Table(["model version", "reason", "effects and fitted coefficients"],
                  caption="Every model version recorded on 'model', in order; coefficients in "
                          "SI units exactly as in the version's YAML")
    for _, text, version, reason in data.models:
        try:
            model = yaml.safe_load(text) or {}
        except yaml.YAMLError:
            model = {}
        parts = []
        for name, entry in (model.get("effects") or {}).items():
            values = (entry or {}).get("coefficients") or (entry or {}).get("values") \
                if isinstance(entry, dict) else None
            parts.append(name + (" (" + ", ".join(f"{k} = {v:.4g}" for k, v in values.items())
                                 + ")" if values else ""))
        table.add(version if version is not None else "?", reason or "-", "; ".join(parts))
    return Section("Model versions", tables=[table])


def _versions_section(check: CheckResult) -> Section:
    table = Table(["model version", "effects", "residual RMS [µm]", "diagnosis"])
    for step in check.steps:
        table.add(step.model_version, ", ".join(step.effects), step.rmse * UM, step.diagnosis)
    return Section("Model versions", tables=[table])


def _axes_section(data: BagData, directory: Path, stem: str) -> Section:
    section = Section("Axes: dual-scale yaw, systematic profile, deterioration")
    if not data.axes:
        section.paragraphs.append("No yaw or systematic-profile topics in this data.")
        return section
    plt = pyplot()
    names = sorted(data.axes)
    fig, axes = plt.subplots(len(names), 2, figsize=(11, 3.2 * len(names)), squeeze=False)
    table = Table(["axis", "error", "chosen k", "CV RMSE [µrad]", "random σ (median) [µrad]",
                   "samples", "max |change| vs baseline [µrad]", "tolerance [µrad]", "alarm"])
    for row, name in enumerate(names):
        axis = data.axes[name]
        left, right = axes[row, 0], axes[row, 1]
        if axis.yaw_rad.size:
            left.plot(data.seconds(axis.yaw_time_ns), axis.yaw_rad * UM, ",", color="0.4")
            right.plot(axis.yaw_position_m * 1e3, axis.yaw_rad * UM, ",", color="0.6",
                       label="yaw samples")
        left.set(xlabel=TIME_LABEL, ylabel=f"yaw of {name.upper()} [µrad]")
        if axis.profiles:
            last = axis.profiles[-1]
            x = np.asarray(last.positions) * 1e3
            systematic = np.asarray(last.systematic) * UM
            sigma = np.asarray(last.random_sigma) * UM
            right.fill_between(x, systematic - 2 * sigma, systematic + 2 * sigma, color="tab:blue",
                               alpha=0.2, label="± 2 random σ")
            right.plot(x, systematic, color="tab:blue", label=f"kNN systematic (k = {last.k})")
            difference = np.asarray(last.baseline_difference) * UM
            if difference.size == systematic.size:
                right.plot(x, systematic - difference, "--", color="tab:orange",
                           label="baseline profile")
            alarm = next((p for p in axis.profiles if p.deterioration), None)
            change = float(np.max(np.abs(difference))) if difference.size else float("nan")
            table.add(name, last.error_name, int(last.k), last.cv_rmse * UM,
                      float(np.median(sigma)) if sigma.size else float("nan"),
                      int(last.sample_count), change, last.tolerance * UM,
                      "yes" if alarm is not None else "no",
                      css_class="rejected" if alarm is None else "")
        right.set(xlabel=f"{name.upper()} position [mm]", ylabel="yaw [µrad]")
        _legend(right)
    figure = save_figure(fig, directory, f"{stem}_axes",
                         "Per axis: the yaw E = (x2 - x1)/D of its scale pair over time (left); "
                         "the kNN systematic profile with ± 2 random σ and the stored baseline "
                         "against position (right).")
    section.figures.append(figure)
    section.tables.append(table)
    section.paragraphs.append(
        "The deterioration alarm compares the latest systematic profile with the baseline "
        "(Kidani eq. 2.1): an alarm when |change| reaches the tolerance anywhere on the stroke.")
    return section


def _temperature_section(data: BagData, directory: Path, stem: str) -> Section:
    section = Section("Temperatures")
    if not data.temperatures:
        section.paragraphs.append("No temperatures in this data.")
        return section
    plt = pyplot()
    names = data.temperatures[-1][1]
    stamps = np.array([t[0] for t in data.temperatures])
    values = np.array([[t[2][j] if j < len(t[2]) else np.nan for j in range(len(names))]
                       for t in data.temperatures])
    order = np.argsort(-np.nanmax(values, axis=0) + np.nanmin(values, axis=0))
    shown = [j for j in order if not names[j].startswith(("x1_", "x2_", "y1_", "y2_", "z1_",
                                                          "z2_"))][:8] or list(order[:8])
    fig, ax = plt.subplots(figsize=(10, 3.6))
    for j in shown:
        ax.plot(data.seconds(stamps), values[:, j], lw=1, label=names[j])
    ax.set(xlabel=TIME_LABEL, ylabel="temperature [°C]")
    _legend(ax)
    section.figures.append(save_figure(fig, directory, f"{stem}_temperatures",
                                       "Temperatures over the run (the structure's sensors that "
                                       "changed most; scale thermocouples left out)."))
    table = Table(["sensor", "start [°C]", "end [°C]", "min [°C]", "max [°C]"])
    for j in shown:
        column = values[:, j]
        finite = column[np.isfinite(column)]
        if finite.size:
            table.add(names[j], finite[0], finite[-1], finite.min(), finite.max())
    section.tables.append(table)
    return section


def _iso_section(data: BagData, directory: Path, stem: str) -> Section:
    section = Section("ISO 230-2 positioning")
    found = []
    if data.references:
        axes = [a.upper() for a in data.references[0][1].command_axes]
        for j, axis in enumerate(axes):
            if axis not in "XYZ" or any(len(r.command_positions) != len(axes)
                                        for _, r in data.references):
                continue
            component = "XYZ".index(axis)
            positions = np.array([r.command_positions[j] for _, r in data.references])
            deviations = np.array([(r.error.x, r.error.y, r.error.z)[component]
                                   for _, r in data.references])
            directions = np.array([r.command_directions[j] if len(r.command_directions) ==
                                   len(axes) else 0 for _, r in data.references], dtype=float)
            runs = positioning_runs(positions, deviations, directions)
            if runs is not None:
                found.append((axis, iso230_2(*runs)))
    if not found:
        section.paragraphs.append(
            "This data has no positioning runs (repeated approaches to the same targets from "
            "both directions, ISO 230-2), so no A, E, R, B, M figures are given.")
        return section
    return iso230_2_section(found, directory, stem)


#: ISO 230-2 figures in the order the standard lists them: (attribute, symbol).
ISO_FIGURES = (("accuracy", "A"), ("accuracy_up", "A↑"), ("accuracy_down", "A↓"),
               ("systematic_deviation", "E"), ("systematic_deviation_up", "E↑"),
               ("systematic_deviation_down", "E↓"), ("mean_deviation_range", "M"),
               ("repeatability", "R"), ("repeatability_up_axis", "R↑"),
               ("repeatability_down_axis", "R↓"), ("reversal_value", "B"),
               ("mean_reversal", "B̄"))


def iso230_2_section(found: list, directory: Path, stem: str, notes: list[str] = ()
                     ) -> Section:
    """The ISO 230-2 section for ``found`` [(axis, Iso2302Result in metres)]: the axis
    figures, a per-target table and the standard's plot (mean deviation +- 2s per
    direction against target) - the same for ``mt-accuracy iso230-2`` and a bag's report."""
    plt = pyplot()
    section = Section("ISO 230-2 positioning")
    table = Table(["axis"] + [symbol for _, symbol in ISO_FIGURES],
                  caption="ISO 230-2 figures [µm]")
    for axis, result in found:
        table.add(axis, *(getattr(result, name) * UM for name, _ in ISO_FIGURES))
    section.tables.append(table)
    fig, axes = plt.subplots(len(found), 1, figsize=(9, 3.6 * len(found)), squeeze=False)
    for (axis, result), ax in zip(found, axes[:, 0]):
        targets_mm = result.targets * 1e3
        per_target = Table(["target [mm]", "x̄↑ [µm]", "x̄↓ [µm]", "x̄ [µm]", "s↑ [µm]",
                            "s↓ [µm]", "B_i [µm]", "R_i [µm]"],
                           caption=f"Axis {axis}: per target position")
        for i, target in enumerate(targets_mm):
            per_target.add(target, result.mean_up[i] * UM, result.mean_down[i] * UM,
                           result.mean_bidirectional[i] * UM, result.s_up[i] * UM,
                           result.s_down[i] * UM, result.reversal[i] * UM,
                           result.repeatability_bidirectional[i] * UM)
        section.tables.append(per_target)
        for mean, s, colour, label in ((result.mean_up, result.s_up, "tab:red", "↑"),
                                       (result.mean_down, result.s_down, "tab:blue", "↓")):
            ax.plot(targets_mm, mean * UM, "-o", ms=3, color=colour, label=f"x̄{label}")
            ax.plot(targets_mm, (mean + 2 * s) * UM, "--", lw=0.8, color=colour,
                    label=f"x̄{label} ± 2s{label}")
            ax.plot(targets_mm, (mean - 2 * s) * UM, "--", lw=0.8, color=colour)
        ax.axhline(0, color="0.6", lw=0.6)
        ax.set(xlabel=f"{axis} target position [mm]", ylabel="positional deviation [µm]",
               title=f"Axis {axis}: A = {result.accuracy * UM:.2f} µm, "
                     f"R = {result.repeatability * UM:.2f} µm, "
                     f"B = {result.reversal_value * UM:.2f} µm")
        _legend(ax)
    section.figures.append(save_figure(
        fig, directory, f"{stem}_iso230_2",
        "Mean positional deviation per direction of approach with its ± 2s band against the "
        "target position (the ISO 230-2 plot)."))
    section.paragraphs.append(
        "A accuracy, E systematic deviation, M mean deviation range, R repeatability, B "
        "reversal value, B̄ mean reversal value; ↑ / ↓ the approaches from below / above.")
    section.paragraphs.extend(notes)
    return section


def _table_section(data: BagData, directory: Path, stem: str) -> Section:
    section = Section("Compensation table")
    if not data.tables:
        section.paragraphs.append("No compensation table in this data.")
        return section
    plt = pyplot()
    fig, axes = plt.subplots(1, len(data.tables), figsize=(4.2 * len(data.tables) + 1.5, 3.4),
                             squeeze=False)
    for col, (axis, message) in enumerate(sorted(data.tables.items())):
        values = np.asarray(message.values).reshape(-1, len(message.columns))
        ax = axes[0, col]
        for j, column in enumerate(message.columns[1:], start=1):
            scale, unit = (UM, "µm") if column.endswith("_m") else (UM, "µrad")
            ax.plot(values[:, 0] * 1e3, values[:, j] * scale,
                    label=f"{column.rsplit('_', 1)[0]} [{unit}]")
        ax.set(xlabel=f"{axis.upper()} position [mm]", ylabel="error [µm, µrad]",
               title=f"axis {axis.upper()} (model v{message.model_version})")
    _legend(axes[0, -1])
    section.figures.append(save_figure(fig, directory, f"{stem}_table",
                                       "The latest compensation table per axis (ISO 230-1 "
                                       "component errors, as a CNC's tables take them)."))
    for axis, message in sorted(data.tables.items()):
        values = np.asarray(message.values).reshape(-1, len(message.columns))
        step = max(1, values.shape[0] // 10)
        headers = [message.columns[0].replace("_m", " [mm]")] + [
            c.replace("_m", " [µm]").replace("_rad", " [µrad]") for c in message.columns[1:]]
        table = Table(headers, caption=f"axis {axis.upper()}, every {step}. row")
        for row in values[::step]:
            table.add(*(float(v * (1e3 if j == 0 else UM)) for j, v in enumerate(row)))
        section.tables.append(table)
    if data.tables:
        first = next(iter(data.tables.values()))
        if len(first.squareness_names):
            # Location errors: angles (squareness, a line's tilt) and a rotary line's
            # offsets (EX0C ...: a length), told apart by the name's second letter.
            section.paragraphs.append("Location errors: " + ", ".join(
                f"{n} = {v * UM:.3g} {'µrad' if n[1] in 'ABC' else 'µm'}"
                for n, v in zip(first.squareness_names, first.squareness)) + ".")
    section.paragraphs.append("Positions in mm, linear errors in µm, angular errors in µrad.")
    return section


# ----------------------------------------------------------------------- thermal logs
def csv_report_sections(check: CheckResult, directory: Path, stem: str) -> list[Section]:
    """A thermal log on the survey engine: the same sections as a survey's, the headline
    judged on the rows after training (in the target column's unit)."""
    log, plot = check.log, check.plot
    scale, unit = plot["unit_scale"], plot["unit"]
    source = Section("Data", paragraphs=[
        f"Data: {check.data} - {check.source.rows_note or ''}.",
        f"Target: {log.target} (e_{log.component}); the selection saw the first "
        f"{log.train_rows} rows ({check.validation}); every model version is judged "
        f"on the {log.rows - log.train_rows} rows after them. Noise band ± "
        f"{check.band * scale:.3g} {unit} (k = 2)."])
    sections = [source, _log_headline(check, directory, stem),
                localisation_section(check, directory, stem), _evidence_section(check),
                _log_versions_section(check)]
    if log.walk_forward is not None:
        from .walk import walk_forward_section

        sections.append(walk_forward_section(log.walk_forward, unit, scale, directory, stem))
    if check.runs:
        runs = Table(["run", "part", "rows", f"constant [{unit}]",
                      f"least squares, every input [{unit}]", f"model [{unit}]"],
                     caption="RMS error of each run; the held-out runs judge, unseen.")
        for run in check.runs:
            runs.add(run.run, run.part, run.rows, run.constant_rmse * scale,
                     run.least_squares_rmse * scale, run.model_rmse * scale)
        sections.append(Section("Runs", tables=[runs], paragraphs=[
            f"{len(check.runs)} runs; "
            + ("each zeroed at its start (its own zero); " if log.zeroed_runs else
               "absolute readings across runs; ")
            + "every lag restarts at its run's first reading, and time is counted from each "
              "run's start."]))
    return sections


def _log_fit_figure(check: CheckResult, directory: Path, stem: str) -> Figure:
    """Measured against the model before and after, and the residual, over the log."""
    plt = pyplot()
    plot = check.plot
    scale, unit = plot["unit_scale"], plot["unit"]
    hours = (plot["time"] - plot["time"][0]) / 3600
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    top.plot(hours, plot["target"] * scale, "k-", lw=0.8, label="measured")
    top.plot(hours, plot["before"] * scale, "b-", lw=0.8, label="model before")
    top.plot(hours, plot["after"] * scale, "r-", lw=0.8, label="model after")
    split = hours[np.argmin(plot["train"])] if not plot["train"].all() else hours[-1]
    for ax in (top, bottom):
        ax.axvline(split, color="0.5", ls="--", label="end of training" if ax is top else None)
        for k, start in enumerate(plot.get("run_starts") if plot.get("run_starts") is not None
                                  else []):
            if k:
                ax.axvline(hours[start], color="0.8", lw=0.6,
                           label="run boundary" if ax is top and k == 1 else None)
    bottom.plot(hours, (plot["target"] - plot["before"]) * scale, "b-", lw=0.8,
                label="residual before")
    bottom.plot(hours, (plot["target"] - plot["after"]) * scale, "r-", lw=0.8,
                label="residual after")
    top.set(ylabel=f"{check.log.target} [{unit}]")
    bottom.set(xlabel="time since start [h]" if plot.get("run_starts") is None else
               "time, runs laid end to end [h]", ylabel=f"residual [{unit}]")
    _legend(top)
    _legend(bottom)
    return save_figure(fig, directory, f"{stem}_fit",
                       "Measured against the model before and after (top) and the residual "
                       "(bottom); the selection saw the rows left of the dashed line, the "
                       "rows right of it judge.")


def _log_headline(check: CheckResult, directory: Path, stem: str) -> Section:
    """The held-out figures of a thermal log's model, its baselines and its warnings."""
    log = check.log
    scale, unit = check.plot["unit_scale"], check.plot["unit"]
    headline = Section("Headline", figures=[_log_fit_figure(check, directory, stem)],
                       paragraphs=[
        f"Held-out RMSE {log.held_out_baseline_rmse * scale:.4g} {unit} before, "
        f"{check.final_rmse * scale:.4g} {unit} after adding "
        f"{', '.join(check.added) or 'nothing'} ({log.judged_on}). A constant "
        f"leaves {log.constant_held_out_rmse * scale:.4g} {unit}; least squares on "
        f"every input {log.all_inputs_least_squares_held_out_rmse * scale:.4g} {unit}."])
    baselines = Table(["on the held-out rows", f"RMSE [{unit}]"],
                      caption="The same rows, unseen by every decision.")
    for name, value in log.baselines_held_out_m.items():
        baselines.add(name, value * scale)
    headline.tables.append(baselines)
    headline.paragraphs += [as_paragraph(line) for line in check.warnings or []]
    if weights_sentence(log):
        headline.paragraphs.append(as_paragraph(weights_sentence(log)
                                                + " (share of its spread)"))
    return headline


def _log_versions_section(check: CheckResult) -> Section:
    """A thermal log's model versions, the large gains refused and the whole models'
    contest."""
    log = check.log
    scale, unit = check.plot["unit_scale"], check.plot["unit"]
    versions = Table(["model version", "effects", f"held-out RMSE [{unit}]",
                      f"CV RMSE, training rows [{unit}]", "added"])
    for step in check.steps:
        versions.add(step.model_version, ", ".join(step.effects) or "-",
                     step.held_out_rmse * scale, step.cv_rmse * scale,
                     ", ".join(step.added or []))
    refused = Table(["candidate", "CV gain", "refused by"],
                    caption="Candidates with a large CV gain that were not added, and why.")
    for entry in log.not_added:
        test = entry.test
        if entry.before is not None:
            test += f": {entry.before * scale:.4g} -> {entry.after * scale:.4g} {unit}"
        refused.add(entry.name, f"{100 * entry.cv_reduction:.0f} %", test)
    contest = Table(["whole model", f"forward, training blocks [{unit}]",
                     f"each block [{unit}] (rows fitted)",
                     f"each training regime from the others [{unit}]",
                     "inputs beyond their fitted range", f"held out [{unit}]", "chosen"],
                    caption="Whole models contested by forward validation over the training "
                            "blocks and by each regime of the training rows predicted from "
                            "the others (the worse of the two decides; within 10 % of the "
                            "best, the model whose inputs left their range least); the "
                            "held-out column is computed after the decision and decided "
                            "nothing.")
    for entry in log.model_contest:
        contest.add(entry.name, entry.forward_rmse * scale,
                    ", ".join(f"{b['rmse'] * scale:.3g} ({b['trained_rows']})"
                              for b in entry.forward_blocks),
                    ", ".join(f"{b['regime']} {b['rmse'] * scale:.3g}"
                              for b in entry.cross_regime_blocks) or "one regime",
                    f"{entry.range_excess:.2g} of the span",
                    entry.held_out_rmse * scale, "yes" if entry.chosen else "")
    return Section("Model versions", tables=[versions] + ([refused] if refused.rows else []) +
                   ([contest] if len(contest.rows) > 1 else []))
