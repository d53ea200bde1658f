"""Report sections of rotary-axis work: ball bar, probing, CNC table export."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import Section, Table, pyplot, save_figure

ARCSEC = np.pi / (180.0 * 3600.0)


def ballbar_sections(calibration, directory: Path, stem: str) -> list[Section]:
    """Zhu's Fig. 5.12 (data, polar), Tables 5.2/5.3 and Fig. 5.13 (residuals, polar)."""
    plt = pyplot()
    angles = calibration.angles_rad
    closed = np.append(angles, angles[:1]) if not np.isclose(
        abs(angles[-1] - angles[0]), 2 * np.pi) else angles
    data = Section("Ball bar: the readings (Zhu Fig. 5.12)", [
        f"{angles.size} table positions per run; bars "
        f"{calibration.short.setup.bar_length_m * 1e3:.3f}"
        f" and {calibration.long.setup.bar_length_m * 1e3:.3f} mm, table ball at R_x = "
        f"{calibration.short.setup.radius_m * 1e3:.3f} mm (bar angles "
        f"{np.degrees(calibration.short.setup.bar_angle_rad):.2f} and "
        f"{np.degrees(calibration.long.setup.bar_angle_rad):.2f} deg to the table axis). "
        "The polar plots show the bar's length change around a reference circle: an offset "
        "circle is the setup's eccentricity, which the two-setup method cancels (Zhu eq. 5.16)."])
    fig, axes = plt.subplots(1, 2, subplot_kw={"projection": "polar"}, figsize=(9, 4.2))
    for ax, run in zip(axes, (calibration.short, calibration.long)):
        readings_um = run.readings_m * 1e6
        base = max(5.0, 1.5 * float(np.max(np.abs(readings_um))))
        ax.plot(closed, np.full(closed.size, base), "r:", label="nominal length")
        for i, row in enumerate(readings_um):
            ax.plot(angles, base + row, "-", lw=1, label="measured" if i == 0 else None)
        ax.set_title(f"{run.name}\n(radius: {base:.0f} um + length change)", fontsize=9)
        ax.set_yticklabels([])
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.0, 1.15), fontsize=8)
    data.figures.append(save_figure(fig, directory, f"{stem}_ballbar_data",
                                    "Length change of each bar at each table angle, every "
                                    "repetition (polar; Zhu Fig. 5.12)."))
    table = Table(["method", "E_x [arcsec]", "E_y [arcsec]", "D_z [um]", "max |e| [mm^2]",
                   "range e [mm^2]", "RMS e [mm^2]"],
                  caption="Tables 5.2 and 5.3: the estimates and their residuals e_i "
                          "(Zhu eq. 5.16, in mm^2 as Zhu gives them). l-infinity minimises the "
                          "largest residual, l2 the RMS.")
    for fit in (calibration.l2, calibration.linf):
        p = fit.parameters
        table.add("l2 (least squares)" if fit.method == "l2" else "l-infinity (minimax)",
                  p[0] / ARCSEC, p[1] / ARCSEC, p[2] * 1e6, fit.max_abs * 1e6, fit.range * 1e6,
                  fit.rms * 1e6)
    u = calibration.l2.uncertainties
    estimates = Section("Ball bar: the table's tilt and axial errors (Zhu Tables 5.2, 5.3)", [
        f"Least squares: E_x {calibration.l2.parameters[0] / ARCSEC:.2f} +- {2 * u[0] / ARCSEC:.2f}"
        f" arcsec, E_y {calibration.l2.parameters[1] / ARCSEC:.2f}"
        f" +- {2 * u[1] / ARCSEC:.2f} arcsec,"
        f" D_z {calibration.l2.parameters[2] * 1e6:.2f} +- {2 * u[2] * 1e6:.2f} um (k = 2, from "
        f"the residuals). cond(J) = {calibration.condition_number:.1f} (Zhu eq. 5.20). "
        "D_x, D_y cancel with the eccentricity they are coupled to, and E_z is not seen by a "
        "ball bar; their combination per setup is listed below.",
        "Repeatability of the readings (pooled standard deviation of the repetitions): "
        + ", ".join(f"{r.name} {r.repeatability_m * 1e6:.3f} um"
                    for r in (calibration.short, calibration.long)) + "."],
        tables=[table])
    lumped = Table(["run", "D_x - H_x [um]", "D_y - H_y [um]"],
                   caption="Radial error less the eccentricity, per setup (Zhu eq. 5.13).")
    for fit in calibration.single_setups:
        lumped.add(fit.run, fit.radial_less_eccentricity_m[0] * 1e6,
                   fit.radial_less_eccentricity_m[1] * 1e6)
    estimates.tables.append(lumped)
    fig, axes = plt.subplots(1, 2, subplot_kw={"projection": "polar"}, figsize=(9, 4.2))
    for ax, fit in zip(axes, (calibration.l2, calibration.linf)):
        scale = max(float(np.max(np.abs(fit.residuals))) * 1e6 * 2, 1e-6)
        ax.plot(closed, np.full(closed.size, scale), "k:", lw=0.8, label="zero")
        ax.plot(angles, scale + fit.residuals * 1e6, "b.-", lw=1, label="residual")
        ax.set_title(f"{'l2' if fit.method == 'l2' else 'l-infinity'} residuals\n"
                     f"(radius: {scale:.3g} mm^2 + e_i)", fontsize=9)
        ax.set_yticklabels([])
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.0, 1.15), fontsize=8)
    residual = Section("Ball bar: what the estimates leave (Zhu Fig. 5.13)", [
        "Residuals of Zhu eq. 5.16 with each estimate. A jump between 0 and 360 deg - the same "
        "table angle, reached from opposite directions - is the rotary axis's lost motion "
        "(backlash)."])
    residual.figures.append(save_figure(fig, directory, f"{stem}_ballbar_residuals",
                                        "Residuals of the two-setup equation (polar)."))
    jumps = Table(["residual of", "0/360 deg jump [mm^2]", "noise [mm^2]", "backlash?"])
    for jump in calibration.reversal:
        jumps.add(jump.run, jump.jump * 1e6, jump.noise * 1e6, bool(jump.significant))
    residual.tables.append(jumps)
    return [data, estimates, residual]


