"""Output paths checked before any work: a long run must not end in a failed write.

Every command that writes (``--json``, ``--report``, ``--out``, ``-o/--output``,
``recover``'s new bag) hands its output paths to :func:`check_outputs` first; a path
that cannot be written is refused in one line naming the flag, the path and the mend,
and nothing has been computed or written yet.

The rules (one place, for every command):

* A **file** (``--json``, ``--report``) may exist (it is replaced) but must not be a
  directory; its directory is **created** when missing (as every writer of this package
  does, ``mkdir -p``), so its nearest existing ancestor must be a writable directory - a
  path through a file (``notes.txt/s.json``) is refused.
* A **directory** (``--out`` of ``demo`` and ``simulate``) may exist (it must be a
  directory then) or not: the command creates it, parents included, so its nearest
  existing ancestor must be a writable directory.
* A **new** directory (``recover``'s and ``record``'s bag) must not exist (a bag is
  never overwritten); it is created the same way.
* No output is one of the command's inputs (it would be overwritten), and no two
  outputs are the same path.

Writable means :func:`os.access` grants writing and entering (a read-only file system
refuses too); the check creates nothing.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from ..core.errors import ParameterError

#: What an output is: a file, a directory (created when missing) or a new directory.
KINDS = ("file", "directory", "new directory")


@dataclass(frozen=True)
class Output:
    """One output a command will write: the ``flag`` that names it (``--json``,
    ``OUTPUT``), its ``path`` (None: not asked for) and its ``kind`` (:data:`KINDS`)."""

    flag: str
    path: str | os.PathLike | None
    kind: str = "file"


def _writable_directory(flag: str, path: Path, directory: Path) -> None:
    """Refuse unless ``directory`` (where ``path`` goes) is a directory this process may
    write into."""
    if not directory.is_dir():
        raise ParameterError(f"{flag} {path}: {directory} is a file, not a directory")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise ParameterError(f"{flag} {path}: the directory {directory} is not writable "
                             "(choose another place)")


def _nearest_existing(path: Path) -> Path:
    """``path`` or its nearest ancestor that exists (the filesystem root at worst)."""
    for candidate in (path, *path.parents):
        if candidate.exists():
            return candidate
    return Path(path.anchor or ".")


def check_output(output: Output) -> Path | None:
    """Refuse ``output`` in one line (:class:`ParameterError` naming its flag and path)
    unless it can be written as its kind says; returns its path (None when not asked)."""
    if output.path is None:
        return None
    if output.kind not in KINDS:
        raise ValueError(f"unknown output kind {output.kind!r}")
    path = Path(output.path)
    flag = output.flag
    if not str(output.path).strip():
        raise ParameterError(f"{flag}: an empty path; give a file or directory name")
    if output.kind == "file":
        if path.is_dir():
            raise ParameterError(f"{flag} {path} is a directory; give a file name in it, "
                                 f"e.g. {path / 'summary'}{'.json' if 'json' in flag else '.html'}")
        _writable_directory(flag, path, _nearest_existing(path.parent))
        return path
    if path.exists():
        if output.kind == "new directory":
            raise ParameterError(f"{flag} {path} already exists; give a new directory (a bag "
                                 "is never overwritten)")
        if not path.is_dir():
            raise ParameterError(f"{flag} {path} is a file, not a directory")
        _writable_directory(flag, path, path)
        return path
    _writable_directory(flag, path, _nearest_existing(path.parent))
    return path


def check_outputs(outputs: list[Output], inputs: list[str | os.PathLike] = ()) -> None:
    """:func:`check_output` of each output, then refuse an output that is one of
    ``inputs`` (it would be overwritten) or that two flags share."""
    seen: dict[Path, str] = {}
    sources = {Path(p).resolve(): str(p) for p in inputs if p is not None}
    for output in outputs:
        path = check_output(output)
        if path is None:
            continue
        resolved = path.resolve()
        if resolved in sources:
            raise ParameterError(f"{output.flag} {path} is the input {sources[resolved]}; it "
                                 "would be overwritten (give another path)")
        if resolved in seen:
            raise ParameterError(f"{output.flag} {path} is also {seen[resolved]}'s path; give "
                                 "each output its own")
        seen[resolved] = output.flag
