"""The named, individually switchable error effects of the virtual machine tool.

Each effect is one physical cause with its equation and seed reference; the
workbench diagnoses exactly this list. An effect acts on the **scale readings**
(what the dual-scale system sees), on the **TCP** (what a reference instrument
sees), or on both - that difference is what makes an effect diagnosable.

Symbols: q = actual axis position [m], v = axis velocity [m/s], D = scale
distance [m], C = scale expansion coefficient [1/K], h(t) = first-order
thermal response (see :mod:`.thermal_state`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class EffectSpec:
    """What an effect is, what it acts on, and its parameters (default, unit)."""

    name: str
    summary: str
    equation: str
    reference: str
    acts_on: str  # "scales", "tcp" or "both"
    parameters: dict[str, tuple[object, str]] = field(default_factory=dict)


EFFECTS: dict[str, EffectSpec] = {spec.name: spec for spec in [
    EffectSpec(
        "geometric", "Six motion errors per linear axis (smooth, not polynomial) and the "
        "yaw the scale pair sees.",
        "E_j(q) = sum_k a_k sin(2 pi q / lambda_k + phi_k)", "Kidani eq. 2.6-2.12",
        "both", {"linear_m": (4e-6, "m, amplitude of positioning/straightness"),
                 "angular_rad": (5e-6, "rad, amplitude of pitch/yaw/roll")}),
    EffectSpec(
        "scale_thermal_expansion", "Uneven warming of the two scales of a pair: each "
        "reads short by its own expansion, so the pair reports a false yaw.",
        "x_i,read = x - C int_0^x dT_i(s) ds;  dE = -(dL_2 - dL_1) / D",
        "Kidani eq. 3.17, section 3.3.3", "scales",
        {"rise_scale_1_k": (2.0, "K, steady rise of scale 1 under continuous motion"),
         "rise_scale_2_k": (0.9, "K, steady rise of scale 2"),
         "time_constant_s": (4.0 * 3600, "s"),
         "expansion_per_k": (12e-6, "1/K, C of the SQ57 (Table 3.2)")}),
    EffectSpec(
        "structural_thermal_drift", "Column and spindle-head growth with the structure's "
        "temperature: a TCP offset independent of position.",
        "e(t) = beta * dT_column(t)", "Zhu eq. 3.12", "tcp",
        {"beta_m_per_k": ([1.0e-6, 4.0e-6, 2.0e-6], "m/K in (x, y, z)"),
         "rise_k": (3.0, "K, steady column rise under full motion + spindle"),
         "time_constant_s": (1.5 * 3600, "s")}),
    EffectSpec(
        "position_dependent_thermal", "Expansion of the structure carrying an axis "
        "relative to its scale: positioning error growing with position and temperature.",
        "e_a(q, t) = alpha (q - q_ref) dT_bed(t)", "Zhu eq. 3.13 (P(x) = x)", "tcp",
        {"axis": ("X", "axis"), "alpha_per_k": (11e-6, "1/K"), "rise_k": (2.5, "K"),
         "time_constant_s": (2.0 * 3600, "s"), "reference_m": (0.0, "m")}),
    EffectSpec(
        "timing_skew", "Head 2 of every pair sampled later than head 1: a false yaw "
        "proportional to velocity.", "dE = v dt / D", "Kidani eq. 2.20", "scales",
        {"skew_s": (2e-6, "s")}),
    EffectSpec(
        "scale_parallelism", "Scale 2 mounted at an angle delta to scale 1: it reads the "
        "travel divided by cos(delta).", "x_2,read = x / cos(delta);  dE = (L/cos(delta) - L)/D",
        "Kidani eq. 3.5", "scales", {"delta_rad": (0.61e-3, "rad")}),
    EffectSpec(
        "guideway_deterioration", "A distorted guideway: the yaw changes over part of the "
        "stroke after an event, ~22 um at the TCP.", "dE(q) = (de_max / d) b(q);  de = dE d",
        "Kidani eqs. 3.11-3.16, section 3.3.2", "both",
        {"axis": ("Y", "axis"), "start_m": (-0.16, "m"), "end_m": (0.0, "m"),
         "tcp_change_m": (22e-6, "m, peak TCP change"),
         "lever_m": (0.0, "m, tool offset d; 0 = the machine model's lever for this yaw")}),
    EffectSpec(
        "abbe_offset", "A tool/workpiece offset from the scales' line: every angular error "
        "acts through the extra lever arm at the TCP.", "de = eps x dt", "Kidani eq. 2.10; "
        "ISO 230-1 (Abbe principle)", "tcp", {"offset_m": ([0.1, 0.0, 0.05], "m")}),
    EffectSpec(
        "squareness", "Out-of-squareness of two axes: an error proportional to the other "
        "axis' position.", "e_x = -S_xy y (location error EC0Y)", "Kidani eq. 2.12; ISO 230-1",
        "tcp", {"errors_rad": ({"EC0Y": 20e-6, "EB0Z": -15e-6, "EA0Z": 10e-6}, "rad")}),
    EffectSpec(
        "spindle_thermal_growth", "The spindle warms with speed and grows along the tool "
        "axis with a thermal time constant.", "e_z(t) = G (1 - exp(-t / tau)) while running",
        "Zhu eq. 3.9 (first-order modal response)", "tcp",
        {"growth_m": (15e-6, "m, steady growth at full speed"),
         "time_constant_s": (0.5 * 3600, "s"), "direction": ([0.0, 0.0, 1.0], "unit vector")}),
    EffectSpec(
        "ballscrew_pitch", "A periodic positioning error of one axis with the ball screw's "
        "pitch (lead error, wobble of the nut), its amplitude growing as the column warms "
        "(the screw and its bearings heat up). Not one of the effects the workbench was "
        "first built for: it is named by the open catalogue's periodic positioning family.",
        "E_aa(q) = A (1 + g dT_column) sin(2 pi q / p + phi)",
        "ISO 230-2 periodic error; ISO 230-1 positioning error E_XX", "tcp",
        {"axis": ("X", "axis"), "pitch_m": (0.01, "m, screw lead"),
         "amplitude_m": (3e-6, "m"), "phase_rad": (0.0, "rad"),
         "growth_per_k": (0.0, "1/K, relative growth of the amplitude per K of the column "
                                "(the column's warm-up: structural_thermal_drift's rise_k, "
                                "time_constant_s)")}),
    EffectSpec(
        "rotary_location", "Where the rotary axes really are: each axis line offset and "
        "tilted from its nominal place, and its zero angle shifted (what Heidenhain "
        "KinematicsOpt / Siemens Cycle 996 identify by probing a sphere). Position-"
        "independent, so the TCP error it causes turns with the rotary axes.",
        "T_loc = Trans(EX0R, EY0R, EZ0R) Rot(EA0R, EB0R, EC0R) before the axis' rotation",
        "ISO 230-1 location errors of a rotary axis R; Khan & Chen section 5", "tcp",
        {"errors": ({"EY0A": 25e-6, "EZ0A": -20e-6, "EB0A": 40e-6, "EC0A": -30e-6,
                     "EX0B": 20e-6, "EA0B": 30e-6}, "m (EX0/EY0/EZ0) or rad (EA0/EB0/EC0)")}),
    EffectSpec(
        "rotary_runout", "An eccentric bearing or encoder disc of one rotary axis: a radial "
        "error motion and an angular positioning error, each once per revolution.",
        "E_radial(theta) = r (cos(theta + phi), sin(theta + phi));  "
        "E_RR(theta) = p sin(theta + phi)",
        "ISO 230-7 (error motions of axes of rotation); Zhu section 5.2", "tcp",
        {"axis": ("A", "rotary axis"), "radial_m": (8e-6, "m, radius of the radial error motion"),
         "positioning_rad": (20e-6, "rad, amplitude of the angular positioning error"),
         "phase_rad": (0.4, "rad")}),
    EffectSpec(
        "reversal", "Backlash in the drive: the axis lags by b/2 against the direction of "
        "motion (semi-closed loop; the scales see it).", "q = c - sign(v) b / 2",
        "ISO 230-2 reversal value B", "both",
        {"backlash_m": (6e-6, "m"), "axes": (["X", "Y", "Z"], "axes")}),
    EffectSpec(
        "table_tilt", "The table (an axis that carries the workpiece) pitches, yaws or "
        "rolls as it travels: its guideway is not straight, or it sags under the part. "
        "The part under the tool moves by the tilt times the arm from the table's frame "
        "to the machining point, so the error grows with the tool's height above the "
        "table and with the other axes' positions.",
        "E_table(q, t) = eps ((1 - k) u + k u^3) (1 + g dT_bed(t)), u = q over the stroke in "
        "[-1, 1]; e = -E x (P_tool - O_table)",
        "Kidani eqs. 2.9-2.10 (w the machining point); ISO 230-1 angular error motions",
        "tcp", {"errors_rad": ({"EAY": 12e-6, "EBX": -10e-6}, "rad, amplitude at the stroke's "
                               "ends of angular error motions of workpiece-side axes"),
                "bow": (0.0, "k in [0, 1]: the cubic share of the pitch (a worn middle)"),
                "growth_per_k": (0.0, "1/K, relative growth per K of the bed")}),
    EffectSpec(
        "servo_lag", "Residual following error after feed-forward: the axis trails the "
        "command by v tau.", "q = c - v tau_lag", "servo following error (Kidani section 4.2)",
        "both", {"lag_s": (2e-4, "s"), "axes": (["X", "Y", "Z"], "axes")}),
]}

#: Effects on unless a scenario switches them off.
DEFAULT_ON = ("geometric",)

def deterioration_bump(q: NDArray[np.float64], start_m: float, end_m: float) -> NDArray[np.float64]:
    """0 outside [start, end], rising smoothly (raised cosine) to 1 at ``end``.

    The distorted section of Kidani Fig. 3.19: the yaw change exceeds the
    tolerance between y = -160 mm and 0 mm and grows towards one end.
    """
    low, high = min(start_m, end_m), max(start_m, end_m)
    u = np.clip((q - low) / max(high - low, 1e-12), 0.0, 1.0)
    if end_m < start_m:
        u = 1.0 - u
    return 0.5 - 0.5 * np.cos(np.pi * u)


@dataclass(frozen=True)
class SineProfile:
    """Smooth, non-polynomial error profile: a sum of sines over position [m]."""

    amplitudes: tuple[float, ...]
    wavelengths_m: tuple[float, ...]
    phases_rad: tuple[float, ...]

    def __call__(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        q = np.asarray(q, dtype=np.float64)
        out = np.zeros_like(q)
        for amplitude, wavelength, phase in zip(self.amplitudes, self.wavelengths_m,
                                                self.phases_rad):
            out += amplitude * np.sin((2.0 * np.pi / wavelength) * q + phase)
        return out

    def tabulated(self, low: float, high: float, step: float = 1e-4):
        """The profile as a linear interpolant on a ``step`` grid over [low, high].

        Interpolating is ~50x cheaper than evaluating sines per sample; with the
        shortest wavelength >= 50 mm the relative error is < (2 pi step/lambda)^2/8
        ~ 2e-5 of the amplitude (sub-nanometre / sub-nanoradian).
        """
        grid = np.arange(low - 2 * step, high + 3 * step, step)
        values = self(grid)
        return lambda q: np.interp(q, grid, values)


def random_profiles(axes, rng: np.random.Generator, linear_m: float, angular_rad: float
                    ) -> dict[str, dict[str, SineProfile]]:
    """axis -> component (X, Y, Z, A, B, C) -> profile; three sines each."""
    out = {}
    for axis in axes:
        out[axis] = {}
        for component in "XYZABC":
            scale = linear_m if component in "XYZ" else angular_rad
            amplitudes = tuple(scale * rng.uniform(0.3, 1.0) / (k + 1) for k in range(3))
            wavelengths = tuple(float(w) for w in rng.uniform([0.6, 0.2, 0.08], [1.2, 0.4, 0.15]))
            phases = tuple(float(p) for p in rng.uniform(0, 2 * np.pi, 3))
            out[axis][component] = SineProfile(amplitudes, wavelengths, phases)
    return out
