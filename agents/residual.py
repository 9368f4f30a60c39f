"""The base of a residual agent: a classical controller whose action the agent corrects.

A residual agent acts on top of a controller (the arrangement industrial RL deploys: the
conventional loops stay in charge, the agent corrects them). The env receives::

    u = clip(base(obs) + scale * a, -1, 1)

with ``a`` the agent's action in [-1, 1]. Two forms:

- the **observed** form (an entry's ``residual_base``: any registered baseline, e.g.
  ``cascade_pi_ff_tuned`` or ``mpc_linear``): the agent sees the base's action of this
  step (appended to the env's observation, in action units) and the base is told the
  command that was applied (``applied``, where the base has it: ``mpc_linear``'s
  estimator then does not take the correction for a disturbance and fight it);
- the **legacy** form (no ``residual_base``): the base is the industrial reference
  ``cascade_pi_ff``, unobserved, and not told; the files trained so keep acting as
  they were trained.

One implementation (:class:`ResidualBase`) serves the training wrapper
(agents.wrappers.VecResidual) and the shipped agents' Policy (agents/policy.py), so that
what the agent trained with holds at evaluation.
"""

from __future__ import annotations

from typing import Any

import numpy as np

import baselines
from steamtemp_gym.signals import OBS_LIMIT


def check_residual(scale: Any, base: Any) -> None:
    """ValueError naming the problem unless ``scale`` is in (0, 2] and ``base`` is None or
    a registered baseline's name."""
    ok = isinstance(scale, (int, float)) and not isinstance(scale, bool)
    if not (ok and np.isfinite(scale) and 0 < scale <= 2):
        raise ValueError(f"residual_scale must be a number in (0, 2], got {scale!r}")
    if base is not None and base not in baselines.NAMES:
        raise ValueError(
            f"residual_base must be a registered baseline, got {base!r}; "
            f"valid: {list(baselines.NAMES)}"
        )


class ResidualBase:
    """The base controller of a residual agent, per row (module docstring).

    Args:
        env: The env (single or vector) acted on.
        scale: The residual's scale (``residual_scale``).
        base: A registered baseline's name (the observed form), or None (legacy form).
    """

    def __init__(self, env: Any, scale: float, base: str | None = None) -> None:
        check_residual(scale, base)
        self.scale = float(scale)
        self.observed = base is not None
        self.name = base if base is not None else baselines.INDUSTRIAL_REFERENCE
        self.policy = baselines.make(self.name, env)
        self.n_u = int(env.unwrapped.plant.n_u)
        self._tell = getattr(self.policy, "applied", None) if self.observed else None
        self.action = np.zeros((0, self.n_u))

    def reset(self) -> None:
        self.policy.reset()
        self.action = np.zeros((0, self.n_u))

    def step(self, obs: np.ndarray, restart: np.ndarray) -> np.ndarray:
        """The base's action (rows, n_u) for the raw observations ``obs`` (rows, n_obs);
        ``restart``: rows starting an episode. Kept as :attr:`action`."""
        a, _ = self.policy.predict(obs, episode_start=restart)
        self.action = np.asarray(a, dtype=np.float64).reshape(obs.shape[0], self.n_u)
        return self.action

    def combine(self, residual: np.ndarray) -> np.ndarray:
        """The env's action (float32) for the agent's ``residual`` (rows, n_u) on top of
        the last :meth:`step`; the base is told what was applied (observed form)."""
        r = np.clip(np.asarray(residual, dtype=np.float64).reshape(self.action.shape), -1, 1)
        u = np.clip(self.action + self.scale * r, -1.0, 1.0)
        if self._tell is not None:
            self._tell(u)
        return u.astype(np.float32)

    def extend(self, obs: np.ndarray, action: np.ndarray | None = None) -> np.ndarray:
        """``obs`` (rows, n_obs) with the base's action appended (observed form; ``obs``
        itself otherwise); ``action``: another one than the last :meth:`step`'s."""
        if not self.observed:
            return obs
        a = self.action if action is None else action
        return np.concatenate([obs, a.astype(obs.dtype)], axis=1)

    def extend_space(self, space: Any) -> Any:
        """The observation space with the base's action appended (observed form)."""
        import gymnasium as gym

        if not self.observed:
            return space
        shape = (*space.shape[:-1], space.shape[-1] + self.n_u)
        return gym.spaces.Box(-OBS_LIMIT, OBS_LIMIT, shape=shape, dtype=space.dtype)


__all__ = ["ResidualBase", "check_residual"]
