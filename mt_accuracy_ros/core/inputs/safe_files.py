"""Reading description files (machines, models) without trusting where their names came from.

A machine or model may be named by a user on the command line, or by a message or
parameter that any peer on the DDS network can send. Whatever the source, a
description is read only from a **regular file** no larger than
:data:`MAX_DESCRIPTION_BYTES` (a FIFO would block the reader forever, ``/dev/zero``
would fill memory), opened non-blocking, and a YAML error names the line and
column of the problem but never quotes the file's content (a line of a secret
file must not travel to a foreign node inside an error on ``/diagnostics``).
"""
from __future__ import annotations

import os
import re
import stat
from pathlib import Path

from ..errors import MtAccuracyError
from .file_kinds import bom_encoding, signature_kind

#: The largest machine or model description read [bytes] (the bundled ones are < 10 kB).
MAX_DESCRIPTION_BYTES = 1 << 20

#: A plain name: letters, digits, '_', '-' and inner dots, no separator, no '..'.
_PLAIN_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$")


def plain_name(text: str) -> bool:
    """Is ``text`` a bare file or bundled name (no directory part, no traversal)?

    Parameters
    ----------
    text : str
        A name as given.

    Returns
    -------
    bool
        True for letters, digits, ``_``, ``-`` and inner dots, no ``..``, at most 255
        characters.
    """
    return bool(_PLAIN_NAME.match(text)) and ".." not in text and len(text) <= 255


def read_description(path: str | Path, what: str, error_class: type[MtAccuracyError],
                     max_bytes: int = MAX_DESCRIPTION_BYTES) -> str:
    """The text of the description file ``path`` (UTF-8, or the encoding its byte-order
    mark declares).

    Raises ``error_class`` (naming ``path`` and ``what``, never the content) when it is
    missing, not a regular file, larger than ``max_bytes`` or not text.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What it is (``machine description``, ``model``), named in errors.
    error_class : type of MtAccuracyError
        The error raised.
    max_bytes : int, optional
        Largest size read [bytes] (default :data:`MAX_DESCRIPTION_BYTES`).

    Returns
    -------
    str
        The decoded text.

    Raises
    ------
    MtAccuracyError
        ``error_class``: missing, not a regular file, too large, or not text.
    """
    path = Path(path)
    try:
        info = os.stat(path)
    except FileNotFoundError as exc:
        raise error_class(f"{what} not found: {path}") from exc
    except OSError as exc:
        raise error_class(f"{path}: cannot read {what} ({exc.strerror})") from exc
    if not stat.S_ISREG(info.st_mode):
        raise error_class(f"{path}: {what} is not a regular file")
    if info.st_size > max_bytes:
        raise error_class(f"{path}: {what} of {info.st_size} bytes exceeds the "
                          f"{max_bytes}-byte limit")
    try:
        # Non-blocking: the file may have been swapped for a FIFO since the check.
        descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
        with os.fdopen(descriptor, "rb") as handle:
            data = handle.read(max_bytes + 1)
    except OSError as exc:
        raise error_class(f"{path}: cannot read {what} ({exc.strerror})") from exc
    if len(data) > max_bytes:
        raise error_class(f"{path}: {what} exceeds the {max_bytes}-byte limit")
    return _description_text(data, path, what, error_class)


def _description_text(data: bytes, path: Path, what: str,
                      error_class: type[MtAccuracyError]) -> str:
    """``data`` decoded: by its byte-order mark (a Windows editor's "Unicode" is UTF-16),
    else as UTF-8; what is neither is refused naming its kind and the mend."""
    encoding = bom_encoding(data) or "utf-8"
    kind = signature_kind(data)
    if kind:
        raise error_class(f"{path}: {what} is {kind}, not a YAML text file")
    if encoding == "utf-8" and b"\x00" in data:
        # NUL is valid UTF-8 but never in a description: UTF-16 that lost its mark.
        raise error_class(f"{path}: {what} holds NUL bytes, not UTF-8 text; UTF-16 without "
                          "a byte-order mark? save it as UTF-8")
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        name = "UTF-8" if encoding == "utf-8" else encoding.upper().replace("-SIG", "")
        raise error_class(f"{path}: {what} is not {name} text (byte {exc.start})") from exc


def yaml_problem(exc: Exception) -> str:
    """Where and what a YAML error is, without the snippet of text it would quote.

    Parameters
    ----------
    exc : Exception
        A YAML error (with ``problem_mark`` / ``problem`` when PyYAML's).

    Returns
    -------
    str
        The problem, quoted tokens longer than two characters left out, and its line
        and column.
    """
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    problem = getattr(exc, "problem", None) or getattr(exc, "context", None) or "malformed"
    # PyYAML's problems quote at most a token ("found undefined alias 'secret'"): a
    # quoted part longer than one character (an escape like '\t') is left out too.
    problem = re.sub(r"'[^']{3,}'", "'...'", str(problem))
    where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
    return f"{problem}{where}"


def load_yaml(text: str, source: str, error_class: type[MtAccuracyError]):
    """``yaml.safe_load`` of ``text``; a YAML error becomes ``error_class`` without content.

    Parameters
    ----------
    text : str
        The YAML text.
    source : str
        Where it came from, named in errors.
    error_class : type of MtAccuracyError
        The error raised.

    Returns
    -------
    object
        The loaded document (None for an empty one).

    Raises
    ------
    MtAccuracyError
        ``error_class``: not valid YAML, or nested too deeply.
    """
    import yaml

    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise error_class(f"{source}: not valid YAML ({yaml_problem(exc)})") from exc
    except RecursionError as exc:
        raise error_class(f"{source}: YAML nested too deeply") from exc
