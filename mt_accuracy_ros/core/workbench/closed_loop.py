"""The machine's error with the loop closed, phase by phase, at the same reference points.

A reference instrument measuring a compensated machine reads
``measured = e_machine + c_applied`` (the CNC added ``c_applied`` to the
command; Kidani's p2 = p1 - delta e, Kidani eq. 3.16, makes ``c_applied = -e_model``).
The controller knows ``c_applied``, so at every reading both are known:

* the machine's error **without** compensation, ``measured - c_applied``;
* the error **with** the compensation live at that moment, ``measured``.

:func:`loop_phases` cuts a run at its events (model versions, an alarm) and
gives, for each phase and each TCP component, both RMS values with their
k = 2 uncertainties (:mod:`.statistics`) at the same readings, then the run's
end state. Pure numpy; nothing here knows ROS or the simulator.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InputDataError
from .conformance import Conformance, Verdict, judge, overall
from .statistics import Figure, rms_with_uncertainty

COMPONENTS = ("x", "y", "z")
#: The end state: the run's last this many seconds [s of data]. Long enough that the
#: RMS's uncertainty allows a decision against a band of the instrument's own U (at a
#: reading every 0.37 s, ~80 readings: U(RMS) about 0.15 U, against ~0.28 U over 10 s).
END_WINDOW_S = 30.0


@dataclass(frozen=True)
class Phase:
    """One stretch of the run. Figures per component x, y, z [m].

    Attributes
    ----------
    label : str
        The phase's name.
    start_s, end_s : float
        Its first and last reading's time [s].
    count : int
        Readings.
    without : tuple of Figure
        x, y, z: measured - applied, no compensation [m].
    with_compensation : tuple of Figure
        x, y, z: as measured, the compensation live [m].
    """

    label: str
    start_s: float
    end_s: float
    count: int
    without: tuple[Figure, Figure, Figure]     # measured - applied: no compensation
    with_compensation: tuple[Figure, Figure, Figure]

    def as_dict(self) -> dict:
        def um(figures):
            return {c: {"rms_um": f.rms * 1e6, "u_k2_um": f.rms_u_k2 * 1e6,
                        "max_abs_um": f.max_abs * 1e6} for c, f in zip(COMPONENTS, figures)}
        return {"label": self.label, "start_s": self.start_s, "end_s": self.end_s,
                "readings": self.count, "without_compensation": um(self.without),
                "with_compensation": um(self.with_compensation)}

    def verdicts(self, band: float, *, unit: str = "µm", scale: float = 1e6,
                 prefix: str = "e_") -> list[Verdict]:
        """Each component's compensated RMS judged against ``band`` (the figures' unit,
        m or rad) by ISO 14253-1 (:mod:`.conformance`), shown in ``unit`` (x ``scale``).

        The RMS includes the instrument's own noise (u = U/2 per reading), so a perfect
        compensation reads about U/2 with an instrument of band U: conformance is shown
        only when the phase has enough readings for RMS + U(RMS) to fall below the band.

        Parameters
        ----------
        band : float
            The limit each component's RMS is judged against [m] (or [rad]).
        unit : str, optional
            Display unit of the verdicts.
        scale : float, optional
            Factor from the figures' unit to ``unit``.
        prefix : str, optional
            Put before the component letter in each verdict's name.

        Returns
        -------
        list of Verdict
            One per component x, y, z, in ``unit``.

        Raises
        ------
        ParameterError
            A band that is not finite and > 0.
        """
        return [judge(f"{prefix}{c}", f.rms * scale, f.rms_u_k2 * scale, band * scale, unit)
                for c, f in zip(COMPONENTS, self.with_compensation)]

    def conformance(self, band: float) -> Conformance:
        """Every component's verdict together (:func:`.conformance.overall`).

        Parameters
        ----------
        band : float
            The limit [m] (or [rad]).

        Returns
        -------
        Conformance
            WITHIN, OUTSIDE or UNDECIDED.
        """
        return overall(v.state for v in self.verdicts(band))

    def within(self, band: float) -> bool:
        """Conformance shown for every component (RMS + U <= band, ISO 14253-1).

        Parameters
        ----------
        band : float
            The limit [m] (or [rad]).

        Returns
        -------
        bool
            True only when every component is WITHIN.
        """
        return self.conformance(band) is Conformance.WITHIN


def _figures(values: np.ndarray, instrument_u_k2: float, seed: int) -> tuple:
    return tuple(rms_with_uncertainty(values[:, j], instrument_u_k2, seed=seed + j)
                 for j in range(3))


def loop_phases(time_s: ArrayLike, measured_m: ArrayLike, applied_m: ArrayLike,
                events: list[tuple[float, str]], instrument_u_k2: float, *,
                settle_s: float = 1.0, end_window_s: float = END_WINDOW_S,
                min_readings: int = 5) -> list[Phase]:
    """Phases of a closed-loop run.

    Parameters
    ----------
    time_s : array_like, shape (N,)
        Reading times [s], ascending.
    measured_m, applied_m : array_like, shape (N, 3)
        What the instrument read and what the CNC had added [m].
    events : list of tuple of (float, str)
        (time [s], label of the phase that starts there); the first phase's label at
        time -inf included or not (then "start").
    instrument_u_k2 : float
        The reference instrument's expanded uncertainty (k = 2) [m].
    settle_s : float, optional
        Readings this close after an event are left out (the change settling) [s].
    end_window_s : float, optional
        The end state is the last this many seconds of the run [s].
    min_readings : int, optional
        Fewest readings of a phase shown.

    Returns
    -------
    list of Phase
        The whole run without compensation, one phase per event with at least
        ``min_readings`` readings, and the end state (label ``"end state"``); figures
        [m].

    Raises
    ------
    InputDataError
        Lengths that differ, no readings, or NaN/inf.
    """
    t = np.asarray(time_s, dtype=np.float64).reshape(-1)
    measured = np.asarray(measured_m, dtype=np.float64).reshape(-1, 3)
    applied = np.asarray(applied_m, dtype=np.float64).reshape(-1, 3)
    if not (t.size == measured.shape[0] == applied.shape[0]) or t.size == 0:
        raise InputDataError("loop phases: times, measured and applied differ in length or "
                             "are empty")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(measured))
            and np.all(np.isfinite(applied))):
        raise InputDataError("loop phases: NaN/inf in the readings")
    raw = measured - applied
    ordered = sorted(events)
    if not ordered or ordered[0][0] > t[0]:
        ordered.insert(0, (float(t[0]) - 1.0, "start"))
    phases = [Phase("whole run", float(t[0]), float(t[-1]), t.size,
                    _figures(raw, instrument_u_k2, 0), _figures(measured, instrument_u_k2, 10))]
    for k, (start, label) in enumerate(ordered):
        end = ordered[k + 1][0] if k + 1 < len(ordered) else np.inf
        rows = (t >= start + (settle_s if k else 0.0)) & (t < end)
        if rows.sum() < min_readings:
            continue
        phases.append(Phase(label, float(t[rows][0]), float(t[rows][-1]), int(rows.sum()),
                            _figures(raw[rows], instrument_u_k2, 20 + 3 * k),
                            _figures(measured[rows], instrument_u_k2, 40 + 3 * k)))
    rows = t >= t[-1] - end_window_s
    phases.append(Phase("end state", float(t[rows][0]), float(t[-1]), int(rows.sum()),
                        _figures(raw[rows], instrument_u_k2, 90),
                        _figures(measured[rows], instrument_u_k2, 95)))
    return phases


@dataclass(frozen=True)
class VersionJudgement:
    """A model version judged at the machine: the compensated machine's measured error
    over the readings after it went live against the previous version's last ones.

    ``before`` / ``after``: per component x, y, z, RMS of the compensated error with its
    k = 2 uncertainty (sampling and instrument). ``worse`` names the component whose
    error rose by more than the two uncertainties combined (``None`` if none did).

    Attributes
    ----------
    before, after : tuple of Figure
        x, y, z figures of the compensated error [m].
    worse : str or None
        The component that rose beyond both uncertainties.
    """

    before: tuple[Figure, Figure, Figure]
    after: tuple[Figure, Figure, Figure]
    worse: str | None

    @property
    def rise(self) -> tuple[float, float]:
        """(before, after) RMS [m] of the component that rose most (or of the worst)."""
        k = COMPONENTS.index(self.worse) if self.worse else int(np.argmax(
            [a.rms - b.rms for a, b in zip(self.after, self.before)]))
        return self.before[k].rms, self.after[k].rms

    def sentence(self) -> str:
        before, after = self.rise
        if self.worse:
            return (f"measured error rose from {before * 1e6:.2f} to {after * 1e6:.2f} um "
                    f"(e_{self.worse}, beyond the k = 2 uncertainty of both)")
        return ("measured error " + ", ".join(
            f"e_{c} {b.rms * 1e6:.2f} -> {a.rms * 1e6:.2f} um"
            for c, b, a in zip(COMPONENTS, self.before, self.after)) +
            ": not worse beyond the uncertainty")


def judge_version(before_m: ArrayLike, after_m: ArrayLike, instrument_u_k2: float,
                  *, min_readings: int = 5) -> VersionJudgement:
    """Is the machine worse with the new version? (see :class:`VersionJudgement`)

    Parameters
    ----------
    before_m : array_like, shape (N, 3)
        Compensated error the instrument measured under the previous version (its last
        readings) [m].
    after_m : array_like, shape (M, 3)
        The same under the new version (its first readings after it settled) [m].
    instrument_u_k2 : float
        The instrument's expanded uncertainty (k = 2) [m].
    min_readings : int, optional
        Fewest readings needed before and after.

    Returns
    -------
    VersionJudgement
        Figures before and after per component [m], and the component that got worse.

    Raises
    ------
    InputDataError
        Fewer than ``min_readings`` readings on a side, or NaN/inf.
    """
    before = np.asarray(before_m, dtype=np.float64).reshape(-1, 3)
    after = np.asarray(after_m, dtype=np.float64).reshape(-1, 3)
    if before.shape[0] < min_readings or after.shape[0] < min_readings:
        raise InputDataError(f"{before.shape[0]} readings before and {after.shape[0]} after: "
                             f"need {min_readings} of each to judge a version")
    if not (np.all(np.isfinite(before)) and np.all(np.isfinite(after))):
        raise InputDataError("readings to judge a version must be finite")
    figures_before = _figures(before, instrument_u_k2, 11)
    figures_after = _figures(after, instrument_u_k2, 23)
    worse, margin = None, 0.0
    for c, b, a in zip(COMPONENTS, figures_before, figures_after):
        excess = (a.rms - b.rms) - float(np.hypot(a.rms_u_k2, b.rms_u_k2))
        if excess > margin:
            worse, margin = c, excess
    return VersionJudgement(figures_before, figures_after, worse)
