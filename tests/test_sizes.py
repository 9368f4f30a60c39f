"""The source stays readable in one sitting: no Python function of the distribution over 80
lines (numba kernels aside: splitting one costs a compiled call)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("steamtemp_gym", "baselines", "agents")
MAX_FUNCTION_LINES = 80


def _modules(package: str) -> list[Path]:
    found = sorted((ROOT / package).rglob("*.py"))
    assert len(found) > 5, f"{package}: only {len(found)} modules found under {ROOT}"
    return found


def _compiled(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    """Whether a decorator compiles it (numba's njit/jit, directly or called)."""
    for d in fn.decorator_list:
        target = d.func if isinstance(d, ast.Call) else d
        name = target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", "")
        if name in {"njit", "jit", "vectorize", "guvectorize"}:
            return True
    return False


def _long_functions(path: Path) -> list[tuple[str, str, int]]:
    """(file:line, name, lines) of every Python function in ``path`` over the limit."""
    long = []
    for node in ast.walk(ast.parse(path.read_bytes())):
        if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) or _compiled(node):
            continue
        n = node.end_lineno - node.lineno + 1
        if n > MAX_FUNCTION_LINES:
            long.append((f"{path.relative_to(ROOT).as_posix()}:{node.lineno}", node.name, n))
    return long


@pytest.mark.parametrize("package", PACKAGES)
def test_no_python_function_over_the_line_limit(package):
    long = [f for path in _modules(package) for f in _long_functions(path)]
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines: {long}"
