"""Shared input checks for the core: one place that words the errors."""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InputDataError, ParameterError


def finite_array(values: ArrayLike, name: str, *, ndim: int | None = None,
                 allow_empty: bool = False) -> NDArray[np.float64]:
    """Return ``values`` as a float64 array after checking it is finite.

    Parameters
    ----------
    values : array_like
        Numbers, any shape and unit (returned unchanged in value).
    name : str
        What they are, named in errors.
    ndim : int, optional
        Required number of dimensions.
    allow_empty : bool, optional
        Accept an empty array.

    Returns
    -------
    ndarray of float64
        The values, shape as given.

    Raises
    ------
    InputDataError
        If the array is empty (unless allowed), has the wrong number of
        dimensions or holds NaN/inf; the message names ``name`` and the first
        bad index.
    """
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputDataError(f"{name}: cannot be read as numbers ({exc})") from exc
    if ndim is not None and array.ndim != ndim:
        raise InputDataError(f"{name}: expected {ndim}-D array, got shape {array.shape}")
    if array.size == 0 and not allow_empty:
        raise InputDataError(f"{name}: empty input")
    bad = ~np.isfinite(array)
    if bad.any():
        first = tuple(int(i) for i in np.argwhere(bad)[0])
        raise InputDataError(
            f"{name}: {int(bad.sum())} non-finite value(s) (NaN or inf), first at index {first}")
    return array


def same_length(name_a: str, a: NDArray, name_b: str, b: NDArray) -> None:
    """Raise :class:`InputDataError` unless ``a`` and ``b`` have equal length.

    Parameters
    ----------
    name_a : str
        Name of ``a``, for the message.
    a : sequence
        First array.
    name_b : str
        Name of ``b``, for the message.
    b : sequence
        Second array.

    Raises
    ------
    InputDataError
        Lengths differ.
    """
    if len(a) != len(b):
        raise InputDataError(f"{name_a} has {len(a)} values but {name_b} has {len(b)}")


def positive(value: float, name: str) -> float:
    """Return ``value`` as float after checking it is finite and > 0.

    Parameters
    ----------
    value : float
        The number, any unit.
    name : str
        What it is, named in errors.

    Returns
    -------
    float
        ``value``.

    Raises
    ------
    ParameterError
        Not finite or not > 0.
    """
    value = float(value)
    if not np.isfinite(value) or value <= 0.0:
        raise ParameterError(f"{name} must be a finite positive number, got {value!r}")
    return value


#: Sample periods a scale stream may declare [s]: 10 MHz down to 0.1 Hz. Outside,
#: the number is a unit mistake (ms or us given as s) or garbage.
SAMPLE_PERIOD_RANGE_S = (1e-7, 10.0)


def sample_period(value: float, name: str = "sample_period") -> float:
    """A stream's sample period [s], checked against :data:`SAMPLE_PERIOD_RANGE_S`.

    Parameters
    ----------
    value : float
        Sample period [s].
    name : str, optional
        What it is, named in errors.

    Returns
    -------
    float
        ``value`` [s].

    Raises
    ------
    InputDataError
        Not finite or outside :data:`SAMPLE_PERIOD_RANGE_S`.
    """
    value = float(value)
    low, high = SAMPLE_PERIOD_RANGE_S
    if not (np.isfinite(value) and low <= value <= high):
        raise InputDataError(f"{name} {value!r} s: must be finite, within [{low:g}, {high:g}] s "
                             "(seconds, not ms)")
    return value


def as_samples(values: ArrayLike, n: int) -> NDArray[np.float64]:
    """``values`` as a read-only (n,) float64 array, a one-value input repeated n times.

    What ``np.broadcast_to(np.asarray(values, float).ravel(), (n,))`` gives (the caller's
    data cannot be written through it), without that call's cost when the values
    already are n: a view of them. A node evaluates a model at one row per message,
    and there the broadcast cost more than the arithmetic.

    Parameters
    ----------
    values : array_like
        n values (any shape of that size, read flat) or one value.
    n : int
        Number of samples.

    Returns
    -------
    ndarray, shape (n,)
        Read-only.

    Raises
    ------
    ValueError
        Neither n values nor one.
    """
    array = np.asarray(values, dtype=np.float64)
    if array.size != 1:
        array = array.ravel()
    if array.shape == (n,):
        view = array.view()
        view.flags.writeable = False
        return view
    return np.broadcast_to(array, (n,))
