"""Every equation the package cites names its source, so a reader can find it.

A bare "eq. 2.13" could be any of the four seeds' (Kidani's and Zhu's chapters both
number from 2.1); the citation's form is "Kidani eq. 2.13". A source may sit on the
line before, where a sentence wraps.
"""
from __future__ import annotations

import re
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "mt_accuracy_ros"
#: The seeds' authors and the standards the package cites by equation.
SOURCES = ("Kidani", "Zhu", "Khan & Chen", "Chen", "Krulewich", "JCGM 100", "GUM", "ISO")
CITATION = re.compile(r"\b[Ee]qs?\.\s?\d")
#: How far before "eq." the source may stand (a wrapped line, an "and" between two).
REACH = 60


def bare_citations(text: str) -> list[str]:
    """The lines of ``text`` citing an equation with no source within reach before it."""
    bare = []
    for match in CITATION.finditer(text):
        before = text[max(0, match.start() - REACH):match.start()]
        if not any(source in before for source in SOURCES):
            line_start = text.rfind("\n", 0, match.start()) + 1
            line_end = text.find("\n", match.start())
            bare.append(text[line_start:line_end].strip())
    return bare


def test_the_rule_finds_a_bare_citation_and_passes_a_named_one():
    assert bare_citations("yaw from the pair (eq. 2.13)\n") == ["yaw from the pair (eq. 2.13)"]
    assert bare_citations("# Kidani eq. 2.13\n") == []
    assert bare_citations("(Kidani\n    eqs. 2.22-2.23)\n") == []


def test_every_equation_the_package_cites_names_its_source():
    found = {}
    for path in sorted(PACKAGE.rglob("*")):
        if path.suffix in (".py", ".yaml", ".md") and path.is_file():
            bare = bare_citations(path.read_text(encoding="utf-8"))
            if bare:
                found[str(path.relative_to(PACKAGE))] = bare
    assert not found, found
