"""The ``mt-accuracy`` command prints what it printed, on the README's cheap examples.

The cases (:mod:`cli_golden_cases`: every command's ``--help``, refusals of bad flags, bag
information, ``check`` on a thermal log, a log of zeroed runs, a survey mapped two ways and
a simulated bag) were run before the commands were reshaped - one typed check result
rendered three ways, command modules that raise - and their outputs are in
``test/golden/cli/``. Printed text must be the same byte for byte; a JSON summary must
hold the same keys with the same values, plus its ``schema_version``.
"""
from __future__ import annotations

import json
import math

import pytest

from cli_golden_cases import CASES, GOLDEN, run_cases, transcript

JSON_CASES = [case for case in CASES if case.json]


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory):
    """Every case run once, in order, in one directory: (the inputs' digests, outcomes)."""
    return run_cases(tmp_path_factory.mktemp("cli_golden"))


def test_the_generated_inputs_are_the_goldens_inputs(outcomes):
    """The survey and the log of runs come from the studies' seeded generators: were they
    to change, every comparison below would fail for a reason that is not the CLI's."""
    digests, _ = outcomes
    assert digests == json.loads((GOLDEN / "inputs.json").read_text())


@pytest.mark.parametrize("case", CASES, ids=lambda case: case.name)
def test_printed_output_is_byte_identical(outcomes, case):
    _, results = outcomes
    expected = (GOLDEN / f"{case.name}.txt").read_text()
    assert transcript(case, results[case.name]) == expected


def _same(new, old, where: str = "") -> list[str]:
    """Where ``new`` differs from ``old``: the same keys in the same order, the same
    values (floats to 1e-9 relative: a refactored sum may round its last bit apart)."""
    if isinstance(old, dict):
        if not isinstance(new, dict) or list(new) != list(old):
            return [f"{where}: keys {list(new) if isinstance(new, dict) else new!r} != "
                    f"{list(old)}"]
        return [d for key in old for d in _same(new[key], old[key], f"{where}.{key}")]
    if isinstance(old, list):
        if not isinstance(new, list) or len(new) != len(old):
            return [f"{where}: {new!r} != {old!r}"[:300]]
        return [d for k, (a, b) in enumerate(zip(new, old)) for d in _same(a, b, f"{where}[{k}]")]
    if isinstance(old, float) and isinstance(new, (int, float)) and not isinstance(new, bool):
        return [] if math.isclose(new, old, rel_tol=1e-9, abs_tol=1e-15) else \
            [f"{where}: {new!r} != {old!r}"]
    return [] if new == old and type(new) is type(old) else [f"{where}: {new!r} != {old!r}"[:300]]


@pytest.mark.parametrize("case", JSON_CASES, ids=lambda case: case.name)
def test_the_json_keeps_its_keys_and_values(outcomes, case):
    _, results = outcomes
    summary = dict(results[case.name]["json"])
    old = json.loads((GOLDEN / f"{case.name}.json").read_text())
    summary.pop("schema_version", None)
    assert _same(summary, old) == []
