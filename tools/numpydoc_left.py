"""Count the core's public functions whose docstring has no numpydoc Parameters section.

``python3 tools/numpydoc_left.py [DIR] [-v] [--returns]`` (DIR defaults to
mt_accuracy_ros/core): per file, then the total; ``-v`` lists each function. Public:
module-level functions and public classes' methods whose names do not start with ``_``
and that take an argument besides ``self`` / ``cls``. ``--returns`` also counts one
whose docstring has no Returns (or Yields) section although it returns a value.
"""
from __future__ import annotations

import ast
import sys
from collections import Counter
from pathlib import Path

DEFS = (ast.FunctionDef, ast.AsyncFunctionDef)


def arguments(function: ast.FunctionDef) -> list[str]:
    """The names ``function`` takes, ``self`` and ``cls`` left out."""
    spec = function.args
    names = [a.arg for a in spec.posonlyargs + spec.args + spec.kwonlyargs]
    names += [a.arg for a in (spec.vararg, spec.kwarg) if a is not None]
    return [name for name in names if name not in ("self", "cls")]


def returns_value(function: ast.FunctionDef) -> bool:
    """Whether ``function`` itself (not a function or lambda inside it) returns a value
    other than a bare ``None``."""
    todo = list(function.body)
    while todo:
        node = todo.pop()
        if isinstance(node, (*DEFS, ast.Lambda, ast.ClassDef)):
            continue
        if isinstance(node, ast.Return) and node.value is not None and not (
                isinstance(node.value, ast.Constant) and node.value.value is None):
            return True
        todo.extend(ast.iter_child_nodes(node))
    return False


def lacks(function: ast.FunctionDef, returns: bool) -> bool:
    """No Parameters section; with ``returns``, or no Returns / Yields section for a
    function that returns a value."""
    doc = ast.get_docstring(function) or ""
    if "Parameters\n" not in doc:
        return True
    return returns and returns_value(function) and \
        "Returns\n" not in doc and "Yields\n" not in doc


def public_functions(tree: ast.Module):
    """(qualified name, node) of each public function and public class's method."""
    for node in tree.body:
        if isinstance(node, DEFS) and not node.name.startswith("_"):
            yield node.name, node
        elif isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
            for sub in node.body:
                if isinstance(sub, DEFS) and not sub.name.startswith("_"):
                    yield f"{node.name}.{sub.name}", sub


def main(argv: list[str]) -> int:
    """Print the count per file and in all; return 0."""
    paths = [a for a in argv if a not in ("-v", "--returns")]
    root = Path(paths[0] if paths else "mt_accuracy_ros/core")
    per_file, total, missing = Counter(), 0, []
    for path in sorted(root.rglob("*.py")):
        for name, function in public_functions(ast.parse(path.read_text())):
            if not arguments(function):
                continue
            total += 1
            if lacks(function, "--returns" in argv):
                per_file[str(path)] += 1
                missing.append(f"{path}:{function.lineno} {name}")
    if "-v" in argv:
        print("\n".join(missing))
    for path, count in sorted(per_file.items()):
        print(f"{count:4d} {path}")
    print(f"{len(missing)} of {total} public functions with arguments lack a Parameters "
          "section" + (" (or Returns)" if "--returns" in argv else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
