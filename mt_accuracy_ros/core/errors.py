"""Exception types of the numerical core.

Each subclasses the built-in exception a caller would naturally catch, so that
``except ValueError`` still works for code that does not know this package.
"""
from __future__ import annotations


class MtAccuracyError(Exception):
    """Base class of every error raised on purpose by mt_accuracy_ros."""


class InputDataError(MtAccuracyError, ValueError):
    """Measured data that cannot be used: NaN/inf, empty, mismatched lengths."""


class ParameterError(MtAccuracyError, ValueError):
    """A configuration or model parameter outside its valid range."""


class InsufficientDataError(InputDataError):
    """Fewer samples than the method needs (e.g. fewer points than k)."""


class CalibrationError(MtAccuracyError, ValueError):
    """A fit or calibration that is singular, under-determined or ill-posed."""


class MachineDescriptionError(MtAccuracyError, ValueError):
    """A machine description (YAML) that is malformed or incomplete."""


class ScenarioError(MtAccuracyError, ValueError):
    """A simulator scenario file that is malformed or physically impossible."""


class BagError(MtAccuracyError, OSError):
    """A bag or MCAP file that cannot be read or written as asked."""
