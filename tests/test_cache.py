"""The compile cache: its location, its key, pruning, its size and the compile notice."""

from __future__ import annotations

import logging
import os
import shlex
import shutil
import subprocess
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from numba import njit

import steamtemp_gym
from steamtemp_gym import _cache
from steamtemp_gym.steam import T_ph

CODE = '''"""Module docstring."""


def f(x):
    """Docstring."""
    return x + 1  # a comment
'''


def _tree(tmp_path: Path, text: str) -> Path:
    root = tmp_path / "pkg"
    root.mkdir(exist_ok=True)
    (root / "m.py").write_text(text)
    return root


def test_key_ignores_docstrings_and_comments_but_not_code(tmp_path):
    root = _tree(tmp_path, CODE)
    memo = tmp_path / "memo.json"
    key = _cache._code_digest([root], memo)
    assert len(key) == 16
    edited = CODE.replace("Docstring.", "Another docstring.").replace("a comment", "other")
    _tree(tmp_path, edited)
    assert _cache._code_digest([root], memo) == key
    _tree(tmp_path, CODE.replace("x + 1", "x + 2"))
    assert _cache._code_digest([root], memo) != key


def test_key_memo_is_used_and_survives_a_corrupt_file(tmp_path):
    root = _tree(tmp_path, CODE)
    memo = tmp_path / "memo.json"
    key = _cache._code_digest([root], memo)
    assert key in memo.read_text()
    memo.write_text("{not json")
    assert _cache._code_digest([root], memo) == key


