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


#: What a loader of user files may raise by accident on malformed content
#: (a list where a mapping belongs, text where a number does, a binary file).
MALFORMED_INPUT = (TypeError, ValueError, KeyError, IndexError, AttributeError,
                   UnicodeDecodeError, OverflowError, RecursionError)


def reraise_as(error_class: type[MtAccuracyError], context: str):
    """Decorator: a loader raises only this package's errors.

    Any :data:`MALFORMED_INPUT` exception escaping the wrapped function becomes
    ``error_class`` with ``context`` and the original message, chained with
    ``from``; this package's own errors pass through unchanged.

    Parameters
    ----------
    error_class : type of MtAccuracyError
        The error raised instead.
    context : str
        What was being read, put before the message (with the first argument when it is
        a path or text).

    Returns
    -------
    callable
        The decorator.
    """
    import functools

    def decorate(function):
        @functools.wraps(function)
        def wrapper(*args, **kwargs):
            try:
                return function(*args, **kwargs)
            except MtAccuracyError:
                raise
            except MALFORMED_INPUT as exc:
                source = args[0] if args and isinstance(args[0], (str, bytes)) or \
                    (args and hasattr(args[0], "__fspath__")) else ""
                where = f"{context} {str(source)[:80]!s}".strip() if source else context
                raise error_class(f"{where}: malformed ({type(exc).__name__}: {exc})") from exc
        return wrapper
    return decorate
