"""User expressions: evaluated by a tree walk, never eval; anything unsafe refused."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.effects.expression import ExpressionError, parse


def _run(text, **values):
    return parse(text).evaluate(values, lambda name, tau: values[name] * 0 + tau)


def test_arithmetic_and_functions_match_numpy():
    x = np.linspace(0, 0.4, 9)
    y = np.linspace(-0.2, 0.1, 9)
    got = _run("2 * x ** 2 - y / 3 + sin(2 * pi * x / 0.01) * exp(-abs(y)) + sqrt(x) * -1", x=x,
               y=y)
    expected = 2 * x ** 2 - y / 3 + np.sin(2 * np.pi * x / 0.01) * np.exp(-np.abs(y)) - np.sqrt(x)
    np.testing.assert_allclose(got, expected, rtol=1e-15)
    assert parse("k * x * lag(T_spindle, 1200)").lagged == (("T_spindle", 1200.0),)
    assert parse("k * x * y").names == {"k", "x", "y"}


@pytest.mark.parametrize("text, message", [
    ("__import__('os').system('rm -rf /')", "attribute access"),
    ("__import__('os')", "function '__import__' is not allowed"),
    ("__builtins__ * x", "names starting with '_'"),
    ("x.__class__", "attribute access"),
    ("np.sin(x)", "only plain function calls"),
    ("open('/etc/passwd')", "function 'open' is not allowed"),
    ("eval('1')", "function 'eval' is not allowed"),
    ("(lambda: 1)()", "only plain function calls"),
    ("lambda: 1", "lambda"),
    ("x[0]", "subscripts"),
    ("[a for a in x]", "comprehensions"),
    ("'text'", "only numbers"),
    ("x if y else 1", "conditional"),
    ("x > 1", "comparisons"),
    ("sin(x=1)", "keyword arguments"),
    ("(x := 3)", "assignments"),
    ("sin(x, y)", "takes 1 argument"),
    ("lag(T_a + 1, 10)", "lag takes a variable name"),
    ("x +", "syntax error"),
    ("True * x", "only numbers"),
    ("-(" * 60 + "x" + ")" * 60, "nested deeper"),
])
def test_unsafe_or_malformed_expressions_are_refused(text, message):
    with pytest.raises(ExpressionError, match=message):
        parse(text, "user effect 'bad'")