def test_location_from_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("STEAMTEMP_GYM_CACHE_DIR", str(tmp_path / "a"))
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "b"))
    assert _cache.base_dir() == tmp_path / "a"
    monkeypatch.delenv("STEAMTEMP_GYM_CACHE_DIR")
    assert _cache.base_dir() == tmp_path / "b"
    monkeypatch.delenv("NUMBA_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert _cache.base_dir() == tmp_path / "xdg" / "steamtemp_gym"


def test_prune_keeps_recent_and_in_use_versions(tmp_path):
    current = tmp_path / "numba-1.0-current"
    current.mkdir()
    now = time.time()
    ages = {"old1": 3 * 86400, "old2": 2 * 86400, "old3": 86400, "recent": 60.0}
    for name, age in ages.items():
        d = tmp_path / f"numba-0.9-{name}"
        d.mkdir()
        (d / "last_used").touch()
        os.utime(d / "last_used", (now - age, now - age))
    (tmp_path / "unrelated").mkdir()
    _cache._prune(tmp_path, current)
    left = sorted(p.name for p in tmp_path.iterdir())
    # the two most recently used others stay; of the rest, only ones unused for an hour go
    assert left == ["numba-0.9-old3", "numba-0.9-recent", "numba-1.0-current", "unrelated"]


_LOOKUPS = """
import json
from steamtemp_gym.steam import T_ph, h_pT, rho_ph
values = [T_ph(20e6, 3.2e6), rho_ph(20e6, 3.2e6), h_pT(16e6, 800.0), T_ph(1e6, 5e5)]
stats = [(sum(f.stats.cache_hits.values()), sum(f.stats.cache_misses.values()))
         for f in (T_ph, rho_ph, h_pT)]
print(json.dumps([values, stats]))
"""


def test_cached_steam_lookups_read_the_tables_of_the_process_that_loads_them():
    """The IF97 tables are bound to cached machine code by symbol name
    (llvmlite.binding.add_symbol): a new process loading the lookups from the cache, not
    compiling them, gets the values this process computes."""
    import json

    from steamtemp_gym.steam import h_pT, rho_ph

    here = [T_ph(20e6, 3.2e6), rho_ph(20e6, 3.2e6), h_pT(16e6, 800.0), T_ph(1e6, 5e5)]
    out = subprocess.run(
        [sys.executable, "-c", _LOOKUPS], capture_output=True, text=True, check=True
    ).stdout
    values, stats = json.loads(out.strip().splitlines()[-1])
    assert all(hits >= 1 and misses == 0 for hits, misses in stats), stats
    assert values == here
    iapws = pytest.importorskip("iapws")
    ref = iapws.IAPWS97(P=20.0, h=3200.0)
    assert values[0] == pytest.approx(ref.T, abs=1e-3) and values[1] == pytest.approx(
        ref.rho, rel=1e-5
    )


def test_steam_tables_are_not_frozen_into_cached_kernels():
    T_ph(20e6, 3.2e6)
    files = list(Path(steamtemp_gym.CACHE_DIR).rglob("properties.T_ph-*.nbc"))
    assert files, f"no cached T_ph under {steamtemp_gym.CACHE_DIR}"
    # with the 2 MB of tables frozen in, each file was 4.2 MB
    assert max(f.stat().st_size for f in files) < 300_000


def _notices(caplog, module: str, n_compiles: int) -> list[str]:
    """Lines the compile notice logs while ``n_compiles`` fresh kernels of ``module``
    compile back to back."""
    from numba.core import event

    where = Path("/cache/here")
    notice = _cache._CompileNotice(_cache.Folder(where, True, where))
    event.register("numba:compile", notice)
    try:
        with caplog.at_level(logging.WARNING, logger="steamtemp_gym"):
            for k in range(n_compiles):

                def kernel(x, k=float(k)):
                    return x * 2.0 + k

                kernel.__module__ = module
                njit(kernel)(np.float64(1.0))
    finally:
        event.unregister("numba:compile", notice)
    # (the package's own notice, installed at import, may log too: it names another folder)
    return [r.getMessage() for r in caplog.records if "/cache/here" in r.getMessage()]


def test_compile_notice_is_logged_once_per_burst(caplog):
    lines = _notices(caplog, "steamtemp_gym.fake_module", 2)
    assert len(lines) == 1 and "compiling kernels" in lines[0]


def test_compile_notice_ignores_other_packages(caplog):
    assert _notices(caplog, "someone_else", 1) == []


def test_the_package_notice_hears_numbas_compile_events(caplog):
    """numba's event API (experimental) still reaches the listener installed at import: a
    fresh kernel of the package compiling logs the notice naming this version's folder."""
    assert _cache._NOTICE is not None, "numba.core.event is gone: no compile notice"
    _cache._NOTICE.last = -1e9

    def kernel(x):
        return x * 5.0

    kernel.__module__ = "steamtemp_gym.fake_module"
    with caplog.at_level(logging.WARNING, logger="steamtemp_gym"):
        njit(kernel)(np.float64(1.0))
    assert any(
        "compiling kernels" in r.getMessage() and steamtemp_gym.CACHE_DIR.name in r.getMessage()
        for r in caplog.records
    ), [r.getMessage() for r in caplog.records]


def test_notice_in_a_read_only_folder_warns_once():
    where = Path("/read/only")
    notice = _cache._CompileNotice(_cache.Folder(where, False, None))
    ev = type("Ev", (), {"data": {"dispatcher": T_ph}})()
    logger = logging.getLogger("steamtemp_gym")
    records = []
    handler = logging.Handler(logging.INFO)
    handler.emit = records.append
    logger.addHandler(handler)
    level = logger.level
    logger.setLevel(logging.INFO)
    try:
        for _ in range(3):  # three bursts
            notice.last = -1e9
            notice.on_start(ev)
            notice.on_end(ev)
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
    levels = [r.levelno for r in records]
    assert levels == [logging.WARNING, logging.INFO, logging.INFO]
    assert "not writable" in records[0].getMessage() and "/read/only" in records[0].getMessage()


def test_configure_with_unusable_folder_still_imports(monkeypatch, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("STEAMTEMP_GYM_CACHE_DIR", str(blocker))
    monkeypatch.setattr(_cache, "_FOLDER", _cache.folder())
    where = _cache.configure("9.9")  # cannot create the folder: no exception
    assert where.parent == blocker
    assert _cache.folder() == _cache.Folder(where, False, None)  # compile in memory


# ------------------------------------------------------------- numba's own configuration
def test_kernels_defined_after_numba_reloads_its_configuration_cache_in_the_folder(monkeypatch):
    """A NUMBA_* variable changed after import makes numba reload its configuration at the
    next compile, which resets numba.config.CACHE_DIR; kernels defined after that (a
    plant's specialised integrator step, say) still cache in this code version's folder."""
    import numba

    from steamtemp_gym._jit import njit as project_njit

    monkeypatch.setenv("NUMBA_OPT", "2" if os.environ.get("NUMBA_OPT") == "3" else "3")
    numba.njit(lambda x: x + 1)(1)  # numba reloads its configuration here
    assert numba.config.CACHE_DIR == os.environ.get("NUMBA_CACHE_DIR", "")  # numba's own

    def late(x):
        return x * 3.0

    kernel = project_njit(cache=True)(late)
    where = Path(steamtemp_gym.CACHE_DIR)
    assert Path(kernel.stats.cache_path).is_relative_to(where), kernel.stats.cache_path
    assert numba.config.CACHE_DIR == os.environ.get("NUMBA_CACHE_DIR", "")  # left as it was


# ------------------------------------------------------------------ a read-only cache
def _read_only_run(tmp_path: Path, cache: Path, code: str) -> subprocess.CompletedProcess:
    """``code`` in a fresh process that sees ``cache``, the package's sources and a home
    folder read-only (a bind mount in a mount namespace of its own), as in a read-only
    container image with a shared cache."""
    home = tmp_path / "home"
    home.mkdir()
    src = Path(steamtemp_gym.__file__).parent
    if subprocess.run(["unshare", "-rm", "true"], capture_output=True).returncode != 0:
        pytest.skip("needs unshare -rm (a mount namespace) to make folders read-only")
    mounts = " && ".join(f"mount --bind -o ro {d} {d}" for d in (cache, src, home))
    env = dict(
        os.environ,
        STEAMTEMP_GYM_CACHE_DIR=str(cache),
        XDG_CACHE_HOME=str(home),
        HOME=str(home),
        PYTHONPATH=str(src.parent),
    )
    env.pop("NUMBA_CACHE_DIR", None)
    script = f"{mounts} && exec {sys.executable} -c {shlex.quote(code)}"
    return subprocess.run(
        ["unshare", "-rm", "sh", "-c", script], env=env, text=True, capture_output=True, timeout=120
    )


_STEP = """
import gymnasium as gym, steamtemp_gym
env = gym.make("steamtemp/Cascade300MW-v0")
env.reset(seed=0)
env.step(env.action_space.sample())
misses = [k.py_func.__qualname__ for k, _ in env.unwrapped.core.compile_calls()
          if sum(k.stats.cache_misses.values())]
print("misses:", misses)
"""


def test_a_read_only_populated_cache_is_loaded_from(tmp_path):
    """The folder of this code version, filled by this process, copied and made read-only:
    a new process makes and steps Cascade300MW loading every step-path kernel from it,
    compiling nothing (no compile notice) and writing nothing."""
    env = gym.make("steamtemp/Cascade300MW-v0")  # fills this process's folder if need be
    env.reset(seed=0)
    env.step(env.action_space.sample())
    cache = tmp_path / "cache"
    shutil.copytree(steamtemp_gym.CACHE_DIR, cache / Path(steamtemp_gym.CACHE_DIR).name)
    before = sorted(str(p) for p in cache.rglob("*"))
    run = _read_only_run(tmp_path, cache, _STEP)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "misses: []" in run.stdout, run.stdout
    assert "compiling" not in run.stderr, run.stderr
    assert sorted(str(p) for p in cache.rglob("*")) == before


def test_an_empty_read_only_cache_compiles_in_memory_with_one_warning(tmp_path):
    cache = tmp_path / "cache"
    cache.mkdir()
    code = (
        "import numpy as np, steamtemp_gym\n"
        "from steamtemp_gym.rewards import reward, temperature_cost\n"
        "w = np.ones(9)\n"
        "print(temperature_cost(3.0, w), reward(1.0, 0.0, 0.0, 0.0, False, w))"
    )
    run = _read_only_run(tmp_path, cache, code)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.split() == ["14.0", "-2.0"], run.stdout
    lines = [ln for ln in run.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "not kept" in lines[0] and "not writable" in lines[0], lines
    assert str(cache) in lines[0]
    assert list(cache.iterdir()) == []
