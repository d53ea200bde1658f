"""Write docs/reliability.md from the bad-input corpus in test/bad_inputs/.

Each corpus module holds ``CLASSES``: (class, input, expected outcome) tuples, one
pytest case each. The table is generated from them, so that the document says exactly
what the tests assert. ``python tools/reliability_table.py`` rewrites the file;
``--check`` exits 1 when it is out of date (test/test_reliability_doc.py runs that).
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
CORPUS = REPO / "test" / "bad_inputs"
DOC = REPO / "docs" / "reliability.md"

#: Corpus module -> the section's title.
SECTIONS = {
    "test_survey_inputs.py": "Surveys, column maps, laser runs, ball-bar and probing files",
    "test_log_inputs.py": "Thermal logs",
    "test_survey_and_bag_sensors.py": "Temperature sensors in surveys and bags",
    "test_files_and_flags.py": "Files, encodings, bags and flags",
    "test_live_inputs.py": "Live messages to the running nodes",
}

HEADER = """# Reliability: what the package does with bad input

Every class below is one test case in `test/bad_inputs/` (the table is generated from
their `CLASSES` lists by `python tools/reliability_table.py`; a test fails when it is out
of date). Each asserts one of two outcomes:

- **refused**: one line naming the problem and the mend (which row, column, flag or unit;
  what was expected), exit code 2, nothing written;
- **announced**: the run goes on, and the decision is said in the output (and in the JSON
  where there is one) in the words quoted. Live nodes say it on `/diagnostics` and keep
  running.

Run them: `.venv/bin/python -m pytest test/bad_inputs -q`.
"""


def corpus_classes(path: Path) -> list[tuple[str, str, str]]:
    """The ``CLASSES`` of one corpus module (imported without running its tests)."""
    for where in (str(REPO), str(REPO / "test")):
        if where not in sys.path:
            sys.path.insert(0, where)
    spec = importlib.util.spec_from_file_location(f"corpus_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return [tuple(entry[:3]) for entry in module.CLASSES]


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def table() -> str:
    """The whole document."""
    lines = [HEADER]
    total = 0
    order = list(SECTIONS)
    files = sorted(CORPUS.glob("test_*.py"),
                   key=lambda p: (order.index(p.name) if p.name in order else len(order), p.name))
    for path in files:
        classes = corpus_classes(path)
        total += len(classes)
        lines += [f"## {SECTIONS.get(path.name, path.stem)} ({len(classes)} classes, "
                  f"`test/bad_inputs/{path.name}`)", "",
                  "| class | input | outcome |", "| --- | --- | --- |"]
        for name, described, outcome in classes:
            kind, _, words = str(outcome).partition(":")
            lines.append(f"| `{_cell(name)}` | {_cell(described)} | **{_cell(kind)}**: "
                         f"{_cell(words)} |")
        lines.append("")
    lines.insert(1, f"{total} classes of bad or awkward input, each with its asserted outcome.\n")
    return "\n".join(lines).rstrip() + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if the file is stale")
    args = parser.parse_args(argv)
    text = table()
    if args.check:
        if not DOC.exists() or DOC.read_text() != text:
            print(f"{DOC} is out of date: run python tools/reliability_table.py", file=sys.stderr)
            return 1
        return 0
    DOC.write_text(text)
    print(f"{DOC}: written")
    return 0


if __name__ == "__main__":
    sys.exit(main())
