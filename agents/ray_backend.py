"""``--backend ray`` of the CLIs (steamtemp-leaderboard, ``python -m agents.train --zoo``):
a function run on each item as a Ray task of one CPU, on a new local Ray or on an
existing cluster; the results come back as the tasks finish. Needs the ``ray`` extra."""

from __future__ import annotations

import importlib.util
from collections.abc import Callable, Iterable, Iterator
from typing import Any

#: What to install when ray is missing (for argparse errors).
INSTALL = "pip install 'steamtemp-gym[ray]'"


def installed() -> bool:
    """Whether ray can be imported."""
    return importlib.util.find_spec("ray") is not None


def results(
    fn: Callable[[Any], Any], items: Iterable[Any], cpus: int, address: str | None = None
) -> Iterator[tuple[Any, Any]]:
    """``(item, fn(item))`` as each task finishes, every item a Ray task of one CPU: on a
    new local Ray with ``cpus`` CPUs, on the cluster at ``address`` (e.g. ``auto`` or
    ``ray://host:10001``), or on the Ray this process has already started. A task's
    exception is raised here; the tasks still pending are then cancelled."""
    import ray

    if not ray.is_initialized():
        ray.init(
            address=address,
            num_cpus=None if address else cpus,
            include_dashboard=False,
            log_to_driver=False,
            configure_logging=False,
        )
    task = ray.remote(num_cpus=1)(fn)
    pending = {task.remote(x): x for x in items}
    try:
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                yield pending.pop(ref), ray.get(ref)
    except BaseException:
        for ref in pending:
            ray.cancel(ref)
        raise
