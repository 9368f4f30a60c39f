"""Discrete loop primitives the baselines share (one implementation of each).

Every baseline keeps per-row state over a batch of observations and restarts the rows
whose episode starts; most read the measurements through the DCS input filter and close
a position-form PI with conditional-integration anti-windup somewhere (cascade_pi's loops,
the inner loops under fuzzy P²ID and neuro-PID).
"""

from __future__ import annotations

from typing import Any

import numpy as np


def restart_rows(fresh: bool, n: int, episode_start: Any) -> np.ndarray:
    """Rows to restart this step: every row of a fresh state (first call, new batch size),
    else those flagged by ``episode_start`` (none if it is None)."""
    if fresh:
        return np.ones(n, dtype=bool)
    if episode_start is None:
        return np.zeros(n, dtype=bool)
    return np.broadcast_to(np.asarray(episode_start, dtype=bool), (n,)).copy()


def input_filter(yf: np.ndarray, y: np.ndarray, a: float, restart: np.ndarray) -> None:
    """First-order input filter yf <- a yf + (1 - a) y in place; restarted rows take y."""
    yf[:] = a * yf + (1.0 - a) * y
    yf[restart] = y[restart]


def into_stop(v: np.ndarray, push: np.ndarray) -> np.ndarray:
    """True where an output at a stop (v >= 1 or v <= 0) is pushed further into it."""
    return ((v >= 1.0) & (push > 0)) | ((v <= 0.0) & (push < 0))


def pi_position(
    v0: np.ndarray, kc: float, e: np.ndarray, integral: np.ndarray, dt: float, ti: float
) -> tuple[np.ndarray, np.ndarray]:
    """Position-form PI v = v0 + kc (e + integral) with conditional integration.

    ``integral`` (a view into the caller's state) grows by e dt / ti unless the output
    sits at a stop and kc e pushes it further in (no integration for ti = inf). ``kc`` and
    ``ti`` may be scalars or per-row arrays.

    Returns:
        (v, stopped): the unclipped output and where it was held at a stop.
    """
    v = v0 + kc * (e + integral)
    stopped = into_stop(v, kc * e)
    if np.all(np.isfinite(ti)):
        integral += np.where(stopped, 0.0, dt / ti * e)
    return v, stopped


def observation_layout(env: Any) -> tuple[list[str], np.ndarray, np.ndarray]:
    """(names, scale, center) of an env's observation entries: a baseline reads the
    physical values y = obs * scale + center (steamtemp_gym.signals)."""
    sig = env.unwrapped.signals.observation
    return (
        [s.name for s in sig],
        np.array([s.scale for s in sig]),
        np.array([s.center for s in sig]),
    )
