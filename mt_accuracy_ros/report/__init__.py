"""Every HTML report of the package: one Jinja2 template, plots as PNG files beside it.

A report is a :class:`Report` of :class:`Section` s, each with paragraphs,
tables and figures; :func:`render` writes it through
``templates/report.html.j2`` (autoescaped, so no text of a bag or CSV can
inject markup), and :meth:`Report.as_dict` is the same content for the JSON
summary. The builders:

* :func:`write_bag_report` - a bag of this package's topics (the main job's
  bag, or any bag ``mt-accuracy check`` is given), with the workbench result;
* :func:`write_check_report` - ``mt-accuracy check`` on a bag or a CSV table.

Sections and plots are built in :mod:`.sections` from what :mod:`.bag_data` reads.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

TEMPLATE = "report.html.j2"


@dataclass(frozen=True)
class Cell:
    text: str
    numeric: bool = False


@dataclass(frozen=True)
class Row:
    cells: list[Cell]
    css_class: str = ""


@dataclass
class Table:
    columns: list[str]
    rows: list[Row] = field(default_factory=list)
    caption: str = ""

    def add(self, *values, css_class: str = "") -> None:
        """Append a row; numbers are right-aligned, floats shown to 4 significant digits."""
        self.rows.append(Row([_cell(v) for v in values], css_class))


@dataclass(frozen=True)
class Figure:
    source: str  # relative to the report
    caption: str


@dataclass
class Section:
    title: str
    paragraphs: list[str] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)

    @property
    def anchor(self) -> str:
        return "-".join("".join(c if c.isalnum() else " " for c in self.title.lower()).split())


@dataclass
class Report:
    title: str
    subtitle: str = ""
    sections: list[Section] = field(default_factory=list)

    def as_dict(self) -> dict:
        """The report's content for a JSON summary: the same sections, tables and figures."""
        return {"title": self.title, "subtitle": self.subtitle, "sections": [
            {"title": s.title, "paragraphs": list(s.paragraphs),
             "tables": [{"caption": t.caption, "rows": [
                 dict(zip(t.columns, (c.text for c in r.cells)), **(
                     {"status": r.css_class} if r.css_class else {})) for r in t.rows]}
                 for t in s.tables],
             "figures": [{"file": f.source, "caption": f.caption} for f in s.figures]}
            for s in self.sections]}


def _cell(value) -> Cell:
    if isinstance(value, bool):
        return Cell("yes" if value else "no")
    if isinstance(value, (int, np.integer)):
        return Cell(str(value), numeric=True)
    if isinstance(value, (float, np.floating)):
        return Cell(f"{value:.4g}", numeric=True)
    return Cell(str(value))


def render(report: Report, path: Path) -> Path:
    """Write ``report`` as HTML to ``path`` (its figures must already be beside it)."""
    from jinja2 import Environment, PackageLoader, StrictUndefined, select_autoescape

    from .. import __version__

    environment = Environment(loader=PackageLoader("mt_accuracy_ros", "templates"),
                              autoescape=select_autoescape(default=True),
                              undefined=StrictUndefined, trim_blocks=True, lstrip_blocks=True)
    page = environment.get_template(TEMPLATE).render(
        title=report.title, subtitle=report.subtitle, sections=report.sections,
        version=__version__)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(page, encoding="utf-8")
    return path


def save_figure(fig, directory: Path, name: str, caption: str) -> Figure:
    """Save a matplotlib figure as ``directory/name.png`` (legends outside the axes) and close
    it."""
    import matplotlib.pyplot as plt

    target = Path(directory) / f"{name}.png"
    fig.savefig(target, dpi=90, bbox_inches="tight")
    plt.close(fig)
    return Figure(target.name, caption)


def pyplot():
    """matplotlib.pyplot with the file backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def write_bag_report(path: Path, bag: Path, check_result=None, *, title: str,
                     subtitle: str = "", extra_sections: list[Section] = (),
                     namespace: str = "") -> Report:
    """The full report of a bag (see :mod:`.sections`), with ``check_result`` (a
    :class:`~mt_accuracy_ros.commands.check_result.CheckResult` of the bag, or None);
    returns the :class:`Report` written."""
    from .bag_data import read_bag
    from .sections import bag_report_sections

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    data = read_bag(bag, namespace)
    sections = bag_report_sections(data, check_result, path.parent, path.with_suffix("").name)
    report = Report(title, subtitle, sections[:2] + list(extra_sections) + sections[2:])
    render(report, path)
    return report


def write_check_report(result, path: Path) -> Report:
    """``mt-accuracy check``'s report of ``result`` (a
    :class:`~mt_accuracy_ros.commands.check_result.CheckResult`): a bag's full report, or
    a CSV table's."""
    from .sections import csv_report_sections, survey_report_sections

    if result.kind == "bag":
        return write_bag_report(path, Path(result.data), result, title="mt-accuracy check",
                                subtitle=f"The model against the measurements of {result.data}",
                                namespace=result.source.namespace or "")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    stem = path.with_suffix("").name
    if result.kind == "survey_csv":
        report = Report("mt-accuracy check", f"The model against the reference survey "
                        f"{result.data}", survey_report_sections(result, path.parent, stem))
    else:
        report = Report("mt-accuracy check", f"Thermal model of {result.log.target} from "
                        f"{result.data}", csv_report_sections(result, path.parent, stem))
    render(report, path)
    return report
