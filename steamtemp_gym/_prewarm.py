"""Compile a plant's step kernels in a helper process while this process calibrates it.

On an empty cache the first ``gym.make`` + ``reset`` + ``step`` of a plant compiles 40-70
kernels, 10-35 s on one core (benchmarks/cold_start.py). About half of that is the
calibration and the steady state, which need the plant's numbers and run here; the
other half is the step path (the plant's integrator step, the env's reset and step
kernels), which needs only the argument types. :func:`start`, called by
``plants.make``, starts a helper process (``python -m steamtemp_gym._prewarm
module:Class``) that compiles the step path from the arguments of a skeleton plant
(:meth:`Plant.skeleton`: nothing calibrated) and a one-row env core
(:meth:`Core.compile_calls`), and leaves it in the on-disk cache. This process meanwhile
calibrates; :meth:`Plant.step` calls :func:`wait` before the first step, so that the
helper's kernels load from the cache instead of compiling a second time.

The helper runs only if the cache folder is writable and holds no marker of an earlier
helper for the class (``prewarm/<Class>``), at least two CPUs are available, and
``$STEAMTEMP_GYM_PREWARM`` is not ``0``. Nothing depends on it: a kernel it did not
compile (it failed, was stopped, or a type differs) compiles in this process as before.
Both processes may compile a shared kernel (a steam-table lookup) at once. Numba's cache
stays consistent when they compile it for the same types, as here: the kernels this
process compiles meanwhile (calibration, steady state) take one signature each, and
the helper's ``to_commands``, compiled for two action dtypes, runs here only after a
reset, hence after :func:`wait`.
"""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import time
from pathlib import Path

log = logging.getLogger("steamtemp_gym")

#: the longest this process waits for a helper before going on without it (s)
TIMEOUT_S = 300.0
#: a helper's lock older than this is taken to be left by a process that died (s)
STALE_S = 600.0
_DIR = "prewarm"

#: class path -> running helper; non-empty while a helper may still be compiling
pending: dict[str, subprocess.Popen] = {}
_started: set[str] = set()


def _cpus() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _folder() -> Path:
    import numba

    return Path(numba.config.CACHE_DIR) / _DIR


def enabled() -> bool:
    """Whether helpers may run here (the environment variable and the CPUs)."""
    return os.environ.get("STEAMTEMP_GYM_PREWARM", "1") != "0" and _cpus() >= 2


def start(cls: type) -> None:
    """Start the compile helper of plant class ``cls`` unless it is not needed (above)."""
    path = f"{cls.__module__}:{cls.__qualname__}"
    if path in _started or not enabled():
        return
    _started.add(path)
    folder = _folder()
    done, lock = folder / cls.__qualname__, folder / f"{cls.__qualname__}.lock"
    try:
        if done.exists():
            return
        folder.mkdir(parents=True, exist_ok=True)
        if lock.exists() and time.time() - lock.stat().st_mtime < STALE_S:
            return  # another process's helper is at it
        lock.touch()
    except OSError:  # a read-only cache: nothing would be kept
        return
    try:
        pending[path] = subprocess.Popen(
            [sys.executable, "-m", "steamtemp_gym._prewarm", path],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            env=dict(os.environ, STEAMTEMP_GYM_PREWARM="0"),
        )  # fmt: skip
    except OSError as exc:  # no interpreter to start (embedded Python, ...)
        log.debug("steamtemp_gym: no compile helper: %s", exc)
        lock.unlink(missing_ok=True)


def wait() -> None:
    """Wait for the running helpers (at most :data:`TIMEOUT_S` each; then stop them)."""
    while pending:
        path, proc = pending.popitem()
        try:
            proc.wait(timeout=TIMEOUT_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
            (_folder() / f"{path.split(':')[1]}.lock").unlink(missing_ok=True)
        if proc.returncode:
            log.debug("steamtemp_gym: compile helper of %s exited with %s", path,
                      proc.returncode)  # fmt: skip


def compile_step_path(cls: type) -> int:
    """Compile the step path of plant class ``cls`` from argument types; the number of
    kernels compiled (or loaded from the cache)."""
    from numba import typeof

    from steamtemp_gym.envs.core import Core
    from steamtemp_gym.rewards import RewardConfig

    core = Core(cls.skeleton(), 1, RewardConfig())
    for kernel, args in core.compile_calls():
        kernel.compile(tuple(typeof(a) for a in args))
    return len(core.compile_calls())


def main(path: str) -> None:
    import importlib

    import steamtemp_gym  # noqa: F401  (points numba at the cache folder)

    module, name = path.split(":")
    cls = getattr(importlib.import_module(module), name)
    folder = _folder()
    try:
        compile_step_path(cls)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / name).touch()
    finally:
        (folder / f"{name}.lock").unlink(missing_ok=True)


if __name__ == "__main__":
    main(sys.argv[1])
