"""The source stays readable in one sitting: no module of the distribution over 450 lines,
no Python function over 80 (numba kernels aside: splitting one costs a compiled call)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("steamtemp_gym", "baselines", "agents")
MAX_MODULE_LINES = 450
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


@pytest.mark.parametrize("package", PACKAGES)
def test_no_module_over_the_line_limit(package):
    long = [(p.relative_to(ROOT).as_posix(), n) for p in _modules(package)
            if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES]  # fmt: skip
    assert not long, f"modules over {MAX_MODULE_LINES} lines: {long}"


@pytest.mark.parametrize("package", PACKAGES)
def test_no_python_function_over_the_line_limit(package):
    long = [(f"{p.relative_to(ROOT).as_posix()}:{node.lineno}", node.name, n)
            for p in _modules(package) for node in ast.walk(ast.parse(p.read_bytes()))
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and not _compiled(node)
            and (n := node.end_lineno - node.lineno + 1) > MAX_FUNCTION_LINES]  # fmt: skip
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines: {long}"
