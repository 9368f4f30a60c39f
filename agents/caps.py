"""SAC with CAPS smoothness regularization of the actor (``sac_caps``).

Source: S. Mysore, B. Mabsout, R. Mancuso and K. Saenko, "Regularizing action policies
for smooth control with reinforcement learning", IEEE International Conference on
Robotics and Automation (ICRA), 2021. CAPS adds two terms to the actor's loss, on the
deterministic actions mu(s) of the policy:

    L_T = lambda_T E || mu(s_t) - mu(s_t+1) ||      (temporal: consecutive states)
    L_S = lambda_S E || mu(s) - mu(s~) ||,  s~ ~ N(s, sigma^2)   (spatial: nearby states)

Their gradient joins the actor loss's in each of SAC's actor steps (on a batch of the same
replay buffer, in the normalized observations SAC trains on), so SB3's own ``SAC.train``
runs unchanged. Why: the shipped SAC agents chatter (docs/notes/agents_sac.md).
"""

from __future__ import annotations

from typing import Any

import torch as th
from stable_baselines3 import SAC


class SACCAPS(SAC):
    """SB3's SAC plus the CAPS actor regularization (module docstring).

    Args:
        caps_temporal: lambda_T.
        caps_spatial: lambda_S.
        caps_sigma: Standard deviation of the state perturbation (normalized observation).
        **kwargs: SAC's.
    """

    def __init__(
        self,
        *args: Any,
        caps_temporal: float = 1.0,
        caps_spatial: float = 1.0,
        caps_sigma: float = 0.05,
        **kwargs: Any,
    ) -> None:
        for name, v in (
            ("caps_temporal", caps_temporal),
            ("caps_spatial", caps_spatial),
            ("caps_sigma", caps_sigma),
        ):
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and v >= 0):
                raise ValueError(f"{name} must be a number >= 0, got {v!r}")
        self.caps_temporal = float(caps_temporal)
        self.caps_spatial = float(caps_spatial)
        self.caps_sigma = float(caps_sigma)
        super().__init__(*args, **kwargs)

    def caps_loss(self, obs: th.Tensor, next_obs: th.Tensor) -> th.Tensor:
        """lambda_T L_T + lambda_S L_S on a batch of (s_t, s_t+1)."""
        mu = self.actor(obs, deterministic=True)
        loss = th.zeros((), device=mu.device)
        if self.caps_temporal > 0.0:
            mu_next = self.actor(next_obs, deterministic=True)
            loss = loss + self.caps_temporal * th.linalg.vector_norm(mu - mu_next, dim=1).mean()
        if self.caps_spatial > 0.0:
            near = obs + self.caps_sigma * th.randn_like(obs)
            mu_near = self.actor(near, deterministic=True)
            loss = loss + self.caps_spatial * th.linalg.vector_norm(mu - mu_near, dim=1).mean()
        return loss

    def train(self, gradient_steps: int, batch_size: int = 64) -> None:
        # SB3's SAC.train unchanged, with the CAPS gradient added to the actor's just before
        # each actor step: one joint step on actor loss + CAPS (Adam normalizes each step,
        # so a CAPS step of its own would move the actor as far as SAC's, whatever lambda)
        opt = self.actor.optimizer
        sac_step = opt.step
        caps = []

        def step(*args: Any, **kwargs: Any) -> Any:
            if self.caps_temporal > 0.0 or self.caps_spatial > 0.0:
                data = self.replay_buffer.sample(batch_size, env=self._vec_normalize_env)
                loss = self.caps_loss(data.observations, data.next_observations)
                loss.backward()
                caps.append(loss.item())
            return sac_step(*args, **kwargs)

        opt.step = step
        try:
            super().train(gradient_steps, batch_size)
        finally:
            del opt.step  # the optimizer's own method again
        if caps:
            self.logger.record("train/caps_loss", sum(caps) / len(caps))
