"""What a fleet is made of: machines, their bags and surveys, and the day of each.

``mt-accuracy fleet`` takes any mix of:

* **a directory** - each sub-directory is a machine (its name the folder's), holding
  bags (a directory of ``.mcap`` files, or one ``.mcap`` file) and CSV surveys; a
  ``model.yaml`` beside them is that machine's model, a ``columns.yaml`` its surveys'
  column map. Bags or surveys directly in the directory belong to a machine named
  after it;
* **a glob** (``plant/*/2026-11-*``) - each match is a bag or a survey of the machine
  named after the folder holding it;
* **a manifest** (``.yaml``)::

      machines:
        hmc-1:
          model: models/hmc1.yaml      # bundled name, a path (from the manifest's
                                       # folder) or inline YAML; bags default: demo
          data: [bags/hmc-1/*]         # globs from the manifest's folder
        vmc-2:
          machine: vmc                 # surveys: the machine they were taken on
          columns: maps/vmc.yaml       # surveys: the column map
          data: [surveys/vmc-2-*.csv]

A bag's day is the UTC date of its first message (from its summary, or from
``metadata.yaml`` when the file is damaged); a survey's is a date in its file name
(``2026-11-24`` or ``20261124``). A file whose day cannot be told is a day of its
own. Nothing here reads more than a bag's summary: the diagnosis is the workers'.
"""
from __future__ import annotations

import datetime as _dt
import glob
import re
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from ..core.errors import InputDataError

#: The keys a manifest's machine may have.
MACHINE_KEYS = {"model", "machine", "columns", "data"}
_DATE = re.compile(r"(?<!\d)(\d{4})-?(\d{2})-?(\d{2})(?!\d)")


@dataclass(frozen=True)
class Dataset:
    """One bag or survey of one machine. Paths are absolute strings (sent to workers)."""

    machine: str
    path: str
    kind: str                       # "bag" or "survey_csv"
    model: str | None = None        # a model (bundled name, path or inline YAML)
    machine_file: str | None = None  # surveys: the machine they were taken on
    columns: str | None = None      # surveys: the column map (a YAML path)


@dataclass
class Day:
    """A day of one machine: the unit of work (one task)."""

    machine: str
    day: str                        # ISO date, or "undated: FILE"
    day_number: float | None        # the date's ordinal [days]; None when undated
    datasets: list[Dataset] = field(default_factory=list)

    def as_task(self, auto: int, min_reduction: float) -> dict:
        """What a worker gets: plain values only."""
        return {"machine": self.machine, "day": self.day, "day_number": self.day_number,
                "auto": int(auto), "min_reduction": float(min_reduction),
                "datasets": [d.__dict__.copy() for d in self.datasets]}


def is_bag_directory(path: Path) -> bool:
    return path.is_dir() and ((path / "metadata.yaml").is_file() or any(path.glob("*.mcap")))


def _kind(path: Path) -> str | None:
    if is_bag_directory(path) or (path.is_file() and path.suffix.lower() == ".mcap"):
        return "bag"
    if path.is_file() and path.suffix.lower() == ".csv":
        return "survey_csv"
    return None


def _datasets_in(folder: Path, machine: str, model: str | None, columns: str | None
                 ) -> list[Dataset]:
    found = []
    for child in sorted(folder.iterdir()):
        kind = _kind(child)
        if kind:
            found.append(Dataset(machine, str(child.resolve()), kind, model,
                                 None, columns))
    return found


def _from_directory(root: Path, model: str | None, columns: str | None) -> list[Dataset]:
    if is_bag_directory(root):
        return [Dataset(root.resolve().parent.name, str(root.resolve()), "bag", model,
                        None, columns)]
    found = _datasets_in(root, root.resolve().name, model, columns)
    for child in sorted(p for p in root.iterdir() if p.is_dir() and not is_bag_directory(p)):
        own_model = child / "model.yaml"
        own_columns = child / "columns.yaml"
        found += _datasets_in(child, child.name,
                              str(own_model.resolve()) if own_model.is_file() else model,
                              str(own_columns.resolve()) if own_columns.is_file() else columns)
    return found


def _from_glob(pattern: str, model: str | None, columns: str | None) -> list[Dataset]:
    found = []
    for match in sorted(glob.glob(pattern)):
        path = Path(match).resolve()
        if path.suffix.lower() == ".mcap" and is_bag_directory(path.parent) and \
                (path.parent / "metadata.yaml").is_file():
            path = path.parent           # a file of a bag directory: the bag
        kind = _kind(path)
        if kind:
            found.append(Dataset(path.parent.name, str(path), kind, model, None, columns))
    unique = {d.path: d for d in found}
    if not unique:
        raise InputDataError(f"{pattern}: matches no bag, .mcap or .csv file")
    return list(unique.values())


def _local(value: str | None, base: Path) -> str | None:
    """A manifest's path from its own folder; a bundled name or inline YAML as given."""
    if value is None:
        return None
    candidate = base / str(value)
    return str(candidate.resolve()) if candidate.is_file() else str(value)


