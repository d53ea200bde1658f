"""Conversions between ROS message fields and numbers: stamps, float64[] arrays.

Shared by the nodes, the bag tools and the simulator's bag export, so that none
of them imports another's layer. Needs the ROS message runtime only when a
``builtin_interfaces/Time`` is built.
"""
from __future__ import annotations

import array


def nanoseconds_to_stamp(nanoseconds: int):
    """``builtin_interfaces/Time`` for an integer number of nanoseconds."""
    from builtin_interfaces.msg import Time

    return Time(sec=int(nanoseconds // 1_000_000_000), nanosec=int(nanoseconds % 1_000_000_000))


def stamp_to_nanoseconds(stamp) -> int:
    """Integer nanoseconds of a ``builtin_interfaces/Time``."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def pack_float64(values) -> "array.array":
    """``array('d')`` of ``values`` - the fast path into rosidl float64[] fields.

    Assigning an ``array.array('d')`` skips rosidl's per-element type checks,
    which dominate at 20 kHz x 6 channels.
    """
    import numpy as np

    packed = array.array("d")
    packed.frombytes(np.ascontiguousarray(values, dtype=np.float64).tobytes())
    return packed


def unpack_float64(field):
    """numpy float64 view of a rosidl float64[] field (no copy for array('d'))."""
    import numpy as np

    if len(field) == 0:
        return np.zeros(0, dtype=np.float64)
    try:
        return np.frombuffer(field, dtype=np.float64)
    except (TypeError, ValueError, BufferError):
        return np.asarray(field, dtype=np.float64)


def machine_error(reading) -> tuple[float, float, float]:
    """A ``ReferenceMeasurement``'s TCP error without the compensation the CNC applied [m].

    ``error - applied_correction``: what the machine does on its own, the quantity a
    model predicts. Readings of earlier bags have no ``applied_correction`` (nothing
    was applied): their error as it is.
    """
    applied = getattr(reading, "applied_correction", None)
    if applied is None:
        return (reading.error.x, reading.error.y, reading.error.z)
    return (reading.error.x - applied.x, reading.error.y - applied.y,
            reading.error.z - applied.z)


def target_point(reading):
    """A ``ReferenceMeasurement``'s fixed target on the workpiece side (3,) [m], or None
    for the machining point (empty, or a reading that predates the field). A target that
    is not 3 finite values within 10 m is refused (InputDataError)."""
    import numpy as np

    from ..core.errors import InputDataError

    values = np.asarray(getattr(reading, "target_point", ()) or (), dtype=np.float64)
    if values.size == 0:
        return None
    if values.shape != (3,) or not np.all(np.isfinite(values)) or np.any(np.abs(values) > 10):
        raise InputDataError(f"reference reading with a target_point of {values.size} values "
                             "(3 finite values in m within 10 m, or none for the machining "
                             "point): skipped")
    return values


def machine_direction_error(reading) -> tuple[float, float, float] | None:
    """A ``ReferenceMeasurement``'s tool-direction error without the rotary correction the
    CNC applied [rad] (``orientation_error - applied_orientation_correction``), or None
    when the instrument did not measure the direction (or the reading predates it)."""
    if not getattr(reading, "orientation_measured", False):
        return None
    error, applied = reading.orientation_error, reading.applied_orientation_correction
    return (error.x - applied.x, error.y - applied.y, error.z - applied.z)
