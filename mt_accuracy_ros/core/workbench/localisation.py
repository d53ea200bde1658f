"""Where the residual lives, in numbers, even when no catalogue effect fits.

For each TCP component c and each variable v (every axis position, velocity,
direction, acceleration, temperature rise, temperature difference, time,
spindle speed, the product of two linear axes' positions, where a twist
lives, each structure sensor lagged by 10, 20 and 40 min, where a
structure following its sensor late lives, and the spindle speed and each
axis' |feed| lagged likewise from rest, where a heat source's growth lives), the
residual r_c is regressed on v alone with the
k-nearest-neighbour smoother whose k is chosen by K-fold cross-validation
(Kidani eqs. 4.10-4.12, the same estimator the yaw pipeline uses). The
**share** of r_c's variance that v explains is 1 - CV MSE / var(r_c), so a
variable that only fits noise scores about zero. For every linear axis a
**periodogram** of r_c in that axis' position (2-50 mm) gives the period and
amplitude of the strongest peak, for pitch and waviness that a smoother of
the whole stroke would blur.

:func:`localise` returns the numbers and :func:`Localisation.sentence` the
plain sentence a user reads first, e.g. "the residual's x component repeats every
10.0 mm of X travel with 4.0 um amplitude: typical of a ball-screw pitch
error".
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..scales.knn import cross_validate_k_many
from .selection.folds import Folds
from ..effects.spectral import (direct_basis, frequency_grid, grid_periodogram, resolvable,
                                weight_sums)
from ..effects.variables import Variables

COMPONENTS = "xyz"
#: Time constants of the lagged temperatures the residual is localised on [s].
LOCALISATION_LAGS_S = (600.0, 1200.0, 2400.0)
#: The kNN shares of a component are computed on at most this many of its readings,
#: evenly spread in time (all of them below it).
SHARE_READINGS = 2500


@dataclass
class Share:
    """How much of one component's residual one variable explains.

    Attributes
    ----------
    variable : str
        The variable's name (:func:`candidate_variables`), e.g. ``x``, ``T_spindle@20min``.
    component : str
        The TCP component, ``x``, ``y`` or ``z``.
    share : float
        Its cross-validated share of the component's residual variance, dimensionless (at
        most 1; about zero, or below, for a variable that only fits noise).
    explained_rms : float
        RMS of the part it explains [m].
    """

    variable: str
    component: str
    share: float          # of the component's residual variance, cross-validated [0..1]
    explained_rms: float  # RMS of the part it explains [m]


@dataclass
class Peak:
    """The strongest periodic component of one TCP component along one linear axis.

    Attributes
    ----------
    axis : str
        The linear axis' letter (``X``, ``Y``, ``Z``).
    component : str
        The TCP component, ``x``, ``y`` or ``z``.
    period_m : float
        The period along the axis' position [m].
    amplitude : float
        The fundamental's amplitude [m], at most what ``share`` supports.
    share : float
        Of the component's variance the sinusoid explains, dimensionless: the lesser of
        the in-sample share and the share held-out time blocks give.
    """

    axis: str
    component: str
    period_m: float
    amplitude: float      # of the fundamental [m]
    share: float          # of the component's variance the sinusoid explains (in-sample)


@dataclass
class Localisation:
    """Where the residual lives: each variable's share and each axis' periodogram peak.

    Attributes
    ----------
    shares : list of Share
        Every variable's share of every measured component, best first.
    peaks : list of Peak
        Every linear axis' strongest period per component, strongest first.
    component_rms : dict of str to float
        Component (``x``, ``y``, ``z``) -> RMS of its residual about its mean [m].
    noise_sigma : float
        The instrument's standard (k = 1) noise [m].
    """

    shares: list[Share]                       # best first
    peaks: list[Peak]                         # strongest first
    component_rms: dict[str, float] = field(default_factory=dict)
    noise_sigma: float = 0.0

    def top(self) -> Share | None:
        return self.shares[0] if self.shares else None

    def top_group(self, within: float = 0.005) -> list[Share]:
        """The top share and every other variable the data cannot rank below it (within
        ``within`` of its share, the resolution of the cross-validation): slow
        temperatures and their lags often explain a warm-up's drift equally well.

        Parameters
        ----------
        within : float, optional
            How far below the top share a variable may lie and still be in the group,
            dimensionless (a share).

        Returns
        -------
        list of Share
            The top share first, then the others in the group (one per variable); empty
            when there are no shares.
        """
        best = self.top()
        if best is None:
            return []
        group, names = [best], {best.variable}
        for share in self.shares[1:]:
            if share.share < best.share - within:
                break
            if share.variable not in names:
                group.append(share)
                names.add(share.variable)
        return group

    def sentence(self) -> str:
        """One plain sentence on where the residual lives (empty if it lives nowhere)."""
        best = self.top()
        peak = self.peaks[0] if self.peaks else None
        # A period is the finding only where it explains at least as much of its
        # component as the best smooth variable there: a drift read by a periodic program
        # aliases into a sinusoid of position that explains much, but less.
        rival = max((s.share for s in self.shares if peak is not None and
                     s.component == peak.component), default=0.0)
        if peak is not None and peak.share >= 0.3 and peak.amplitude > self.noise_sigma and \
                peak.share >= rival:
            return (f"the residual's {peak.component} component repeats every "
                    f"{peak.period_m * 1e3:.1f} mm of {peak.axis} travel with "
                    f"{peak.amplitude * 1e6:.1f} um amplitude ({peak.share:.0%} of its "
                    f"variance): typical of a ball-screw pitch error of {peak.axis} (or a rack, "
                    "or a wavy guideway)")
        if best is None or best.share < 0.1:
            return ""
        v = best.variable
        hint = _HINTS.get(v[:2] if v.startswith(("v_", "T_")) else
                          v if v in _HINTS else v.split("_")[0], "")
        if "@" in v and not v.startswith("T_"):
            hint = "heat from that source reaching the structure with a thermal lag"
        if "*" in v:
            hint = "a twist of that travel plane (a cross-axis error)"
        if v.startswith("T_") and "-" in v:
            hint = "a temperature gradient bending the structure"
        what = _describe(v)
        also = [_describe(s.variable) for s in self.top_group()[1:]]
        more = f" and {len(also) - 3} more" if len(also) > 3 else ""
        equally = f"; as well by {', '.join(also[:3])}{more}" if also else ""
        return (f"the residual in {best.component} follows {what} ({best.share:.0%} of its "
                f"variance, {best.explained_rms * 1e6:.1f} um RMS{equally})"
                f"{': ' + hint if hint else ''}")

    def chart(self, per_component: int = 4, alike: float = 0.05) -> list[dict]:
        """What a chart of where the residual lives should show: per component, the few
        variables that differ. Temperatures that explain about the same (within ``alike``
        of the best of them - a warm-up seen by every sensor) are one bar, "all N
        temperatures alike", not a dozen bars of 92 % that tell the reader nothing.

        Parameters
        ----------
        per_component : int, optional
            The most bars each component shows.
        alike : float, optional
            How far below the best temperature's share another's may lie and still be
            counted alike, dimensionless (a share); three or more alike make one bar.

        Returns
        -------
        list of dict
            One per bar, largest share first: ``{"label", "component", "share"
            (dimensionless), "variables" (the names it stands for)}``; only positive
            shares.
        """
        rows = []
        for component in COMPONENTS:
            mine = [s for s in self.shares if s.component == component and s.share > 0]
            temperatures = [s for s in mine if s.variable.startswith("T_")]
            alike_group = [s for s in temperatures
                           if temperatures and s.share >= temperatures[0].share - alike]
            entries = []
            for share in mine:
                if len(alike_group) >= 3 and share in alike_group:
                    if share is alike_group[0]:
                        entries.append({"label": f"all {len(alike_group)} temperatures alike "
                                                 f"(best {share.variable})",
                                        "component": component, "share": share.share,
                                        "variables": [s.variable for s in alike_group]})
                    continue
                entries.append({"label": share.variable, "component": component,
                                "share": share.share, "variables": [share.variable]})
            rows += entries[:per_component]
        return sorted(rows, key=lambda r: -r["share"])

    def as_dict(self, top: int = 12) -> dict:
        """The localisation as plain data (SI: metres, shares dimensionless).

        Parameters
        ----------
        top : int, optional
            How many of the best shares to give.

        Returns
        -------
        dict
            ``shares`` (the ``top`` best: ``variable``, ``component``, ``share``,
            ``explained_rms_m``), ``chart`` (:meth:`chart`), ``peaks`` (the six strongest:
            ``axis``, ``component``, ``period_m``, ``amplitude_m``, ``share``),
            ``top_group`` (the variables' names) and ``sentence``.
        """
        return {"shares": [{"variable": s.variable, "component": s.component,
                            "share": s.share, "explained_rms_m": s.explained_rms}
                           for s in self.shares[:top]],
                "chart": self.chart(),
                "peaks": [{"axis": p.axis, "component": p.component, "period_m": p.period_m,
                           "amplitude_m": p.amplitude, "share": p.share} for p in self.peaks[:6]],
                "top_group": [s.variable for s in self.top_group()],
                "sentence": self.sentence()}


_HINTS = {"v_": "a following (servo) error or a speed-dependent effect",
          "T_": "a thermal effect of the structure that sensor sits on",
          "dir": "backlash or friction at the reversal",
          "acc": "a structure deflecting under inertial load",
          "t": "a slow drift no sensor follows (thermal, or a settling structure)",
          "t_run": "a warm-up in every run that no sensor follows (thermal, or settling)",
          "spindle": "spindle heat", "x": "a geometric error depending on that axis",
          "y": "a geometric error depending on that axis",
          "z": "a geometric error depending on that axis",
          "a": "an error of the rotary axis", "b": "an error of the rotary axis",
          "c": "an error of the rotary axis"}


def _describe(variable: str) -> str:
    if variable == "t":
        return "time"
    if variable == "t_run":
        return "the time since its run's start"
    if variable.startswith("T_") and "@" in variable:
        name, late = variable[2:].split("@")
        return f"the {name} temperature {late} late"
    if "@" in variable:
        name, late = variable.split("@")
        what = "the spindle speed" if name == "spindle_speed" else \
            f"the {name.strip('|')[2:].upper()} feed"
        return f"{what} {late} late (a heat source)"
    if variable.startswith("T_"):
        name = variable[2:]
        return f"the difference {name.replace('-', ' - ')}" if "-" in name else \
            f"the {name} temperature"
    for prefix, word in (("v_", "feed"), ("acc_", "acceleration"), ("dir_", "direction of "
                                                                           "motion")):
        if variable.startswith(prefix):
            return f"the {variable[len(prefix):].upper()} {word}"
    if variable.startswith("spindle"):
        return "the spindle speed"
    if "*" in variable:
        a, b = variable.split("*")
        return f"the product of the {a.upper()} and {b.upper()} positions"
    return f"the {variable.upper()} position"


def candidate_variables(variables: Variables, structure_sensors: list[str]) -> dict[str, NDArray]:
    """Every scalar variable to localise on (temperatures: structure sensors and their
    differences; constant variables are left out).

    Parameters
    ----------
    variables : Variables
        The machine's state at the N readings.
    structure_sensors : list of str
        The sensors on the structure: their rises, lags and differences are localised on
        (other temperatures are left out).

    Returns
    -------
    dict of str to ndarray, shape (N,)
        Name -> values, each in its own unit: the :class:`~..effects.variables.Variables`
        ones (positions [m] or [rad], feeds [m/s], accelerations [m/s^2], directions +-1,
        ``t`` [s] - ``t_run`` since each run's start when there are runs -, spindle speed
        [rad/s], temperatures' rises ``T_<sensor>`` [K]); the lags of each structure
        sensor's rise ``T_<sensor>@<min>min`` [K] and of the spindle speed and each
        linear axis' |feed| from rest ``<name>@<min>min`` ([rad/s], [m/s]), at the
        :data:`LOCALISATION_LAGS_S` the record spans; products of two linear axes'
        centred positions ``x*y`` [m^2]; differences of two sensors' rises ``T_a-b`` [K].
    """
    out = {}
    for name in variables.names():
        if name.startswith("T_") and name[2:] not in structure_sensors:
            continue
        if name == "spindle_rpm":
            continue
        values = variables.get(name)
        if np.all(np.isfinite(values)) and np.ptp(values) > 0:
            out[name] = values
    if "t" in out and variables.run_starts is not None:
        # Time across runs (a night, a restarted clock) means nothing to the machine: only
        # the time since each run's start can be followed.
        out["t_run"] = out.pop("t")
    if variables.time_s is not None and variables.n > 2:
        # A structure following its sensor late lives in the sensor's lag, not in the
        # sensor: the lags of every structure sensor at a few time constants - only those
        # the record is long enough to see (a 40 min lag of a 90 s record is a ramp).
        span = variables.span_s()     # the longest run's: every lag restarts with its run
        lags = [tau for tau in LOCALISATION_LAGS_S if tau <= span]
        for sensor in structure_sensors:
            for tau in lags:
                values = variables.lag(f"where_{sensor}", variables.rise(sensor), tau)
                if np.ptp(values) > 0:
                    out[f"T_{sensor}@{tau / 60:.0f}min"] = values
        # Heat sources warm the structure late: the operating inputs' lags from rest.
        drivers = {}
        if variables.spindle_speed_rad_s is not None:
            drivers["spindle_speed"] = variables.spindle_speed_rad_s
        drivers.update({f"|v_{a.lower()}|": np.abs(v) for a, v in variables.velocities.items()
                        if a in "XYZ"})
        for name, signal in drivers.items():
            if np.ptp(signal) <= 0:
                continue
            for tau in lags:
                out[f"{name}@{tau / 60:.0f}min"] = variables.lag(f"where_{name}", signal, tau,
                                                                 from_rest=True)
    linear = sorted(a for a in variables.positions if a in "XYZ")
    for i, a in enumerate(linear):
        for b in linear[i + 1:]:
            # A twist lives in neither position alone (its mean over one is zero).
            pa = variables.positions[a] - np.mean(variables.positions[a])
            pb = variables.positions[b] - np.mean(variables.positions[b])
            if np.ptp(pa) > 0 and np.ptp(pb) > 0:
                out[f"{a.lower()}*{b.lower()}"] = pa * pb
    for i, a in enumerate(structure_sensors):
        for b in structure_sensors[i + 1:]:
            values = variables.rise(a) - variables.rise(b)
            if np.ptp(values) > 0:
                out[f"T_{a}-{b}"] = values
    return out


def _blocked_share(q: NDArray[np.float64], r: NDArray[np.float64], period_m: float,
                   folds: int) -> float:
    """Share of r's variance a sinusoid of ``period_m`` along q predicts in held-out
    contiguous time blocks (fitted, with an offset, on the other blocks)."""
    phase = 2.0 * np.pi * q / period_m
    design = np.column_stack([np.ones(q.size), np.cos(phase), np.sin(phase)])
    # Blocks of ceil(N / folds) readings, the last shorter.
    cv = Folds.of_readings(q.size, folds, cut="ceil")
    # Each block's normal equations once; a fit on the others is the whole's minus its own
    # (3 columns of an offset and one sinusoid: well conditioned, and a 3 x 3 solve per
    # block instead of a least-squares fit of the other blocks' rows).
    grams = cv.training_sums(cv.block_products(design, design))
    moments = cv.training_sums(cv.block_products(design, r))

    def solve(fold: int) -> NDArray[np.float64]:
        if np.linalg.cond(grams[fold]) < 1e10:
            return np.linalg.solve(grams[fold], moments[fold])
        # A period the positions barely sample: the minimum-norm fit, as before.
        train = cv.training_rows(fold)
        coefficients, *_ = np.linalg.lstsq(design[train], r[train], rcond=None)
        return coefficients

    residual, _ = cv.held_out_residuals(design, r, solve)
    squared = 0.0
    for a, b in cv.bounds:
        squared += float(np.sum(residual[a:b] ** 2))
    return max(0.0, 1.0 - squared / float(np.sum(r ** 2)))



def _variable_shares(candidates: dict[str, NDArray], measured: dict, folds: int) -> list[Share]:
    """Each candidate variable's held-out kNN share of each component's residual.

    Components measured at the same readings share one neighbour search (the
    neighbours depend on the variable alone).
    """
    groups: dict[bytes, list[str]] = {}
    for component, (rows, _, _) in measured.items():
        groups.setdefault(np.packbits(rows).tobytes() + bytes([rows.size % 8]), []
                          ).append(component)
    names = list(candidates)
    found: dict[str, list[Share]] = {}
    for components in groups.values():
        rows = measured[components[0]][0]
        n = int(rows.sum())
        # The shares are estimates with a resolution of ~1/sqrt(N); beyond a few thousand
        # readings more of them sharpen nothing a reader sees, and cost O(N k) each.
        subset = slice(None)
        if n > SHARE_READINGS:
            subset = np.unique(np.linspace(0, n - 1, SHARE_READINGS).round().astype(np.intp))
        r_shares = np.column_stack([measured[c][1][subset] for c in components])
        r_shares = r_shares - r_shares.mean(axis=0)
        variance_shares = np.mean(r_shares ** 2, axis=0)
        size = r_shares.shape[0]
        k_lim = max(1, min(60, int(size * (folds - 1) / folds) - 1))
        jittered = np.empty((len(names), size))
        unit_jitter = np.random.default_rng(0).uniform(-1e-9, 1e-9, size)
        for i, name in enumerate(names):
            v = candidates[name][rows][subset]
            # Ties (a stepped temperature, a direction) share their neighbours fairly: a
            # seeded jitter far below the variable's resolution breaks them.
            jittered[i] = v + unit_jitter * (np.ptp(v) or 1.0)
        results = cross_validate_k_many(jittered, r_shares, k_lim=k_lim, n_folds=folds, seed=0)
        for j, component in enumerate(components):
            variance = measured[component][2]
            found[component] = []
            for name, per_component in zip(names, results):
                share = 1.0 - per_component[j].cv_rmse ** 2 / max(variance_shares[j], 1e-300)
                found[component].append(Share(name, component, float(share),
                                              float(np.sqrt(max(share, 0.0) * variance))))
    return [share for component in COMPONENTS for share in found.get(component, [])]


def localise(residual: NDArray[np.float64], mask: NDArray[np.bool_], variables: Variables,
             structure_sensors: list[str], noise_sigma: float,
             strokes: dict[str, tuple[float, float]] | None = None, folds: int = 5,
             zero_rows: NDArray[np.intp] | None = None) -> Localisation:
    """Shares of the residual (N, 3) explained by each variable, and periodogram peaks.
    ``zero_rows`` (N,): readings of an instrument zeroed at those rows (a log of zeroed
    runs) - every variable is referred to them as the residual is.

    Parameters
    ----------
    residual : ndarray, shape (N, 3)
        The TCP position residual [m], by component x, y, z.
    mask : ndarray of bool, shape (N, 3)
        Which components each reading measured; a component with fewer than
        ``4 * folds`` is left out.
    variables : Variables
        The machine's state at the N readings.
    structure_sensors : list of str
        The sensors on the structure (:func:`candidate_variables`).
    noise_sigma : float
        The instrument's standard (k = 1) noise [m], kept for the sentence.
    strokes : dict of str to (float, float), optional
        Axis letter -> (low, high) stroke [m]: the linear axes named here get a
        periodogram (2-50 mm periods); None: none does.
    folds : int, optional
        K of the cross-validations.
    zero_rows : ndarray of int, shape (N,), optional
        Each reading's zero row; None when the readings are absolute.

    Returns
    -------
    Localisation
        The shares (best first; time after a physical variable within 5 % of it) and the
        peaks (strongest first).
    """
    shares, peaks = [], []
    candidates = candidate_variables(variables, structure_sensors)
    if zero_rows is not None:
        candidates = {name: values - values[zero_rows] for name, values in candidates.items()
                      if np.ptp(values - values[zero_rows]) > 0}
    rms = {}
    measured = {}     # component -> (rows, centred residual, its variance)
    for c, component in enumerate(COMPONENTS):
        rows = mask[:, c]
        r = residual[rows, c]
        if r.size < 4 * folds:
            continue
        r = r - r.mean()
        variance = float(np.mean(r ** 2))
        rms[component] = float(np.sqrt(variance))
        if variance > 0:
            measured[component] = (rows, r, variance)
    shares = _variable_shares(candidates, measured, folds)
    # The exponentials of an axis' positions serve each component read at the same rows.
    bases: dict[tuple, tuple] = {}
    for c, component in enumerate(COMPONENTS):
        if component not in measured:
            continue
        rows, r, variance = measured[component]
        for axis, values in variables.positions.items():
            if strokes is None or axis not in strokes or axis in "ABC":
                continue
            q = values[rows]
            span = float(np.ptp(q))
            if span <= 0:
                continue
            frequencies = resolvable(frequency_grid(span), q)
            if not frequencies.size:
                continue
            periods = 1.0 / frequencies
            key = (axis, np.asarray(rows).tobytes())
            if key not in bases:
                basis = direct_basis(q, frequencies)
                # Unit weights: their sums serve every component read at these rows.
                bases[key] = basis, weight_sums(q, np.ones(q.size), frequencies, basis=basis)
            basis, unit_weights = bases[key]
            explained, amplitude = grid_periodogram(q, r, None, frequencies,
                                                    weights=unit_weights, basis=basis)
            best = int(np.argmax(explained))
            # The best of hundreds of periods explains much in-sample even of a smooth drift
            # (regular readings of a periodic program alias time into position); held-out
            # time blocks tell a period that lives in the data from one that fits it.
            share = min(float(explained[best] / (variance * r.size)),
                        _blocked_share(q, r, float(periods[best]), folds))
            # The amplitude the share supports (a sinusoid of amplitude A holds A^2/2 of
            # variance): an uneven sampling can fit a large sinusoid that explains little,
            # and a finding must not claim more than it explains.
            supported = float(np.sqrt(2.0 * max(share, 0.0) * variance))
            peaks.append(Peak(axis, component, float(periods[best]),
                              min(float(amplitude[best]), supported), share))
    shares.sort(key=lambda s: -s.share)
    # Time is a proxy, never a cause: a physical variable explaining nearly as much
    # (within 5 %) is named before it.
    for i, share in enumerate(shares):
        if share.variable not in ("t", "t_run"):
            continue
        rival = next((j for j in range(i + 1, len(shares))
                      if shares[j].variable not in ("t", "t_run") and
                      shares[j].share >= 0.95 * share.share), None)
        if rival is not None:
            shares.insert(i, shares.pop(rival))
        break
    peaks.sort(key=lambda p: -p.share)
    return Localisation(shares, peaks, rms, noise_sigma)


class LocalisationMemo:
    """The localisations of one set of readings, kept for a residual seen again.

    ``check --auto`` localises what the named effects leave twice: in the first look
    (the selection's joint fit of them) and in the look at the model with them added.
    Both are the same residual to rounding (1e-15 of its RMS on a 10,000-reading
    survey), and a localisation costs a kNN search over every variable. A residual
    equal to a kept one - on the same rows, with the same settings, each component
    within ``relative_tolerance`` of its RMS about its mean (the mean is no part of a
    localisation) - gets the kept localisation. One memo serves one set of readings.

    Parameters
    ----------
    relative_tolerance : float, optional
        How far (max |difference|) a component's centred residual may lie from a kept
        one's, relative to the kept one's RMS, to be taken as equal; dimensionless.
    size : int, optional
        How many localisations are kept (the latest).
    """

    def __init__(self, relative_tolerance: float = 1e-9, size: int = 4) -> None:
        self.relative_tolerance = float(relative_tolerance)
        self.size = int(size)
        self._kept: list[tuple] = []
        #: How many localisations were served from the memo (for tests and benches).
        self.reused = 0

    def localise(self, residual: NDArray[np.float64], mask: NDArray[np.bool_],
                 variables: Variables, structure_sensors: list[str], noise_sigma: float,
                 strokes: dict[str, tuple[float, float]] | None = None, folds: int = 5,
                 zero_rows: NDArray[np.intp] | None = None) -> Localisation:
        """:func:`localise`, or the kept result of an equal residual.

        Parameters
        ----------
        residual : ndarray, shape (N, 3)
            The TCP position residual [m].
        mask : ndarray of bool, shape (N, 3)
            Which components each reading measured.
        variables : Variables
            The machine's state at the N readings.
        structure_sensors : list of str
            The sensors on the structure.
        noise_sigma : float
            The instrument's standard (k = 1) noise [m].
        strokes : dict of str to (float, float), optional
            Axis letter -> (low, high) stroke [m] (:func:`localise`).
        folds : int, optional
            K of the cross-validations.
        zero_rows : ndarray of int, shape (N,), optional
            Each reading's zero row; None when the readings are absolute.

        Returns
        -------
        Localisation
            As :func:`localise` gives it (the kept object itself when reused: do not
            change it).
        """
        settings = (variables.n, tuple(variables.names()), tuple(structure_sensors),
                    float(noise_sigma), tuple(sorted((strokes or {}).items())), int(folds),
                    None if zero_rows is None else np.asarray(zero_rows).tobytes())
        mask = np.asarray(mask, dtype=bool)
        centred = [residual[mask[:, c], c] - residual[mask[:, c], c].mean()
                   if mask[:, c].any() else np.zeros(0) for c in range(mask.shape[1])]
        for kept_settings, kept_mask, kept_centred, result in self._kept:
            if kept_settings == settings and np.array_equal(kept_mask, mask) and all(
                    a.size == b.size and (a.size == 0 or float(np.max(np.abs(a - b))) <=
                                          self.relative_tolerance *
                                          float(np.sqrt(np.mean(b ** 2))))
                    for a, b in zip(centred, kept_centred)):
                self.reused += 1
                return result
        result = localise(residual, mask, variables, structure_sensors, noise_sigma, strokes,
                          folds, zero_rows)
        self._kept = (self._kept + [(settings, mask.copy(), centred, result)])[-self.size:]
        return result