def probing_section(result) -> Section:
    table = Table(["error", "value", "U (k = 2)", "unit"],
                  caption="Location errors of the rotary axes (Khan & Chen notation).")
    for name, value in result.parameters.items():
        linear = name[1] in "XYZ"
        factor = 1e6
        table.add(name, value * factor, 2 * result.uncertainties[name] * factor,
                  "um" if linear else "urad")
    section = Section("Probing: where the rotary axes really are", [
        f"{result.measured_m.shape[0]} probing cycles. The sphere's centre wandered by up to "
        f"{result.dispersion_before_m * 1e6:.1f} um as the axes turned; with the identified "
        f"errors it is modelled to within {result.dispersion_after_m * 1e6:.2f} um (RMS "
        f"{result.rms_after_m * 1e6:.2f} um)."
        + (f" Repeatability of repeated cycles: {result.repeatability_m * 1e6:.2f} um."
           if result.repeatability_m else ""),
        "The sphere sat " + ", ".join(f"{v * 1e6:+.1f}" for v in result.sphere_offset_m)
        + " um from its nominal place (separated out)."
        + (f" Not observable with one sphere, left at zero: {', '.join(result.not_observable)}."
           if result.not_observable else "")], tables=[table])
    return section


def export_section(round_trip, files: list[str]) -> Section:
    table = Table(["column", "max |table - model|", "bound h^2/8 max|f''|"],
                  caption="Each column read back and interpolated as the CNC does, against "
                          "the model (m or rad).")
    for name, error in round_trip.column_max_error.items():
        table.add(name, error, round_trip.column_bound[name])
    return Section("CNC compensation tables", [
        f"Written: {', '.join(files)}; spacing {round_trip.spacing_m * 1e3:g} mm.",
        f"Read back and applied through the kinematic chain at random positions, the tables "
        f"differ from the model by at most {round_trip.tcp_max_error_m * 1e6:.3f} um at the "
        f"TCP (RMS {round_trip.tcp_rms_error_m * 1e6:.3f} um; the model's own geometric error "
        f"is {round_trip.tcp_model_rms_m * 1e6:.2f} um RMS); the interpolation bound is "
        f"{round_trip.tcp_bound_m * 1e6:.3f} um."], tables=[table])
