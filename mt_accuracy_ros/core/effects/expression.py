"""Safe arithmetic expressions over named variables, for user-defined effects.

A user writes an effect as text in the model YAML, e.g.::

    expression: "p1 * x * y + p2 * sin(2 * pi * x / 0.01) * lag(T_spindle, 1200)"
    parameters: [p1, p2]

The text is parsed with :mod:`ast` into a tree and that tree is interpreted
here over numpy arrays; nothing is ever handed to ``eval`` or ``exec``. Only
numbers, names, + - * / ** (unary +/- too) and calls of the whitelisted
functions below are allowed; attribute access, subscripts, imports, lambdas,
comprehensions, keyword arguments, strings and any other call are refused
with an :class:`ExpressionError` that names the construct.

Functions: sin cos tan arcsin arccos arctan tanh sinh cosh exp log log10
sqrt abs sign minimum maximum, and ``lag(variable, tau_s)``: the first-order
lag of a variable with a fixed time constant (see
:func:`.variables.first_order_lag`). Constants: ``pi``, ``e``.
"""
from __future__ import annotations

import ast
from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError

MAX_LENGTH = 2000
MAX_DEPTH = 40

FUNCTIONS: dict[str, Callable] = {
    "sin": np.sin, "cos": np.cos, "tan": np.tan, "arcsin": np.arcsin, "arccos": np.arccos,
    "arctan": np.arctan, "tanh": np.tanh, "sinh": np.sinh, "cosh": np.cosh, "exp": np.exp,
    "log": np.log, "log10": np.log10, "sqrt": np.sqrt, "abs": np.abs, "sign": np.sign,
    "minimum": np.minimum, "maximum": np.maximum,
}
CONSTANTS = {"pi": float(np.pi), "e": float(np.e)}
_BINARY = {ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply,
           ast.Div: np.divide, ast.Pow: np.power}
_UNARY = {ast.USub: np.negative, ast.UAdd: np.positive}


class ExpressionError(ParameterError):
    """An expression that is not valid, not safe, or not usable here."""


@dataclass(frozen=True)
class Expression:
    """A checked expression: its text, tree and the names it uses.

    Attributes
    ----------
    text : str
        The expression, stripped.
    tree : ast.AST
        Its checked syntax tree (``mode="eval"``).
    names : frozenset of str
        The variables and parameters it names (constants left out).
    lagged : tuple of tuple of (str, float)
        (variable, tau [s]) of every ``lag()`` call.
    """

    text: str
    tree: ast.AST
    names: frozenset[str]
    lagged: tuple[tuple[str, float], ...]   # (variable, tau) of every lag() call

    def evaluate(self, values: dict[str, object], lag: Callable[[str, float], NDArray]
                 ) -> NDArray[np.float64]:
        """Value of the expression; ``values`` maps every name, ``lag(var, tau)`` the lags.

        Parameters
        ----------
        values : dict of str to object
            Every name the expression uses -> a float or an ndarray of shape (N,), in the
            variable's unit (:mod:`.variables`).
        lag : callable
            ``lag(variable, tau_s)`` -> ndarray, shape (N,): the lagged variable.

        Returns
        -------
        ndarray
            The value, broadcast over the inputs' shape (N,) (0-d for constants only).
        """
        with np.errstate(all="ignore"):
            return np.asarray(_interpret(self.tree, values, lag), dtype=np.float64)


def _describe(node: ast.AST) -> str:
    kinds = {ast.Attribute: "attribute access", ast.Subscript: "subscripts",
             ast.Lambda: "lambda", ast.ListComp: "comprehensions",
             ast.GeneratorExp: "comprehensions", ast.Constant: "this constant",
             ast.Compare: "comparisons", ast.BoolOp: "boolean operators",
             ast.IfExp: "conditional expressions", ast.NamedExpr: "assignments",
             ast.Starred: "starred arguments", ast.JoinedStr: "strings",
             ast.List: "lists", ast.Tuple: "tuples", ast.Dict: "dicts"}
    return kinds.get(type(node), type(node).__name__)


