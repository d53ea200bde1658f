"""Command-line options checked against their range: one wording for every refusal.

Each refusal is one :class:`ParameterError` line ``FLAG must be EXPECTED, got VALUE``
(e.g. ``--train-fraction must be a fraction in (0, 1), got 2``), or ``FLAG applies to
..., not to ...`` for an option given where nothing reads it.
"""
from __future__ import annotations

import math

from ..errors import ParameterError


def _shown(value) -> str:
    """``value`` as a user typed it (``2``, ``0.5``, ``nan``)."""
    return f"{value:g}" if isinstance(value, float) else str(value)


def _interval(low: float, high: float, low_open: bool, high_open: bool) -> str:
    """``> 0``, ``>= 1``, ``<= 19`` or ``in [0, 1)``."""
    if math.isinf(high):
        return f"{'>' if low_open else '>='} {_shown(low)}"
    if math.isinf(low):
        return f"{'<' if high_open else '<='} {_shown(high)}"
    return f"in {'(' if low_open else '['}{_shown(low)}, {_shown(high)}{')' if high_open else ']'}"


def in_range(flag: str, value: float | int | None, *, low: float = -math.inf,
             high: float = math.inf, low_open: bool = False, high_open: bool = False,
             what: str = "", unit: str = "") -> None:
    """Refuse ``value`` of ``flag`` unless it is finite and within the bounds.

    Parameters
    ----------
    flag : str
        The option as typed (``--rate``).
    value : float or int or None
        Its value, in the option's unit; None (not given) passes.
    low, high : float, optional
        Bounds, in the option's own unit; infinite: none.
    low_open, high_open : bool, optional
        The bound itself is outside the range.
    what : str, optional
        What the option is (``"an integer"``, ``"a fraction"``; "" for a number), for the
        message.
    unit : str, optional
        The option's unit shown after the range (``"s"``), "" for none.

    Raises
    ------
    ParameterError
        ``FLAG must be [WHAT] RANGE [UNIT], got VALUE`` (``--rate must be > 0, got 0``).
    """
    if value is None:
        return
    inside = math.isfinite(value) and (value > low if low_open else value >= low) and \
        (value < high if high_open else value <= high)
    if not inside:
        bounds = "" if math.isinf(low) and math.isinf(high) else \
            _interval(low, high, low_open, high_open)
        kind = what if math.isfinite(value) else \
            "a finite " + (what.removeprefix("a ").removeprefix("an ") or "number")
        expected = " ".join(part for part in (kind, bounds) if part)
        raise ParameterError(f"{flag} must be {expected}{f' [{unit}]' if unit else ''}, "
                             f"got {_shown(value)}")


def not_applicable(flag: str, applies_to: str, given_with: str) -> ParameterError:
    """The error of ``flag`` given where nothing reads it (raise it).

    Parameters
    ----------
    flag : str
        The option as the user wrote it, e.g. ``--tau``.
    applies_to : str
        What reads it, in words.
    given_with : str
        What it was given with, in words.

    Returns
    -------
    ParameterError
        The error, not raised.
    """
    return ParameterError(f"{flag} applies to {applies_to}, not to {given_with}; leave it out")
