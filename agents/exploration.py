"""Exploration noise correlated in time, for off-policy agents (``noise_type: lowpass``).

White Gaussian noise on every decision moves the valves far more than any controller may:
on the FSH, a noise of 5 % of the stroke every 4 s strokes the valve about 70 times the
industrial reference's travel (TD3's first rollout), so the data an agent learns from is
of a valve the budget forbids, and a travel price measured along those states reads the
noise. A first-order low-pass noise of the same spread (an AR(1) process, the discrete
Ornstein-Uhlenbeck process) wanders the valves slowly instead::

    x <- a x + sqrt(1 - a**2) sigma n,    a = exp(-decision interval / tau),  n ~ N(0, 1)

with the stationary spread ``sigma`` and a per-decision step of ``sigma sqrt(2 (1 - a))``.
The time constant ``tau`` is read from the plant (``noise_tau_s: plant``,
agents/horizons.py ``exploration_time_constant``): the plant's time scale, so that the
exploration covers the valve range the temperatures respond to within the budget's travel.
The noise of each env row restarts from its stationary spread at every episode's start
(SB3's ``VectorizedActionNoise`` resets it).
"""

from __future__ import annotations

import numpy as np
from stable_baselines3.common.noise import ActionNoise


def low_pass(x: np.ndarray, a: float, white: np.ndarray) -> np.ndarray:
    """One step of the AR(1) recursion from ``x`` with innovation ``white`` (of the
    stationary spread; also the noise of agents/datasets.py's ``--noise``)."""
    return a * x + np.sqrt(1.0 - a**2) * white


class LowPassActionNoise(ActionNoise):
    """Low-pass Gaussian action noise (module docstring).

    Args:
        sigma: Stationary standard deviation per action (action units, [-1, 1] range).
        a: Gain per decision, ``exp(-decision interval / tau)``, in [0, 1).
    """

    def __init__(self, sigma: np.ndarray, a: float) -> None:
        sigma = np.asarray(sigma, dtype=np.float64)
        if not (np.all(np.isfinite(sigma)) and np.all(sigma >= 0)):
            raise ValueError(f"noise sigma must be finite and >= 0, got {sigma!r}")
        if not (isinstance(a, float) and 0.0 <= a < 1.0):
            raise ValueError(f"noise gain a must be a float in [0, 1), got {a!r}")
        super().__init__()
        self.sigma, self.a = sigma, a
        self.reset()

    def reset(self) -> None:
        # SB3's noises draw from NumPy's global generator, which its seed sets
        self.x = np.random.normal(size=self.sigma.shape)  # noqa: NPY002 - the stationary spread

    def __call__(self) -> np.ndarray:
        white = np.random.normal(size=self.sigma.shape)  # noqa: NPY002 - as SB3's noises
        self.x = low_pass(self.x, self.a, white)
        return self.sigma * self.x

    def __repr__(self) -> str:
        return f"LowPassActionNoise(sigma={self.sigma}, a={self.a})"


__all__ = ["LowPassActionNoise", "low_pass"]
