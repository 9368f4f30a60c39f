"""Safety-Gymnasium's step signature for the envs, for safe-RL libraries that expect it
(OmniSafe and code written for Safety-Gymnasium; docs/safe_rl.md).

:class:`SafetyStep` wraps a ``gym.make`` env and :class:`SafetyVectorStep` the native vector
env; their ``step`` returns ``(obs, reward, cost, terminated, truncated, info)``, the cost
being ``info["cost"]`` (envs/cost.py), and ``reset`` returns ``(obs, info)`` as before.
Nothing else changes: the trajectory, the reward and the info are the env's.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv

from steamtemp_gym.envs.steam_temp_env import SteamTempEnv
from steamtemp_gym.envs.vector_env import SteamTempVectorEnv


class SafetyStep(gym.Wrapper):
    """A steamtemp env whose ``step`` returns Safety-Gymnasium's six-tuple
    ``(obs, reward, cost, terminated, truncated, info)`` (``cost``: ``info["cost"]``, a
    float). ``cost_limit`` is the current episode's default budget.

    Args:
        env: A ``gym.make`` env of this package (other wrappers around it allowed).

    Raises:
        ValueError: ``env`` is not a Gymnasium env (e.g. a vector env: use
            :class:`SafetyVectorStep`) or not one of this package's.
    """

    def __init__(self, env: gym.Env) -> None:
        if isinstance(env, VectorEnv) or not isinstance(env, gym.Env):
            raise ValueError(
                f"SafetyStep wraps a gym.make env, got {type(env).__name__}"
                + ("; use SafetyVectorStep for a vector env" if isinstance(env, VectorEnv) else "")
            )
        if not isinstance(env.unwrapped, SteamTempEnv):
            raise ValueError(
                f"SafetyStep needs an env of steamtemp_gym (its info carries the cost), got "
                f"{type(env.unwrapped).__name__}"
            )
        super().__init__(env)

    @property
    def cost_limit(self) -> float:
        """The default limit of the current episode's summed cost (envs/cost.py)."""
        return self.env.unwrapped.cost_limit

    def step(self, action: Any) -> tuple[Any, float, float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, info["cost"], terminated, truncated, info


class SafetyVectorStep(gym.vector.VectorWrapper):
    """The native vector env with Safety-Gymnasium's six-tuple ``step``: ``(obs, rewards,
    costs, terminated, truncated, info)``, ``costs`` of shape (num_envs,).

    Each row's cost is that of the step its reward is: ``info["cost"]``, except that with
    ``autoreset_mode`` SAME_STEP a row that just ended reports the new episode's reset in
    ``info`` and its last step's cost in ``info["final_info"]["cost"]``, which ``costs``
    takes (a NEXT_STEP reset step costs 0, as its reward is 0). ``cost_limit`` is each
    row's default budget for its current episode.

    Args:
        env: A native vector env of this package (``gym.make_vec(id,
            vectorization_mode="vector_entry_point")``).

    Raises:
        ValueError: ``env`` is not this package's native vector env.
    """

    def __init__(self, env: VectorEnv) -> None:
        if not isinstance(env, VectorEnv) or not isinstance(env.unwrapped, SteamTempVectorEnv):
            raise ValueError(
                "SafetyVectorStep wraps the native vector env of steamtemp_gym (gym.make_vec(id, "
                f"vectorization_mode='vector_entry_point')), got {type(env).__name__}"
            )
        super().__init__(env)

    @property
    def cost_limit(self) -> np.ndarray:
        """Each sub-env's default limit of its current episode's summed cost."""
        return self.env.unwrapped.cost_limit

    def step(self, actions: Any) -> tuple[Any, Any, np.ndarray, Any, Any, dict[str, Any]]:
        obs, rewards, terminated, truncated, info = self.env.step(actions)
        costs = np.array(info["cost"], dtype=np.float64)
        if self.env.unwrapped.autoreset_mode == AutoresetMode.SAME_STEP and "final_info" in info:
            ended = info["_final_info"]
            costs[ended] = info["final_info"]["cost"][ended]
        return obs, rewards, costs, terminated, truncated, info
