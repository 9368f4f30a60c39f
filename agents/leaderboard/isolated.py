"""A policy that is not shipped with the benchmark (a factory ``module:callable``, a trained
agent's files, a baseline registered by an ``--import`` module) runs in a process of its
own: :class:`PolicyProcess`.

That process builds the policy with its factory on a *commissioning env* of its own, made
as the evaluation env is (the same id, scenario and number of rows, the nominal plant), and
answers ``reset`` and ``predict`` over a pipe. The evaluation env, its reward weights and
its scenario stay in the leaderboard's process, out of the policy's reach; the return and
the metrics are computed there from the trajectory it stepped. Whatever the policy does (an
exception, ``SystemExit``, ``KeyboardInterrupt``, ending its process, hanging) fails its
episodes (:class:`PolicyFailed`), never the run: a call that does not answer within the
episode's time (``--episode-timeout``) ends the process (:class:`PolicyTimeout`). Ctrl-C
and SIGTERM stop the leaderboard, and the policy's process ends with it.

The actions cross the pipe pickled, bit for bit: a policy scores the same here as in the
leaderboard's own process (tests/test_leaderboard_isolation.py). The leaderboard unpickles
an answer with :class:`_AnswerUnpickler`, which builds numbers, strings, containers and
numpy arrays only: an answer that would run code in the leaderboard's process when
unpickled (an object whose ``__reduce__`` names ``sys.exit`` or ``exec``) fails the
policy's episodes instead, and so does an answer that holds more than :data:`ANSWER_ITEMS`
numbers once every reference to a shared object is counted (a few bytes of pickle can
stand for gigabytes of floats).
"""

from __future__ import annotations

import importlib
import io
import os
import pickle
import signal
import sys
import threading
import time
import traceback
from typing import Any

import gymnasium as gym
import numpy as np

from agents.leaderboard import sandbox
from steamtemp_gym.testing import guard

#: The environment variable naming the run's output directory, which a policy's process
#: sees read-only (agents/leaderboard/sandbox.py); the leaderboard sets it at its start.
OUT_ENV = "STEAMTEMP_LEADERBOARD_OUT"
#: The largest answer a policy's process may send (bytes, pickled): an action is a few
#: numbers per row, a recurrent policy's state a few arrays of them.
ANSWER_BYTES = 64 * 2**20
#: The most numbers, strings and containers an answer may hold once unpickled, every
#: reference counted: a pickle names an object once and refers to it again by a few bytes,
#: so a small answer can stand for a huge one when the leaderboard converts it to arrays.
ANSWER_ITEMS = 2**23
#: How often a child process checks that the process that started it is alive (s).
PARENT_POLL_S = 0.5


class PolicyFailed(Exception):
    """The policy raised in its process (``SystemExit`` and ``KeyboardInterrupt`` included),
    its process ended, or it did not answer in time. ``remote_traceback``: the traceback in
    the policy's process."""

    def __init__(self, message: str, remote_traceback: str = "") -> None:
        super().__init__(message)
        self.remote_traceback = remote_traceback


class PolicyTimeout(PolicyFailed):
    """The policy did not answer within its episodes' time (``--episode-timeout``)."""


#: The only globals an answer from a policy's process may name when unpickled: what numpy
#: arrays, scalars and dtypes pickle to (numpy 1 and 2 module names).
_ANSWER_GLOBALS = frozenset(
    [
        (m, n)
        for m in ("numpy.core.multiarray", "numpy._core.multiarray")
        for n in ("_reconstruct", "scalar")
    ]
    + [(m, "_frombuffer") for m in ("numpy.core.numeric", "numpy._core.numeric")]
    + [("numpy", "ndarray"), ("numpy", "dtype")]
)


class _AnswerUnpickler(pickle.Unpickler):
    """Unpickles numbers, strings, containers and numpy arrays; refuses any other global
    (a class or callable of the policy's choosing would run in this process)."""

    def find_class(self, module: str, name: str) -> Any:
        if (module, name) not in _ANSWER_GLOBALS:
            raise pickle.UnpicklingError(f"it names {module}.{name}")
        return super().find_class(module, name)


