"""The clocks of a training run. Its budget (``max_minutes``) is minutes of one core: the CPU
time of the run's process, so that a run on a machine busy with other work trains as much
as one alone (a wall-clock budget would give it what the other work leaves). The wall time
is recorded beside it. A run trains on one core: torch's intra-op threads and the native
vector env's row threads are set to one (``one_core``).
"""

from __future__ import annotations

import time

from steamtemp_gym.plants.threads import set_threads


class RunClock:
    """CPU and wall seconds since the clock was made."""

    def __init__(self) -> None:
        self.cpu0, self.wall0 = time.process_time(), time.monotonic()

    def cpu(self) -> float:
        """CPU seconds of this process since the start: the budget's clock."""
        return time.process_time() - self.cpu0

    def wall(self) -> float:
        """Wall seconds since the start."""
        return time.monotonic() - self.wall0

    def stamp(self) -> dict[str, float]:
        """Both, as a curve point records them (``cpu_s``, ``wall_s``)."""
        return {"cpu_s": self.cpu(), "wall_s": self.wall()}


def one_core() -> None:
    """Run this process's numerical work on one core (torch and the plant's row threads)."""
    import torch

    torch.set_num_threads(1)
    set_threads(1)
