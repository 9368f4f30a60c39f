"""The code is laid out by the formatter and passes the linter: ``ruff format --check`` and
``ruff check`` (line length and rules from pyproject.toml) over the packages, the tests,
scripts and benchmarks. The formatter is switched off (``# fmt: skip``, ``# fmt: off``)
only for a few aligned data tables of the packages (the plants' slot tables in
``layout.py``), and nowhere in the tests, scripts or benchmarks."""

from __future__ import annotations

import io
import subprocess
import sys
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("steamtemp_gym", "baselines", "agents")
OTHERS = ("tests", "scripts", "benchmarks")
#: The most formatter markers the three packages may hold together.
MAX_FMT_SKIPS = 20
MARKERS = {"fmt: skip", "fmt:skip", "fmt: off", "fmt:off"}


def _ruff(*args: str) -> subprocess.CompletedProcess:
    """Run ruff (the [test] extra's) from the project's root, where pyproject.toml is."""
    command = [sys.executable, "-m", "ruff", *args, "--no-cache", *PACKAGES, *OTHERS]
    return subprocess.run(command, cwd=ROOT, capture_output=True, text=True)


@pytest.mark.parametrize("args", [("format", "--check"), ("check",)], ids=["format", "check"])
def test_ruff_passes(args):
    done = _ruff(*args)
    assert done.returncode == 0, f"ruff {' '.join(args)}:\n{done.stdout}{done.stderr}"


def _markers(folder: str) -> list[str]:
    """file:line of every comment in ``folder``'s modules that switches the formatter off,
    alone or among other pragmas (``# noqa: E501  # fmt: skip``)."""
    found = []
    for path in sorted((ROOT / folder).rglob("*.py")):
        for tok in tokenize.generate_tokens(io.StringIO(path.read_text()).readline):
            parts = tok.string.split("#") if tok.type == tokenize.COMMENT else []
            if any(part.strip() in MARKERS for part in parts):
                found.append(f"{path.relative_to(ROOT).as_posix()}:{tok.start[0]}")
    return found


def test_the_formatter_is_switched_off_only_for_a_few_data_tables():
    in_packages = [m for package in PACKAGES for m in _markers(package)]
    assert len(in_packages) <= MAX_FMT_SKIPS, (
        f"{len(in_packages)} formatter markers in {', '.join(PACKAGES)}, at most "
        f"{MAX_FMT_SKIPS} (aligned data tables only): {in_packages}"
    )
    elsewhere = [m for folder in OTHERS for m in _markers(folder)]
    assert not elsewhere, f"formatter markers: {elsewhere}"
