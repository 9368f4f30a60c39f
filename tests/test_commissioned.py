"""Commissioning results kept on disk (baselines/commissioned.py): computed once per code
version, read back to the bit, keyed by every argument, and computed as before where the
cache cannot be written."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from baselines import commissioned as memo_module
from baselines.cascade_pi import CascadePI
from baselines.commissioned import commissioned


@pytest.fixture
def cache(monkeypatch, tmp_path):
    """A cache folder of this test's own (the folder is chosen once per process)."""
    monkeypatch.setenv("STEAMTEMP_GYM_CACHE_DIR", str(tmp_path))
    memo_module.folder.cache_clear()
    yield tmp_path
    memo_module.folder.cache_clear()


def _counted():
    calls = []

    @commissioned(maxsize=4)
    def design(env_id: str, gain: float, cls: type | None = None) -> dict:
        calls.append((env_id, gain, cls))
        rng = np.random.default_rng(len(env_id))
        return {"K": rng.standard_normal((3, 3)) * gain, "name": env_id}

    return design, calls


def test_a_result_is_computed_once_and_read_back_to_the_bit(cache):
    design, calls = _counted()
    first = design("plant-a", 0.1)
    assert len(calls) == 1
    design.cache_clear()  # as a new process: only the disk is left
    again = design("plant-a", 0.1)
    assert len(calls) == 1
    assert again["K"].tobytes() == first["K"].tobytes() and again["name"] == "plant-a"
    stored = list(memo_module.folder().glob("*.pkl"))
    assert len(stored) == 1 and stored[0].name.startswith(f"{__name__}.")


def test_every_argument_is_part_of_the_key(cache):
    design, calls = _counted()
    design("plant-a", 0.1)
    design("plant-a", 0.1000000001)
    design("plant-b", 0.1)
    design("plant-a", 0.1, CascadePI)
    design("plant-a", 0.1, cls=CascadePI)
    assert len(calls) == 5
    assert len(list(memo_module.folder().glob("*.pkl"))) == 5


def test_an_argument_without_a_stable_key_is_refused(cache):
    design, calls = _counted()
    with pytest.raises(TypeError, match="cannot be keyed by a frozenset"):
        design("plant-a", frozenset({0.1}))  # hashable, but no stable text
    assert calls == []


def test_a_corrupt_or_partial_file_is_computed_again(cache):
    design, calls = _counted()
    design("plant-a", 0.1)
    (path,) = memo_module.folder().glob("*.pkl")
    path.write_bytes(b"\x80\x05partial")
    design.cache_clear()
    value = design("plant-a", 0.1)
    assert len(calls) == 2 and value["K"].shape == (3, 3)
    assert pickle.loads(path.read_bytes())["K"].tobytes() == value["K"].tobytes()


def _computed_in_each_process(monkeypatch, where) -> None:
    """With the cache at ``where``, which cannot be written: no folder, and a result is
    computed again once the process's own memo is gone."""
    monkeypatch.setenv("STEAMTEMP_GYM_CACHE_DIR", str(where))
    memo_module.folder.cache_clear()
    try:
        design, calls = _counted()
        design("plant-a", 0.1)
        design.cache_clear()
        design("plant-a", 0.1)
        assert memo_module.folder() is None and len(calls) == 2
    finally:
        memo_module.folder.cache_clear()


def _blas_threads() -> dict:
    @commissioned(maxsize=1)
    def design(tag: str) -> int:
        np.linalg.eigvals(np.eye(3))  # BLAS/LAPACK loaded and used
        return max(p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas")

    return design


@pytest.mark.parametrize("where", ["cache", "no cache"])
def test_a_result_is_computed_on_one_blas_thread_whatever_the_caller(monkeypatch, tmp_path, where):
    """The stored result does not depend on the caller's thread pools: the function runs
    on one BLAS thread under a caller on two, with or without the disk cache."""
    monkeypatch.setenv(
        "STEAMTEMP_GYM_CACHE_DIR", str(tmp_path if where == "cache" else tmp_path / "file")
    )
    if where == "no cache":
        (tmp_path / "file").write_text("not a folder")
    memo_module.folder.cache_clear()
    try:
        with threadpool_limits(limits=2, user_api="blas"):
            caller = max(p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas")
            inside = _blas_threads()(where)
        stored = memo_module.folder() is not None
    finally:
        memo_module.folder.cache_clear()
    assert stored == (where == "cache")
    assert caller == 2 and inside == 1


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root writes anywhere")
def test_a_read_only_cache_computes_in_the_process(monkeypatch, tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        _computed_in_each_process(monkeypatch, ro)
    finally:
        ro.chmod(0o700)


def test_an_unwritable_cache_computes_in_the_process(monkeypatch, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    _computed_in_each_process(monkeypatch, blocker)


_CHILD = """
import sys
from baselines.cascade_pi import commissioned_tuning
g = commissioned_tuning("steamtemp/BensonSubcritical-v0", "{}")
sys.stdout.write(f"{g.shape} {g.tobytes().hex()}")
"""


def test_a_second_process_reads_what_the_first_commissioned(tmp_path):
    """Two processes on one cache: the first commissions the SIMC tuning and stores it in
    the folder of this code's version, the second reads the file instead of commissioning
    (shown by a stored value it could not have computed)."""
    env = {**os.environ, "STEAMTEMP_GYM_CACHE_DIR": str(tmp_path)}

    def run() -> list[str]:
        return subprocess.run(
            [sys.executable, "-c", _CHILD], env=env, capture_output=True, text=True, check=True
        ).stdout.split(" ", 2)

    first = run()
    (folder,) = tmp_path.glob("commissioning-*")
    (stored,) = folder.glob("baselines.cascade_pi.commissioned_tuning-*.pkl")
    tuning = pickle.loads(stored.read_bytes())
    assert tuning.tobytes().hex() == first[-1] and tuning.shape[1] == 4  # (loops, 4)
    marked = np.full_like(tuning, 7.0)
    stored.write_bytes(pickle.dumps(marked))
    assert run()[-1] == marked.tobytes().hex()