def parse(text: str, where: str = "expression") -> Expression:
    """Check ``text`` and return an :class:`Expression`.

    Parameters
    ----------
    text : str
        The expression (see the module docstring for the grammar).
    where : str, optional
        What it belongs to, named in errors.

    Returns
    -------
    Expression
        The checked expression with its names and lags.

    Raises
    ------
    ExpressionError
        Syntax errors, forbidden constructs, calls outside the whitelist.
    """
    if not isinstance(text, str) or not text.strip():
        raise ExpressionError(f"{where}: expected an expression as text, got {text!r}")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"{where}: longer than {MAX_LENGTH} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise ExpressionError(f"{where}: syntax error at column {exc.offset}: {exc.msg} "
                              f"in {text!r}") from exc
    names: set[str] = set()
    lagged: list[tuple[str, float]] = []

    def check(node: ast.AST, depth: int) -> None:
        if depth > MAX_DEPTH:
            raise ExpressionError(f"{where}: nested deeper than {MAX_DEPTH} levels")
        if isinstance(node, ast.Expression):
            return check(node.body, depth + 1)
        if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            check(node.left, depth + 1)
            return check(node.right, depth + 1)
        if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
            return check(node.operand, depth + 1)
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                raise ExpressionError(f"{where}: only numbers may be written as constants, "
                                      f"not {node.value!r}")
            try:
                finite = np.isfinite(float(node.value))
            except OverflowError:
                finite = False
            if not finite:
                raise ExpressionError(f"{where}: a constant beyond the floating-point range "
                                      f"({str(node.value)[:20]}...)")
            return None
        if isinstance(node, ast.Name):
            if node.id.startswith("_"):
                raise ExpressionError(f"{where}: names starting with '_' are not allowed "
                                      f"({node.id!r})")
            if node.id not in CONSTANTS:
                names.add(node.id)
            return None
        if isinstance(node, ast.Call):
            if not isinstance(node.func, ast.Name):
                raise ExpressionError(f"{where}: only plain function calls are allowed, not "
                                      f"{_describe(node.func)}")
            if node.keywords:
                raise ExpressionError(f"{where}: keyword arguments are not allowed")
            name = node.func.id
            if name == "lag":
                if len(node.args) != 2 or not isinstance(node.args[0], ast.Name) or not (
                        isinstance(node.args[1], ast.Constant) and
                        isinstance(node.args[1].value, (int, float)) and
                        not isinstance(node.args[1].value, bool) and node.args[1].value >= 0):
                    raise ExpressionError(f"{where}: lag takes a variable name and a time "
                                          "constant in seconds, e.g. lag(T_spindle, 1200)")
                names.add(node.args[0].id)
                lagged.append((node.args[0].id, float(node.args[1].value)))
                return None
            if name not in FUNCTIONS:
                raise ExpressionError(f"{where}: function {name!r} is not allowed; allowed: "
                                      f"{', '.join(sorted(FUNCTIONS))}, lag")
            expected = 2 if name in ("minimum", "maximum") else 1
            if len(node.args) != expected:
                raise ExpressionError(f"{where}: {name} takes {expected} argument(s)")
            for argument in node.args:
                check(argument, depth + 1)
            return None
        raise ExpressionError(f"{where}: {_describe(node)} not allowed (only numbers, names, "
                              "+ - * / ** and whitelisted functions)")

    check(tree, 0)
    return Expression(text.strip(), tree, frozenset(names), tuple(lagged))


def _interpret(node: ast.AST, values: dict, lag: Callable):
    if isinstance(node, ast.Expression):
        return _interpret(node.body, values, lag)
    if isinstance(node, ast.BinOp):
        return _BINARY[type(node.op)](_interpret(node.left, values, lag),
                                      _interpret(node.right, values, lag))
    if isinstance(node, ast.UnaryOp):
        return _UNARY[type(node.op)](_interpret(node.operand, values, lag))
    if isinstance(node, ast.Constant):
        return float(node.value)
    if isinstance(node, ast.Name):
        return CONSTANTS[node.id] if node.id in CONSTANTS else values[node.id]
    if isinstance(node, ast.Call):
        if node.func.id == "lag":
            return lag(node.args[0].id, float(node.args[1].value))
        return FUNCTIONS[node.func.id](*[_interpret(a, values, lag) for a in node.args])
    raise ExpressionError(f"cannot evaluate {_describe(node)}")  # parse() forbids it
