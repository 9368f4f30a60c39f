"""The compile cache: its location, its key, pruning, its size and the compile notice."""

from __future__ import annotations

import logging
import os
import time
from pathlib import Path

import numpy as np
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


def test_steam_tables_are_not_frozen_into_cached_kernels():
    T_ph(20e6, 3.2e6)
    files = list(Path(steamtemp_gym.CACHE_DIR).rglob("__init__.T_ph-*.nbc"))
    assert files, f"no cached T_ph under {steamtemp_gym.CACHE_DIR}"
    # with the 2 MB of tables frozen in, each file was 4.2 MB
    assert max(f.stat().st_size for f in files) < 300_000


def _notices(caplog, module: str, n_compiles: int) -> list[str]:
    """Lines the compile notice logs while ``n_compiles`` fresh kernels of ``module``
    compile back to back."""
    from numba.core import event

    notice = _cache._CompileNotice(Path("/cache/here"))
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


def test_configure_with_unusable_folder_still_imports(monkeypatch, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("STEAMTEMP_GYM_CACHE_DIR", str(blocker))
    import numba

    before = numba.config.CACHE_DIR
    try:
        where = _cache.configure("9.9")  # cannot create the folder: no exception
        assert where.parent == blocker
    finally:
        numba.config.CACHE_DIR = before
