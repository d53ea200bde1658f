"""docs/reliability.md is the bad-input corpus' own table: generated from the CLASSES the
tests in test/bad_inputs/ run, so a class added, dropped or reworded shows there."""
from __future__ import annotations

import subprocess
import sys

from conftest import REPO_ROOT


def test_the_reliability_table_is_the_corpus_the_tests_run():
    done = subprocess.run([sys.executable, str(REPO_ROOT / "tools" / "reliability_table.py"),
                           "--check"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr


def test_the_corpus_holds_at_least_sixty_classes_each_refused_or_announced():
    sys.path.insert(0, str(REPO_ROOT / "tools"))
    from reliability_table import CORPUS, corpus_classes

    classes = [c for path in sorted(CORPUS.glob("test_*.py")) for c in corpus_classes(path)]
    assert len(classes) >= 60
    assert len({name for name, _, _ in classes}) == len(classes)      # each class once
    assert all(outcome.split(":", 1)[0] in ("refused", "announced") for _, _, outcome in classes)
