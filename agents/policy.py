"""A trained SB3 model as a Policy (baselines/policy.py): it takes the env's raw
observation and carries its own observation pipeline (controller memory, then the
VecNormalize statistics frozen at the end of training) with the memory's state kept per
row across calls; ``reset()`` or ``episode_start`` restarts it. A residual agent adds its
scaled action to ``cascade_pi``'s.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from agents.wrappers import MemoryConfig, MemoryState
from baselines.loops import restart_rows


def normalize_obs(obs: np.ndarray, stats: dict[str, Any] | None) -> np.ndarray:
    """SB3 VecNormalize's observation normalization with frozen ``stats`` (mean, var,
    epsilon, clip_obs), float32 as VecNormalize returns it; obs unchanged for None."""
    if not stats:
        return obs
    z = (obs - np.asarray(stats["mean"])) / np.sqrt(np.asarray(stats["var"]) + stats["epsilon"])
    return np.clip(z, -stats["clip_obs"], stats["clip_obs"]).astype(np.float32)


class AgentPolicy:
    """A trained model with its observation pipeline (module docstring).

    Args:
        model: The SB3 model (anything with SB3's ``predict``).
        env: The env it acts on (observation layout, plant; cascade_pi for a residual).
        memory: Controller-memory options (agents.wrappers.MemoryConfig fields) or None.
        obs_norm: Frozen VecNormalize statistics or None.
        residual_scale: If set, the action is cascade_pi's plus this times the model's.
    """

    #: Batched and unbatched actions agree to this, not bit for bit: torch's float32 matrix
    #: products round differently with the batch size (measured: 1.5e-8 on the PPO zoo).
    #: Read by steamtemp_gym.testing's check_batched_equals_unbatched.
    batch_tolerance = 1e-6

    def __init__(
        self,
        model: Any,
        env: Any,
        memory: dict | None = None,
        obs_norm: dict | None = None,
        residual_scale: float | None = None,
    ) -> None:
        self.model = model
        self.memory = None
        if memory is not None:
            self.memory = MemoryState(env, MemoryConfig.from_kwargs(memory))
        self.obs_norm = obs_norm
        self.residual_scale = residual_scale
        self.base = None
        if residual_scale is not None:
            import baselines

            self.base = baselines.make("cascade_pi", env)
        #: The LSTM state of a recurrent model (sb3-contrib's RecurrentPPO), per row.
        self.recurrent = hasattr(getattr(model, "policy", None), "lstm_actor")
        self._lstm = None
        self._n: int | None = None

    def reset(self) -> None:
        self._n = None
        self._lstm = None
        if self.base is not None:
            self.base.reset()

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        n = obs.shape[0]
        restart = restart_rows(self._n != n, n, episode_start)
        self._n = n
        x = self.memory(obs, restart) if self.memory is not None else obs
        x = normalize_obs(x, self.obs_norm)
        if self.recurrent:  # the model restarts the LSTM state of the restarted rows
            action, self._lstm = self.model.predict(
                x, state=None if restart.all() else self._lstm, episode_start=restart,
                deterministic=deterministic)  # fmt: skip
        else:
            action, _ = self.model.predict(x, deterministic=deterministic)
        action = np.asarray(action, dtype=np.float32).reshape(n, -1)
        if self.base is not None:
            base, _ = self.base.predict(obs, episode_start=restart)
            action = np.clip(base + self.residual_scale * action, -1.0, 1.0).astype(np.float32)
        return (action[0] if np.ndim(observation) == 1 else action), None
