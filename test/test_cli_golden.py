"""The ``mt-accuracy`` command prints what it printed, on the README's cheap examples.

The cases (:mod:`cli_golden_cases`: every command's ``--help``, refusals of bad flags, bag
information, ``check`` on a thermal log, a log of zeroed runs, a survey mapped two ways and
a simulated bag) were run before the commands were reshaped - one typed check result
rendered three ways, command modules that raise - and their outputs are in
``test/golden/cli/``. Printed text must be the same byte for byte; a JSON summary must
hold the same keys with the same values, plus its ``schema_version`` (and any key added
since, as the schema allows).

The goldens were computed with OpenBLAS' Haswell kernels, which ``conftest.py`` pins on
every x86-64 CPU with AVX2 and FMA: kernels chosen by the CPU round their sums apart in
the last bit, and the simulated bag's check turns that into another answer (with
SkylakeX's, ``positioning:EYY`` enters as the second term, final RMSE 2.583 um; with
Haswell's or Zen's it does not, 2.997 um) - a near-tie of that survey, not the CLI's.
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
    """Where ``new`` differs from ``old``: every key of ``old`` in ``new``, in the same
    order, with the same value (floats to 1e-9 relative: a refactored sum may round its
    last bit apart). A key ``new`` adds is no difference: the schema's rule
    (docs/check_json.md) - a reader ignores keys it does not know."""
    if isinstance(old, dict):
        if not isinstance(new, dict) or [k for k in new if k in old] != list(old):
            return [f"{where}: keys {list(new) if isinstance(new, dict) else new!r} do not "
                    f"hold {list(old)} in order"]
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


def documented_schema() -> tuple[int, dict[str, list[str]], dict[str, set[str]]]:
    """(the schema version, each kind's keys, each kind's keys left out when there is
    nothing to say) as ``docs/check_json.md`` states them."""
    import re

    from conftest import REPO_ROOT

    text = (REPO_ROOT / "docs" / "check_json.md").read_text()
    version = int(re.search(r"\*\*schema_version: (\d+)\*\*", text).group(1))
    keys: dict[str, list[str]] = {}
    keys_part, optional_part = text.split("## Keys", 1)[1].split("### Keys left out", 1)
    for key, kinds in re.findall(r"^\| `(\w+)` \| ((?:`\w+`(?:, )?)+) \|", keys_part, re.M):
        for kind in re.findall(r"`(\w+)`", kinds):
            keys.setdefault(kind, []).append(key)
    optional = {kind: set(re.findall(r"`(\w+)`", rest)) for kind, rest in
                re.findall(r"^\| `(\w+)` \| (.*) \|$", optional_part.split("## ", 1)[0], re.M)}
    return version, keys, optional


def test_the_documented_schema_is_the_code_s():
    """docs/check_json.md and the code that writes the JSON state one key set per kind."""
    from mt_accuracy_ros.commands.check_result import JSON_KEYS, OPTIONAL_KEYS, SCHEMA_VERSION

    version, keys, optional = documented_schema()
    assert version == SCHEMA_VERSION
    assert set(keys) == set(JSON_KEYS) == set(optional)
    for kind, written in JSON_KEYS.items():
        assert sorted(keys[kind]) == sorted(["schema_version", *written, "report"]), kind
        assert optional[kind] == OPTIONAL_KEYS[kind], kind


@pytest.mark.parametrize("case", JSON_CASES, ids=lambda case: case.name)
def test_the_json_validates_against_the_documented_key_set(outcomes, case):
    """The JSON written is its kind's documented keys: every key that is always there, a
    key left out only if the schema allows it, no key it does not name, and its version."""
    _, results = outcomes
    summary = results[case.name]["json"]
    version, keys, optional = documented_schema()
    assert summary["schema_version"] == version
    documented = keys[summary["kind"]]
    assert set(summary) <= set(documented)
    missing = set(documented) - set(summary)
    assert missing <= optional[summary["kind"]] | {"report"}
    assert "report" in summary      # every JSON case writes its report too


def _subcommands(parser):
    """(name, its parser) of every subcommand, nested ones too (``topic echo``)."""
    import argparse

    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield name, sub
                yield from ((f"{name} {n}", p) for n, p in _subcommands(sub))


def test_every_command_is_declared_and_handled_by_its_module_and_cli_only_assembles():
    """cli.py holds the parser class, the assembly and main(); each command's handler and
    validator live in a command module, and no command prints its own error: cli.py's only
    print is main()'s one line for a raised error."""
    import ast
    import inspect

    from mt_accuracy_ros import cli

    handled = 0
    for name, sub in _subcommands(cli.build_parser()):
        handler = sub.get_default("handler")
        if handler is None:
            continue          # a group (``topic``, ``model``): its subcommands handle
        handled += 1
        for function in (handler, sub.get_default("validate")):
            if function is not None:
                assert function.__module__.startswith("mt_accuracy_ros.commands."), name
    assert handled >= 20
    tree = ast.parse(inspect.getsource(cli))
    defined = [n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))]
    assert defined == ["_Parser", "build_parser", "main"]
    prints = [n for n in ast.walk(tree) if isinstance(n, ast.Call) and
              getattr(n.func, "id", "") == "print"]
    assert len(prints) == 1