def read_answer(data: bytes) -> tuple[str, Any]:
    """A policy process's answer ``("ok", value)`` or ``("error", (message, traceback))``
    from its pickled bytes, built by :class:`_AnswerUnpickler`.

    Raises:
        ValueError: the bytes name another global, do not unpickle, or are not such an
            answer; nothing of the policy's choosing has run.
    """
    try:
        answer = _AnswerUnpickler(io.BytesIO(data)).load()
    except Exception as exc:  # noqa: BLE001 - any malformed pickle
        raise ValueError(
            "the policy's answer cannot cross from its process (numbers, strings, "
            f"containers and numpy arrays only): {exc}"
        ) from None
    if _items(answer, ANSWER_ITEMS) > ANSWER_ITEMS:
        raise ValueError(
            f"the policy's answer holds more than {ANSWER_ITEMS:,} numbers, strings "
            "and containers (references to one object counted each time)"
        )
    ok = isinstance(answer, tuple) and len(answer) == 2 and answer[0] in ("ok", "error")
    if ok and answer[0] == "error":
        v = answer[1]
        ok = isinstance(v, tuple) and len(v) == 2 and all(isinstance(x, str) for x in v)
    if not ok:
        raise ValueError(
            f"the policy's process sent an answer of another form: {type(answer).__name__}"
        )
    return answer


def _children(v: Any) -> list | None:
    """The objects a container holds (a dict's keys and values, an object array's
    elements), or None when ``v`` is not a container."""
    if isinstance(v, dict):
        return [*v.keys(), *v.values()]
    if isinstance(v, list | tuple | set | frozenset):
        return list(v)
    if isinstance(v, np.ndarray) and v.dtype == object:
        return v.ravel().tolist()
    return None


def _items(value: Any, limit: int) -> int:
    """How many numbers, strings and containers ``value`` holds, every reference counted (a
    numeric array's elements too), or just past ``limit`` once that is certain; a cyclic
    answer counts as past it. Each object is visited once, whatever refers to it."""
    sizes: dict[int, int] = {}
    open_: set[int] = set()  # the containers on the walk's current path
    stack: list[tuple[Any, list | None]] = [(value, None)]
    while stack:
        v, kids = stack.pop()
        if kids is not None:  # every child counted: this container's total
            sizes[id(v)] = 1 + sum(sizes.get(id(c), 1) for c in kids)
            open_.discard(id(v))
            if sizes[id(v)] > limit:
                return sizes[id(v)]
            continue
        if id(v) in sizes:
            continue
        if id(v) in open_:
            return limit + 1
        kids = _children(v)
        if kids is None:
            sizes[id(v)] = 1 + (v.size if isinstance(v, np.ndarray) else 0)
            continue
        open_.add(id(v))
        stack.append((v, kids))
        stack.extend((c, None) for c in kids if not isinstance(c, int | float | str | bytes))
    return sizes[id(value)]


def start_method() -> str:
    """fork where available (the child starts with the compiled kernels), but spawn once
    torch is loaded here: a child forked after torch started its thread pools deadlocks in
    its first torch operation. Spawned children load the kernels from the disk cache."""
    import multiprocessing as mp

    fork = "fork" in mp.get_all_start_methods() and "torch" not in sys.modules
    return "fork" if fork else "spawn"


def watch_parent(parent: int) -> None:
    """End this process within :data:`PARENT_POLL_S` of the death of ``parent`` (SIGKILL
    included): a daemon thread."""

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def make_env(env_id: str, scenario: Any, num_envs: int | None = None, **kw: Any) -> Any:
    """The env of a unit: ``gym.make`` (``num_envs`` None) or the native vector env;
    ``scenario`` None: the env's default."""
    if scenario is not None:
        kw["scenario"] = scenario
    if num_envs is None:
        return gym.make(env_id, **kw)
    return gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point", **kw)


