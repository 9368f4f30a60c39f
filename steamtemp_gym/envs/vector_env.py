"""SteamTempVectorEnv: the native batched env (``gym.make_vec(..., vectorization_mode=
"vector_entry_point")``), the same Core as SteamTempEnv over B rows.

Sub-env i behaves exactly as a SteamTempEnv seeded with ``seed + i``: its own
generator draws its scenarios and noise keys, the plant kernel and the reward
are the same compiled code. Autoreset follows Gymnasium's default NEXT_STEP
mode: the step after an episode ends resets that sub-env (reward 0, action
ignored). ``info`` holds arrays of shape (num_envs,) with ``_key`` masks.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from steamtemp_gym.envs import options as opts
from steamtemp_gym.envs.core import Core, check_action
from steamtemp_gym.envs.steam_temp_env import draw_episode, spaces


class SteamTempVectorEnv(VectorEnv):
    """B copies of one plant stepped by one compiled kernel call."""

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, plant_id: str, num_envs: int = 1, **options: Any) -> None:
        if not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
        if options.get("render_mode") is not None:
            raise ValueError("the native vector env does not render; use SteamTempEnv")
        plant, self._scenario_spec, reward_cfg, _ = opts.build(plant_id, options)
        self._params_overrides = dict(options.get("params") or {})
        self.plant = plant
        self.num_envs = int(num_envs)
        self.core = Core(plant, self.num_envs, reward_cfg)
        self.signals = self.core.signals
        self.single_observation_space, self.single_action_space = spaces(self.core)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._rngs = [seeding.np_random(None)[0] for _ in range(self.num_envs)]
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._shape = (self.num_envs, plant.n_u)
        self._started = False

    def _reset_rows(self, rows) -> None:
        for b in rows:
            scenario, key = draw_episode(
                self._rngs[b], self._scenario_spec, self.plant.default_duration_s
            )
            self.core.reset_row(int(b), scenario, key)

    def reset(self, *, seed: int | list[int] | None = None, options: dict | None = None):
        if options:
            raise ValueError(f"reset() takes no options, got {sorted(options)}")
        if seed is not None:
            seeds = (
                [seed + i for i in range(self.num_envs)] if isinstance(seed, int) else list(seed)
            )
            if len(seeds) != self.num_envs:
                raise ValueError(f"expected {self.num_envs} seeds, got {len(seeds)}")
            self._rngs = [seeding.np_random(s)[0] for s in seeds]
        self._reset_rows(range(self.num_envs))
        self._autoreset[:] = False
        self._started = True
        return self.core.obs.copy(), self._info()

    def step(self, actions):
        if not self._started:
            raise RuntimeError("call reset() before step()")
        self.core.step(check_action(actions, self._shape))
        rewards = self.core.out[:, 0].copy()
        terminated = self.core.out[:, 1] > 0.5
        truncated = self.core.out[:, 2] > 0.5
        done_before = np.flatnonzero(self._autoreset)
        if done_before.size:
            self._reset_rows(done_before)
            rewards[done_before] = 0.0
            terminated[done_before] = False
            truncated[done_before] = False
        self._autoreset = terminated | truncated
        return self.core.obs.copy(), rewards, terminated, truncated, self._info()

    def _info(self) -> dict[str, Any]:
        info = self.core.info_columns()
        mask = np.ones(self.num_envs, dtype=bool)
        for k in list(info):
            info["_" + k] = mask
        return info

    def close_extras(self, **kwargs: Any) -> None:
        pass
