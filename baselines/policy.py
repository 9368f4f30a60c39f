"""The Policy protocol: what every baseline (and every trained agent) offers.

The signature is Stable-Baselines3's ``predict`` (``PolicyPredictor`` in
``stable_baselines3/common/type_aliases.py``): a policy sees exactly the
observation an RL agent sees and returns actions in [-1, 1]. ``reset()``
clears internal controller state at the start of an episode (it is also done
automatically where ``episode_start`` is True).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class Policy(Protocol):
    """A controller or agent acting on normalized observations."""

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """Action(s) for one observation (n_obs,) or a batch (n_envs, n_obs)."""
        ...

    def reset(self) -> None:
        """Forget the episode (integrators, estimators, histories)."""
        ...
