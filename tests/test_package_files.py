"""What a user of a Gymnasium/SB3 package expects to find: the licence, changelog and
citation files consistent with pyproject.toml, ``py.typed`` markers shipped, the
``python -m steamtemp_gym`` listing (cheap: it compiles nothing), the pytest plugin that
registers the ``slow`` mark, and the ``steamtemp_gym:`` form of ``gym.make``."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import pytest
import yaml

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    tomllib = pytest.importorskip("tomli")

import baselines
import steamtemp_gym
from steamtemp_gym import catalog
from steamtemp_gym.scenarios import heldout
from steamtemp_gym.testing import POLICY_CHECKS

pytest_plugins = ["pytester"]

ROOT = Path(__file__).parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
VERSION = PYPROJECT["project"]["version"]


def test_license_citation_and_changelog_agree_with_pyproject():
    assert PYPROJECT["project"]["license"] == "MIT"  # an SPDX expression (PEP 639)
    assert PYPROJECT["project"]["license-files"] == ["LICENSE"]
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License") and "steamtemp_gym contributors" in text
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and cff["license"] == "MIT"
    assert str(cff["version"]) == VERSION and cff["authors"] and cff["title"] and cff["message"]
    log = (ROOT / "CHANGELOG.md").read_text()
    assert "## [Unreleased]" in log and f"## [{VERSION}]" in log
    assert not re.search(r"\b(issue|session|round) \d+", log, re.I)


def test_changelog_dates_are_commit_dates():
    done = subprocess.run(
        ["git", "log", "--format=%ad", "--date=short"], cwd=ROOT, capture_output=True, text=True
    )
    if done.returncode != 0:
        pytest.skip("not a git checkout")
    commits = set(done.stdout.split())
    dates = set(re.findall(r"\d{4}-\d{2}-\d{2}", (ROOT / "CHANGELOG.md").read_text()))
    assert dates and dates <= commits, dates - commits


def test_py_typed_markers_ship():
    data = PYPROJECT["tool"]["setuptools"]["package-data"]
    for package in ("steamtemp_gym", "baselines", "agents"):
        assert (ROOT / package / "py.typed").is_file()
        assert "py.typed" in data[package]


def test_python_m_steamtemp_gym_lists_everything_and_compiles_nothing(tmp_path):
    """In a fresh process with an empty kernel cache: no numba compilation at all."""
    code = (
        "import numba.core.event as ev, runpy, sys\n"
        "class L(ev.Listener):\n"
        "    def on_start(self, e): print('COMPILED', e.data['dispatcher'], file=sys.stderr)\n"
        "    def on_end(self, e): pass\n"
        "ev.register('numba:compile', L())\n"
        "runpy.run_module('steamtemp_gym', run_name='__main__')\n"
    )
    env = {**os.environ, "STEAMTEMP_GYM_CACHE_DIR": str(tmp_path / "cache")}
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert "COMPILED" not in done.stderr and "compiling" not in done.stderr, done.stderr
    out = done.stdout
    own = [i for i in steamtemp_gym.ENV_IDS if catalog.packaged(i)]  # a fresh process's ids
    for name in (
        *own,
        *baselines.NAMES,
        "setpoint_step",
        "setpoint_step_535_545",
        *(heldout.PREFIX + n for n in heldout.NAMES),
        "random",
        "sb3:ppo",
    ):
        assert name in out, name


_CONTRACT = """
from steamtemp_gym.testing import parametrize_with_checks


@parametrize_with_checks(ids=["steamtemp/Cascade300MW-v0"], policies=["cascade_pi"], env=False)
def test_contract(env_id, check):
    check(env_id)
"""


def test_pytest_plugin_registers_the_slow_mark(pytester, monkeypatch):
    monkeypatch.setenv("PYTHONPATH", str(ROOT))  # this source tree in the subprocesses
    assert PYPROJECT["project"]["entry-points"]["pytest11"] == {
        "steamtemp_gym": "steamtemp_gym.testing.pytest_plugin"
    }
    pytester.makepyfile(test_contract=_CONTRACT)
    args = ("--strict-markers", "--collect-only", "-q", "-p", "no:cacheprovider", "-p", "no:xdist")
    without = pytester.runpytest_subprocess(*args, "-p", "no:steamtemp_gym")
    assert without.ret != 0 and "'slow' not found in `markers`" in without.stdout.str()
    from importlib.metadata import entry_points

    installed = any(e.name == "steamtemp_gym" for e in entry_points(group="pytest11"))
    load = () if installed else ("-p", "steamtemp_gym.testing.pytest_plugin")  # else it is
    plugin = pytester.runpytest_subprocess(*args, *load)  # loaded by its entry point
    plugin.stdout.fnmatch_lines(
        ["*cascade_pi-check_completes_every_scenario*", f"{len(POLICY_CHECKS)} tests collected*"]
    )
    assert plugin.ret == 0


def test_make_with_the_module_prefix():
    """``gym.make("steamtemp_gym:<id>")`` (docs/envs/README.md) imports and makes the id."""
    env = gym.make("steamtemp_gym:steamtemp/Cascade300MW-v0")
    assert env.spec.id == "steamtemp/Cascade300MW-v0"
    venv = gym.make_vec(
        "steamtemp_gym:steamtemp/Cascade300MW-v0",
        num_envs=2,
        vectorization_mode="vector_entry_point",
    )
    assert venv.num_envs == 2
