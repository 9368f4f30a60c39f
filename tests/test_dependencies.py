"""The installed dependencies are within pyproject.toml's bounds: above all numba and
llvmlite, bounded above to the versions whose internals the code was checked against
(docs/architecture.md; .ci/oldest runs the suite on the lower bounds)."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import pytest
from packaging.requirements import Requirement

tomllib = pytest.importorskip("tomllib")  # Python >= 3.11

PROJECT = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())["project"]
REQUIREMENTS = [
    Requirement(r) for r in [*PROJECT["dependencies"], *PROJECT["optional-dependencies"]["agents"]]
]


@pytest.mark.parametrize("req", REQUIREMENTS, ids=[r.name for r in REQUIREMENTS])
def test_installed_version_is_within_the_declared_bounds(req):
    try:
        got = version(req.name)
    except PackageNotFoundError:
        pytest.skip(f"{req.name} is not installed (an optional extra)")
    assert req.specifier.contains(got, prereleases=True), (
        f"{req.name} {got} is outside pyproject.toml's {req.specifier}: for numba and "
        "llvmlite, check every reliance of docs/architecture.md on the new version (their "
        "tests) and then move the bound"
    )


def test_numba_and_llvmlite_are_bounded_above():
    for name in ("numba", "llvmlite"):
        (req,) = [r for r in REQUIREMENTS if r.name == name]
        assert any(s.operator == "<" for s in req.specifier), f"{name} has no upper bound"
