"""Where the units of a leaderboard run execute, in batches (agents/leaderboard/episodes.py
``batches``): ``--jobs`` local worker processes (or this process), or one Ray task per
batch (``--backend ray``, agents/ray_backend.py); the rows are appended to the record as
batches finish, with a progress bar on stderr.
"""

from __future__ import annotations

import os
import signal
import sys
import time

from agents import ray_backend
from agents.leaderboard.episodes import Unit, batches, run_units
from agents.leaderboard.isolated import (
    PARENT_POLL_S,  # noqa: F401 - the workers' poll, too
    start_method,
    watch_parent,
)
from agents.leaderboard.plan import Plan
from agents.leaderboard.records import Record


class Progress:
    """A progress bar with ETA over episodes on ``stream`` (the stderr of the moment it is
    made, by default; a line per 10 % when not a tty)."""

    def __init__(self, total: int, stream=None) -> None:
        self.stream = sys.stderr if stream is None else stream
        self.total, self.done = total, 0
        self.t0 = time.time()
        self.tty = self.stream.isatty()
        self.last_pct = -10

    def update(self, n: int) -> None:
        self.done += n
        el = time.time() - self.t0
        eta = el / self.done * (self.total - self.done) if self.done else 0.0
        pct = 100 * self.done / max(self.total, 1)
        bar = "#" * int(pct / 4) + "." * (25 - int(pct / 4))
        text = (
            f"[{bar}] {self.done}/{self.total} episodes {pct:3.0f} %  "
            f"elapsed {_mmss(el)}  ETA {_mmss(eta)}"
        )
        if self.tty:
            end = "\n" if self.done >= self.total else ""
            print("\r" + text, end=end, file=self.stream, flush=True)
        elif pct >= self.last_pct + 10 or self.done >= self.total:
            self.last_pct = pct
            print(text, file=self.stream, flush=True)


def _mmss(s: float) -> str:
    return f"{int(s // 60)}:{int(s % 60):02d}"


def _pool(jobs: int):
    """A process pool: fork where available (workers start with the compiled kernels),
    but spawn once torch is loaded here: a child forked after torch started its thread
    pools deadlocks in its first torch operation (seen in the test suite, loading a PPO
    agent in a worker). Spawned workers load the kernels from the disk cache."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    return ProcessPoolExecutor(
        max_workers=jobs,
        mp_context=mp.get_context(start_method()),
        initializer=_worker_start,
        initargs=(os.getpid(),),
    )


def _worker_start(parent: int) -> None:
    """In a pool worker: SIGTERM ends it (not the handler a forked worker inherits), and it
    ends itself within :data:`PARENT_POLL_S` of its parent's death, SIGKILL included."""
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    watch_parent(parent)


def _local_results(units: list[Unit], jobs: int):
    """(unit, run_unit's result) as their batches finish, in ``jobs`` local processes."""
    work = batches(units)
    if jobs <= 1 or len(work) <= 1:
        for batch in work:
            yield from zip(batch, run_units(batch), strict=True)
        return
    import multiprocessing as mp
    from concurrent.futures import as_completed

    with _pool(jobs) as pool:
        futures = {pool.submit(run_units, b): b for b in work}
        try:
            for fut in as_completed(futures):
                yield from zip(futures[fut], fut.result(), strict=True)
        except BaseException:
            for f in futures:
                f.cancel()
            for worker in mp.active_children():  # the pool's: stop their units now
                worker.terminate()
            raise


def _ray_results(units: list[Unit], jobs: int, address: str | None):
    """(unit, run_unit's result) as their batches finish, each batch a Ray task (one CPU):
    on a new local Ray with ``jobs`` CPUs, or on the cluster at ``address``."""
    for batch, results in ray_backend.results(run_units, batches(units), jobs, address):
        yield from zip(batch, results, strict=True)


def execute(
    plan: Plan,
    units: list[Unit],
    jobs: int,
    record: Record,
    on_trace,
    backend: str = "local",
    address: str | None = None,
) -> int:
    """Run the units (in ``jobs`` processes or as Ray tasks), appending rows as they
    finish. Failed count."""
    progress = Progress(sum(len(u.seeds) for u in units))
    failed = 0
    results = (
        _ray_results(units, jobs, address) if backend == "ray" else _local_results(units, jobs)
    )
    for u, (rows, trace) in results:
        for row in rows:
            record.write(row)
            if row.get("error"):
                failed += 1
                print(
                    f"\nFAILED {u.env_id} {u.spec} {u.policy} seed {row['seed']}: {row['error']}",
                    file=sys.stderr,
                )
        on_trace(u, trace)
        progress.update(len(rows))
    return failed
