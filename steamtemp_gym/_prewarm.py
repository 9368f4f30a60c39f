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
calibrates and solves the steady state; :meth:`Plant.step` calls :func:`wait` before the
first step, which compiles the :data:`SHARED` kernels the helper has not claimed yet and
waits for the rest, so that the helper's kernels load from the cache instead of
compiling a second time.

The helper runs only if the cache folder is writable and holds no marker of an earlier
helper for the class (``prewarm/<Class>``), no other process's helper for it holds its
lock (``prewarm/<Class>.lock``, an advisory ``flock`` the helper holds until it exits: a
helper that dies, even by SIGKILL, releases it at once), at least two CPUs are
available, and ``$STEAMTEMP_GYM_PREWARM`` is not ``0``. Nothing depends on it: a kernel it did not
compile (it failed, was stopped, or a type differs) compiles in this process as before.
Both processes may compile a shared kernel (a steam-table lookup) at once. Numba's cache
stays consistent when they compile it for the same types, as here: every kernel either
of them compiles meanwhile takes a single signature, except ``to_commands`` (one per
action dtype), whose claim covers both, so that one process compiles it.
"""

from __future__ import annotations

import logging
import os
import subprocess
import sys
from pathlib import Path

from steamtemp_gym import _cache
from steamtemp_gym._jit import entry_point

try:
    import fcntl
except ImportError:  # not on a POSIX system: no helper (its lock needs flock)
    fcntl = None

log = logging.getLogger("steamtemp_gym")

#: the longest this process waits for a helper before going on without it (s)
TIMEOUT_S = 300.0
_DIR = "prewarm"
#: kernels of the step path that either process compiles, whichever gets to each first
#: (claimed by a file ``prewarm/<Class>.<kernel>.claim``): this process when it reaches
#: its first step while the helper is still at the plant's step (the physics plants), the
#: helper once it is done with the rest (Cascade300MW, whose step compiles quickly).
#: Balances the two: with the helper compiling them always, it finished 2-3 s after this
#: process reached its first step (SupercriticalFSH 10.2-11.1 s -> 8.0-8.7 s,
#: BensonSubcritical 12.8-14.6 s -> 11.2-12.9 s; interleaved runs)
SHARED = ("observe", "to_commands", "advance")

#: class path -> running helper; non-empty while a helper may still be compiling
pending: dict[str, subprocess.Popen] = {}
_started: set[str] = set()
#: plant class name -> the step-path calls of this process's env core (share)
_shared: dict[str, list] = {}


def _cpus() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _folder() -> Path:
    return _cache.folder().path / _DIR


def _drop_claims(folder: Path, name: str) -> None:
    for claim in folder.glob(f"{name}.*.claim"):
        claim.unlink(missing_ok=True)


def enabled() -> bool:
    """Whether helpers may run here: the environment variable, the CPUs, and an interpreter
    to start (not a frozen application, whose executable is not Python)."""
    return (os.environ.get("STEAMTEMP_GYM_PREWARM", "1") != "0" and _cpus() >= 2
            and bool(sys.executable) and not getattr(sys, "frozen", False)
            and fcntl is not None)  # fmt: skip


def start(cls: type) -> None:
    """Start the compile helper of plant class ``cls`` unless it is not needed (above)."""
    path = _path(cls)
    if path in _started or not enabled():
        return
    _started.add(path)
    where = _cache.folder()
    if where is None or not where.writable:  # a read-only cache: nothing would be kept
        return
    folder = _folder()
    done = folder / cls.__qualname__
    try:
        if done.exists():
            return
        folder.mkdir(parents=True, exist_ok=True)
        lock = os.open(folder / f"{cls.__qualname__}.lock", os.O_CREAT | os.O_RDWR, 0o644)
    except OSError:
        return
    try:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # another process's helper holds it
            return
        _drop_claims(folder, cls.__qualname__)  # left by a stopped helper
        pending[path] = subprocess.Popen(
            [sys.executable, "-m", "steamtemp_gym._prewarm", path, str(lock)],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            env=dict(os.environ, STEAMTEMP_GYM_PREWARM="0"), pass_fds=(lock,),
        )  # fmt: skip
    except OSError as exc:  # no interpreter to start (embedded Python, ...)
        log.debug("steamtemp_gym: no compile helper: %s", exc)
    finally:
        os.close(lock)  # the helper holds the lock (its copy of the descriptor) until it exits


def _path(cls: type) -> str:
    return f"{cls.__module__}:{cls.__qualname__}"


def wait(cls: type) -> None:
    """Compile the :data:`SHARED` kernels of plant class ``cls`` that its helper has not
    claimed, then wait for the helper (at most :data:`TIMEOUT_S`; then stop it). Helpers
    of other classes go on."""
    calls = _shared.pop(cls.__qualname__, None)
    if calls is not None:
        _compile_shared(cls.__qualname__, calls, SHARED)
    path = _path(cls)
    proc = pending.pop(path, None)
    if proc is not None:
        try:
            proc.wait(timeout=TIMEOUT_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        if proc.returncode:
            log.debug("steamtemp_gym: compile helper of %s exited with %s", path,
                      proc.returncode)  # fmt: skip


def part(calls: list, shared: bool) -> list:
    """The calls (kernel, arguments) of :data:`SHARED` kernels, or of the others."""
    return [(k, args) for k, args in calls if (k.py_func.__name__ in SHARED) == shared]


def _compile(calls: list) -> None:
    for kernel, args in calls:
        entry_point(kernel, args)


def _claim(name: str, kernel: str) -> bool:
    """Whether this process takes the shared ``kernel`` of plant class ``name`` (first come)."""
    try:
        os.close(os.open(_folder() / f"{name}.{kernel}.claim", os.O_CREAT | os.O_EXCL))
    except FileExistsError:
        return False
    except OSError:  # cannot tell: compile it (the other may too; same types, harmless)
        pass
    return True


def _compile_shared(name: str, calls: list, order: tuple[str, ...]) -> None:
    """Compile, in ``order``, the shared kernels of ``calls`` nobody has claimed."""
    for kernel in order:
        group = [(k, args) for k, args in calls if k.py_func.__name__ == kernel]
        if group and _claim(name, kernel):
            _compile(group)


def share(core) -> None:
    """While a helper runs, note ``core``'s step path: :func:`wait` compiles the shared
    kernels the helper has not claimed (called by the env core once it is built)."""
    if _path(type(core.plant)) in pending:
        _shared[type(core.plant).__qualname__] = part(core.compile_calls(), shared=True)


def compile_step_path(cls: type) -> None:
    """The helper's work: compile the step path of plant class ``cls`` from argument types,
    the kernels not :data:`SHARED` first, then the shared ones still unclaimed."""
    from steamtemp_gym.envs.core import Core
    from steamtemp_gym.rewards import RewardConfig

    calls = Core(cls.skeleton(), 1, RewardConfig()).compile_calls()
    _compile(part(calls, shared=False))
    _compile_shared(cls.__qualname__, calls, SHARED[::-1])


def main(path: str) -> None:
    """The helper process: compile ``path``'s step path (``module:Class``), then leave the
    class's marker. It holds its lock through the descriptor it inherited."""
    import importlib

    import steamtemp_gym  # noqa: F401  (chooses the cache folder)

    module, name = path.split(":")
    cls = getattr(importlib.import_module(module), name)
    folder = _folder()
    folder.mkdir(parents=True, exist_ok=True)
    try:
        compile_step_path(cls)
        (folder / name).touch()
    finally:
        _drop_claims(folder, name)


if __name__ == "__main__":
    main(sys.argv[1])