def _from_manifest(path: Path) -> list[Dataset]:
    try:
        content = yaml.safe_load(path.read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise InputDataError(f"fleet manifest {path}: cannot be read ({exc})") from exc
    machines = content.get("machines") if isinstance(content, dict) else None
    if not isinstance(machines, dict) or not machines:
        raise InputDataError(f"fleet manifest {path}: expected 'machines:' mapping each "
                             "machine's name to its data (and model)")
    base = path.resolve().parent
    found = []
    for name, entry in machines.items():
        if not isinstance(entry, dict):
            raise InputDataError(f"fleet manifest {path}: machine {name!r}: expected a "
                                 "mapping with data: [globs] (and model:, machine:, columns:)")
        unknown = set(entry) - MACHINE_KEYS
        if unknown:
            raise InputDataError(f"fleet manifest {path}: machine {name!r}: unknown key "
                                 f"{sorted(unknown)[0]!r} "
                                 f"(known: {', '.join(sorted(MACHINE_KEYS))})")
        patterns = entry.get("data")
        patterns = [patterns] if isinstance(patterns, str) else patterns
        if not patterns or not all(isinstance(p, str) for p in patterns):
            raise InputDataError(f"fleet manifest {path}: machine {name!r} has no data: "
                                 "give data: [glob, ...] of its bags or surveys")
        model = _local(entry.get("model"), base)
        machine_file = _local(entry.get("machine"), base)
        columns = _local(entry.get("columns"), base)
        matched = []
        for pattern in patterns:
            full = pattern if Path(pattern).is_absolute() else str(base / pattern)
            for match in sorted(glob.glob(full)):
                kind = _kind(Path(match))
                if kind:
                    matched.append(Dataset(str(name), str(Path(match).resolve()), kind, model,
                                           machine_file, columns))
        if not matched:
            raise InputDataError(f"fleet manifest {path}: machine {name!r}: its data "
                                 f"{patterns} match no bag, .mcap or .csv file")
        found += matched
    return found


def discover(inputs: list[str], model: str | None = None, columns: str | None = None
             ) -> list[Dataset]:
    """Every dataset of ``inputs`` (directories, globs, manifests), in a stable order.

    ``model`` and ``columns`` apply where a machine has none of its own."""
    if not inputs:
        raise InputDataError("give a directory, a glob or a manifest of the fleet's data")
    found: list[Dataset] = []
    for text in inputs:
        path = Path(text)
        if path.is_file() and path.suffix.lower() in (".yaml", ".yml"):
            found += _from_manifest(path)
        elif path.is_dir():
            found += _from_directory(path, model, columns)
        elif path.is_file():
            kind = _kind(path)
            if kind is None:
                raise InputDataError(f"{path}: not a bag, an .mcap, a .csv or a manifest (.yaml)")
            found.append(Dataset(path.resolve().parent.name, str(path.resolve()), kind, model,
                                 None, columns))
        else:
            found += _from_glob(text, model, columns)
    unique = {(d.machine, d.path): d for d in found}
    if not unique:
        raise InputDataError(f"{', '.join(inputs)}: no bag or survey found")
    return sorted(unique.values(), key=lambda d: (d.machine, d.path))


def bag_start_ns(path: Path) -> int | None:
    """The first message's time of a bag [ns], from its summary or, for a damaged
    file, its ``metadata.yaml``; None when neither tells."""
    from ..core.errors import BagError
    from .bag_reader import bag_info

    try:
        return int(bag_info(path)["start_ns"])
    except (BagError, OSError, ValueError, KeyError):
        pass
    metadata = path / "metadata.yaml" if path.is_dir() else path.parent / "metadata.yaml"
    try:
        info = yaml.safe_load(metadata.read_text())["rosbag2_bagfile_information"]
        return int(info["starting_time"]["nanoseconds_since_epoch"])
    except (OSError, TypeError, KeyError, ValueError, yaml.YAMLError):
        return None


def day_of(dataset: Dataset) -> tuple[str, float | None]:
    """(day, the date's ordinal) of a dataset; ("undated: NAME", None) when unknown."""
    date = None
    path = Path(dataset.path)
    if dataset.kind == "bag":
        start = bag_start_ns(path)
        if start is not None and start > 0:
            date = _dt.datetime.fromtimestamp(start / 1e9, tz=_dt.timezone.utc).date()
    if date is None:
        match = _DATE.search(path.name)
        if match:
            try:
                date = _dt.date(*(int(g) for g in match.groups()))
            except ValueError:
                date = None
    if date is None:
        return f"undated: {path.name}", None
    return date.isoformat(), float(date.toordinal())


def plan_days(datasets: list[Dataset]) -> list[Day]:
    """One :class:`Day` per machine and day (the tasks), by machine then date."""
    days: dict[tuple[str, str], Day] = {}
    for dataset in datasets:
        day, number = day_of(dataset)
        days.setdefault((dataset.machine, day), Day(dataset.machine, day, number)
                        ).datasets.append(dataset)
    return sorted(days.values(), key=lambda d: (d.machine, d.day_number is None,
                                                d.day_number or 0.0, d.day))
