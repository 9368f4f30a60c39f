"""A large batch on every core: the compiled plant steps release the GIL (``nogil``), so
threads run them on disjoint blocks of rows at the same time. Rows are independent
(each row's arithmetic is the same whichever block it falls in), so the result is
bit-identical to one call over the whole batch.

``STEAMTEMP_GYM_THREADS`` sets the number of threads (default: the CPUs this process may
run on); ``1`` turns the threading off, as does :func:`set_threads` (the leaderboard's
worker processes do, since they already fill the cores). Batches below
``MIN_ROWS_PER_THREAD`` rows per thread run in the calling thread: there a thread hand-off
(about 20 µs) costs more than it saves.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numpy as np

#: Fewest rows per thread worth a hand-off (a physics row step takes 2-6 µs).
MIN_ROWS_PER_THREAD = 64
#: Smallest batch that may be split; callers skip run_rows below it (the single env's
#: step pays no threading overhead).
MIN_SPLIT_ROWS = 2 * MIN_ROWS_PER_THREAD

_state: dict[str, object] = {"n": None, "pool": None, "pid": None}


def _default_threads() -> int:
    raw = os.environ.get("STEAMTEMP_GYM_THREADS")
    if raw is not None:
        try:
            n = int(raw)
        except ValueError:
            raise ValueError(
                f"STEAMTEMP_GYM_THREADS must be a positive integer, got {raw!r}"
            ) from None
        if n < 1:
            raise ValueError(f"STEAMTEMP_GYM_THREADS must be a positive integer, got {raw!r}")
        return n
    return usable_cpus()


def usable_cpus() -> int:
    """The CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def n_threads() -> int:
    """Threads a large batch is split over."""
    if _state["n"] is None:
        _state["n"] = _default_threads()
    return int(_state["n"])  # type: ignore[arg-type]


def set_threads(n: int) -> None:
    """Use ``n`` threads from now on (1: every kernel call runs in the calling thread)."""
    if not isinstance(n, (int, np.integer)) or isinstance(n, bool) or n < 1:
        raise ValueError(f"threads must be a positive integer, got {n!r}")
    old = _state["pool"]
    if old is not None and _state["pid"] == os.getpid():
        old.shutdown(wait=False)  # type: ignore[attr-defined]
    _state["n"], _state["pool"] = int(n), None


def _pool() -> ThreadPoolExecutor:
    """The helper threads (n_threads() - 1: the caller runs a block too), made on first use;
    a pool inherited through fork has no threads, so a child makes its own."""
    if _state["pool"] is None or _state["pid"] != os.getpid():
        _state["pool"] = ThreadPoolExecutor(max_workers=max(n_threads() - 1, 1))
        _state["pid"] = os.getpid()
    return _state["pool"]  # type: ignore[return-value]


def run_rows(kernel: Callable, args: tuple, per_row: tuple[int, ...]) -> None:
    """``kernel(*args)`` over every row of a batch. ``per_row`` gives the positions of the
    arguments whose first axis is the batch (the others are common to every row). A large
    batch is split into blocks of rows that threads run at once."""
    n_rows = args[per_row[0]].shape[0]
    n = min(n_threads(), n_rows // MIN_ROWS_PER_THREAD)
    if n <= 1:
        kernel(*args)
        return
    edges = np.linspace(0, n_rows, n + 1).astype(np.int64)

    def block(k: int) -> None:
        s = slice(int(edges[k]), int(edges[k + 1]))
        kernel(*(a[s] if i in per_row else a for i, a in enumerate(args)))

    futures = [_pool().submit(block, k) for k in range(1, n)]
    block(0)
    for f in futures:
        f.result()
