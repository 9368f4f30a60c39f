"""A core whose rows each simulate a plant of their own, drawn at every reset: the
``plant_randomization`` option of SteamTempEnv and the native vector env.

At a reset of row b, after the scenario and noise key are drawn as always, the row's
plant is drawn from the key (steamtemp_gym/plants/perturb.py: one factor per parameter
group over the env's own parameters, redrawn until the plant holds the episode's start),
so an episode's plant, like its scenario and noise, depends on its seed alone: the vector
env's row i is the single env seeded ``seed + i``, bit for bit, plant included. Without
the option the envs use the plain Core, untouched.

Cost: the draw builds a plant (its packing and calibration) at each reset. The step of a
single env is the plain Core's (the row's parameter vector is swapped in at the reset);
a vector env steps its rows' plants one run of rows of one plant at a time (one compiled
call per row of a plant of its own, one for the rows a planner fanned out from one row;
no threads) and runs the rest of the step batched as always.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from steamtemp_gym._jit import entry_point
from steamtemp_gym.envs.actions import non_finite_action
from steamtemp_gym.envs.core import Core
from steamtemp_gym.envs.kernels import advance, to_commands
from steamtemp_gym.plants import perturb
from steamtemp_gym.plants.base import Plant
from steamtemp_gym.rewards import RewardConfig


class PlantRowsCore(Core):
    """Core over B rows, row b simulating ``plants[b]``, drawn at each of its resets.

    Args:
        plant: The env's plant (its ``params`` option): the base of the draws.
        batch: Number of rows.
        reward_cfg: Reward weights.
        ranges: Factor range per parameter group (perturb.parse).
        base: The env's parameter overrides (``params``) the factors multiply.

    Attributes:
        plants: The plant of each row (the env's plant until the row's first reset).
        factors: The group factors of each row's plant (empty until its first reset).
    """

    def __init__(
        self,
        plant: Plant,
        batch: int,
        reward_cfg: RewardConfig,
        ranges: dict[str, tuple[float, float]],
        base: Mapping[str, Any],
    ) -> None:
        super().__init__(plant, batch, reward_cfg)
        self.ranges = dict(ranges)
        self.base = dict(base)
        self.plants: list[Plant] = [plant] * batch
        self.factors: list[dict[str, float]] = [{} for _ in range(batch)]
        self._block_args: list[tuple] | None = None
        self._row_entries: tuple | None = None
        if batch > 1:
            self.step = self._step_rows  # type: ignore[method-assign]

    def _blocks(self) -> list[tuple]:
        """The plant kernel's arguments for each run of consecutive rows that simulate one
        plant object (views of the core's arrays): rows fanned out from one row (a planner's
        copies) step in one call, rows of plants of their own one at a time."""
        out, first = [], 0
        for b in range(1, self.B + 1):
            if b == self.B or self.plants[b] is not self.plants[first]:
                r = slice(first, b)
                out.append(self.plants[first].step_args(self.X[r], self.U[r], self.D[r], self.Z[r]))
                first = b
        return out

    def row_plant(self, b: int) -> Plant:
        return self.plants[b]

    def set_plant(self, b: int, plant: Plant, factors: Mapping[str, float] | None = None) -> None:
        """Make row b simulate ``plant`` (of the core's plant class); its state is not
        touched."""
        self.plants[b] = plant
        self.factors[b] = dict(factors or {})
        self._block_args = None
        if self.B == 1 and self._plant_args is not None:  # Core.step runs this row's plant
            self._plant_args = plant.step_args(self.X, self.U, self.D, self.Z)

    def episode_plant(self, scenario: Any, key: int) -> tuple[Plant, dict[str, float]]:
        """(plant, factors) drawn from ``key`` (plants/perturb.py) for an episode of
        ``scenario``, after the start check of Core.episode_plant.

        Raises:
            ValueError: the env's own plant cannot hold the scenario's start, or no draw
                can (perturb.draw_plant).
        """
        super().episode_plant(scenario, key)
        return perturb.draw_plant(
            self.plant.id, self.base, self.ranges, key, lambda p: self.start_fits(scenario, p)
        )

    def _start_row(
        self, b: int, scenario: Any, key: int, drawn: tuple[Plant, dict[str, float]]
    ) -> None:
        self.set_plant(b, *drawn)
        super()._start_row(b, scenario, key, drawn)

    def _step_rows(self, A: Any) -> None:
        """Core.step for rows of different plants: the plant kernel on each run of rows of
        one plant (:meth:`_blocks`), then the rest of the step over every row."""
        if not to_commands(A, self.U):
            raise non_finite_action(A)
        blocks = self._block_args
        if blocks is None:
            blocks = self._block_args = self._blocks()
        entries = self._row_entries
        if entries is None:
            entries = self._row_entries = (
                entry_point(self.plant.kernel(), blocks[0]),
                entry_point(advance, (self.state,)),
            )
        kernel = entries[0]
        for args in blocks:
            kernel(*args)
        entries[1](self.state)

    def __getstate__(self) -> dict:
        """As Core's, without the per-block kernel arguments (views of the row arrays, made
        again at the next step over the copied arrays) and the bound step."""
        state = super().__getstate__()
        state.update(_row_entries=None, _block_args=None)
        state.pop("step", None)
        return state

    def __setstate__(self, state: dict) -> None:
        super().__setstate__(state)
        if self.B > 1:
            self.step = self._step_rows  # type: ignore[method-assign]