class PolicyProcess:
    """The policy ``name`` for ``env_id`` in a process of its own (module docstring).

    Args:
        name: The policy name (agents/specs.py).
        env_id, scenario, num_envs: How the commissioning env is made (:func:`make_env`).
        imports: Modules the process imports first (``--import``).
        timeout: Seconds allowed for one episode (None: no limit); building the policy may
            take one episode's time, and every call after it together ``episodes`` times it.
        episodes: The episodes this policy runs (side by side in a vector env, or in turn).

    Raises:
        PolicyFailed: building the policy failed, or took longer than ``timeout``.
    """

    def __init__(
        self,
        name: str,
        env_id: str,
        scenario: Any,
        num_envs: int | None,
        imports: tuple[str, ...] = (),
        timeout: float | None = None,
        episodes: int = 1,
    ) -> None:
        import multiprocessing as mp

        self.name, self.timeout, self.episodes = name, timeout, episodes
        ctx = mp.get_context(start_method())
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(
            target=_serve,
            name=f"policy {name}",
            daemon=True,
            args=(child, name, env_id, scenario, num_envs, imports, os.getpid()),
        )
        self._proc.start()
        child.close()
        self._deadline = None if timeout is None else time.monotonic() + timeout
        try:
            self._call("build", None)
        except BaseException:
            self.close()
            raise
        if timeout is not None:
            self._deadline = time.monotonic() + timeout * episodes

    def reset(self) -> None:
        self._call("reset", ())

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        return self._call("predict", (observation, state, episode_start, deterministic))

    def _call(self, what: str, args: Any) -> Any:
        """Send a call (``build`` only waits) and its answer; PolicyFailed otherwise."""
        try:
            if what != "build":
                self._conn.send((what, args))
            wait = None if self._deadline is None else max(self._deadline - time.monotonic(), 0)
            if not self._conn.poll(wait):
                self.close()
                limit = self.timeout if what == "build" else self.timeout * self.episodes
                n = "" if what == "build" or self.episodes == 1 else f" ({self.episodes} episodes)"
                raise PolicyTimeout(
                    f"timed out: the policy did not answer its {what} within "
                    f"{limit:g} s{n} (--episode-timeout {self.timeout:g}); its "
                    "process was ended"
                )
            data = self._conn.recv_bytes(ANSWER_BYTES)
        except OSError as exc:
            if self._proc.is_alive() and "bad message length" in str(exc):
                self.close()
                raise PolicyFailed(
                    f"the policy's answer to its {what} is larger than "
                    f"{ANSWER_BYTES // 2**20} MiB: refused before it is read "
                    "(an action is a few numbers per row)"
                ) from None
            self._proc.join(5)
            code = self._proc.exitcode
            self.close()
            raise PolicyFailed(
                f"the policy's process ended (exit code {code}) during its {what}"
            ) from None
        except EOFError:
            self._proc.join(5)
            code = self._proc.exitcode
            self.close()
            raise PolicyFailed(
                f"the policy's process ended (exit code {code}) during its {what}"
            ) from None
        try:
            kind, value = read_answer(data)
        except ValueError as exc:
            self.close()
            raise PolicyFailed(f"{exc} (in its {what})") from None
        if kind == "error":
            self.close()
            raise PolicyFailed(*value)
        return value

    def close(self) -> None:
        """End the process (idempotent)."""
        if self._proc.is_alive():
            self._proc.kill()
            self._proc.join(5)
        self._conn.close()

    def __enter__(self) -> PolicyProcess:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _error(exc: BaseException, during: str) -> tuple[str, str]:
    tb = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    return f"{guard.describe(exc, 'the policy')} (in its {during})", tb[-4000:]


def _serve(
    conn: Any,
    name: str,
    env_id: str,
    scenario: Any,
    num_envs: int | None,
    imports: tuple[str, ...],
    parent: int,
) -> None:
    """The policy's process: build the policy, then answer calls until the pipe closes or
    the policy fails (its failure is sent, then the process ends)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C stops the leaderboard, which ends this
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    out = os.environ.get(OUT_ENV)
    # from here on in the walls, or as near as the OS allows; the watch of the leaderboard
    # stays outside them (a thread started before would keep the process out)
    sandbox.enter((out,) if out else (), parent, lambda: watch_parent(parent), PARENT_POLL_S)
    from agents import specs

    try:
        for module in imports:
            importlib.import_module(module)
        policy = specs.parse(name).make(env_id, make_env(env_id, scenario, num_envs))
        answer: tuple[str, Any] = ("ok", None)
    except BaseException as exc:  # noqa: BLE001 - the policy's own failure, SystemExit too
        answer = ("error", _error(exc, "factory"))
    while True:
        try:
            conn.send(answer)
        except BaseException as exc:  # noqa: BLE001 - an answer that cannot be sent
            conn.send(("error", _error(exc, "answer (it cannot be pickled)")))
            return
        if answer[0] == "error":
            return
        try:
            what, args = conn.recv()
        except (EOFError, OSError):
            return
        try:
            answer = ("ok", policy.reset() if what == "reset" else policy.predict(*args))
        except BaseException as exc:  # noqa: BLE001 - the policy's own failure
            answer = ("error", _error(exc, what))
