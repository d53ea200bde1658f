"""Is a measured error within its band? The decision rule of ISO 14253-1.

A measured RMS is a figure with an expanded uncertainty U (k = 2,
:mod:`.statistics`). Against a limit (the instrument's band, a tolerance) there are
three outcomes, never two:

* **within** - RMS + U <= limit: conformance is shown;
* **outside** - RMS - U > limit: nonconformance is shown;
* **undecided** - otherwise: the uncertainty straddles the limit, and neither is shown.

Every band verdict of the package goes through :func:`conformance`; a run "in the
band" is one whose conformance is shown, not one that is not proven outside.
Pure Python; nothing here knows ROS.
"""
from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from enum import Enum

from ..errors import ParameterError

#: The standard the rule is from, named in every sentence.
RULE = "ISO 14253-1"


class Conformance(str, Enum):
    """The three outcomes of a measured value judged against a limit."""

    WITHIN = "within"
    OUTSIDE = "outside"
    UNDECIDED = "undecided"


def conformance(rms: float, u_k2: float, limit: float) -> Conformance:
    """The ISO 14253-1 decision for a measured ``rms`` of expanded uncertainty ``u_k2``.

    Parameters
    ----------
    rms : float
        The measured value (an RMS error) [any unit].
    u_k2 : float
        Its expanded uncertainty, k = 2 [the same unit], >= 0.
    limit : float
        The upper limit (the band) [the same unit], > 0.

    Returns
    -------
    Conformance
        WITHIN when rms + u_k2 <= limit, OUTSIDE when rms - u_k2 > limit, else UNDECIDED.

    Raises
    ------
    ParameterError
        A figure that is not finite, a negative uncertainty or a limit <= 0: nothing can
        be decided from them.
    """
    if not all(math.isfinite(v) for v in (rms, u_k2, limit)):
        raise ParameterError(f"conformance: rms {rms!r}, U {u_k2!r} and limit {limit!r} "
                             "must be finite numbers")
    if u_k2 < 0 or limit <= 0:
        raise ParameterError(f"conformance: U {u_k2!r} must be >= 0 and the limit {limit!r} "
                             "> 0 (the same unit as the RMS)")
    if rms + u_k2 <= limit:
        return Conformance.WITHIN
    if rms - u_k2 > limit:
        return Conformance.OUTSIDE
    return Conformance.UNDECIDED


def overall(states: Iterable[Conformance]) -> Conformance:
    """Several components judged together: OUTSIDE if any is, WITHIN only if all are,
    UNDECIDED otherwise (and for no component at all: nothing was shown).

    Parameters
    ----------
    states : iterable of Conformance
        Each component's state.

    Returns
    -------
    Conformance
        The state of all together.
    """
    states = list(states)
    if any(s is Conformance.OUTSIDE for s in states):
        return Conformance.OUTSIDE
    if states and all(s is Conformance.WITHIN for s in states):
        return Conformance.WITHIN
    return Conformance.UNDECIDED


@dataclass(frozen=True)
class Verdict:
    """One figure judged against its limit, with the figures that decided it.

    ``rms``, ``u_k2`` and ``limit`` are in the display unit ``unit`` (e.g. µm).

    Attributes
    ----------
    name : str
        The figure, e.g. ``e_x``.
    rms, u_k2, limit : float
        RMS, its expanded uncertainty (k = 2) and the limit, in ``unit``.
    unit : str
        Display unit.
    state : Conformance
        The ISO 14253-1 outcome.
    """

    name: str
    rms: float
    u_k2: float
    limit: float
    unit: str
    state: Conformance

    def sentence(self) -> str:
        """E.g. 'e_y 0.79 ± 0.28 µm: RMS + U = 1.07 µm > 1.0 µm band: conformance not
        shown (ISO 14253-1)'."""
        head = f"{self.name} {self.rms:.2f} ± {self.u_k2:.2f} {self.unit}"
        band = f"{self.limit:.2g} {self.unit} band"
        upper, lower = self.rms + self.u_k2, self.rms - self.u_k2
        if self.state is Conformance.WITHIN:
            why = f"RMS + U = {upper:.2f} {self.unit} <= {band}: conformance shown"
        elif self.state is Conformance.OUTSIDE:
            why = f"RMS - U = {lower:.2f} {self.unit} > {band}: nonconformance shown"
        else:
            why = (f"RMS + U = {upper:.2f} {self.unit} > {band}: conformance not shown, "
                   f"nor nonconformance (RMS - U = {lower:.2f} {self.unit}): undecided")
        return f"{head}: {why} ({RULE})"

    def as_dict(self) -> dict:
        return {"name": self.name, "rms": self.rms, "u_k2": self.u_k2, "limit": self.limit,
                "unit": self.unit, "conformance": self.state.value,
                "sentence": self.sentence()}


def judge(name: str, rms: float, u_k2: float, limit: float, unit: str) -> Verdict:
    """A :class:`Verdict` of ``rms`` ± ``u_k2`` against ``limit`` (all in ``unit``).

    Parameters
    ----------
    name : str
        The figure's name, e.g. ``e_x``.
    rms : float
        Its RMS, in ``unit``.
    u_k2 : float
        The RMS's expanded uncertainty (k = 2), in ``unit``, >= 0.
    limit : float
        The limit, in ``unit``, > 0.
    unit : str
        The display unit (any; the three numbers share it).

    Returns
    -------
    Verdict
        The verdict by ISO 14253-1.

    Raises
    ------
    ParameterError
        Numbers that are not finite, U < 0 or a limit <= 0.
    """
    return Verdict(name, float(rms), float(u_k2), float(limit), unit,
                   conformance(float(rms), float(u_k2), float(limit)))
