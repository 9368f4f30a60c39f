"""Input checks of sampled signals and exact integrals of their piecewise-linear curves
(the first-order-hold convention of :mod:`steamtemp_gym.metrics`)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

# --------------------------------------------------------------------------- validation


def _as_time(time_s: ArrayLike) -> NDArray[np.float64]:
    t = np.asarray(time_s, dtype=float)
    if t.ndim != 1:
        raise ValueError(f"time_s must be one-dimensional, got shape {t.shape}")
    if t.size < 2:
        raise ValueError(f"time_s needs at least 2 samples, got {t.size}")
    if not np.all(np.isfinite(t)):
        raise ValueError("time_s contains non-finite values (NaN or inf)")
    dt = np.diff(t)
    if np.any(dt <= 0.0):
        k = int(np.argmax(dt <= 0.0))
        raise ValueError(
            f"time_s must be strictly increasing; time_s[{k + 1}] = {t[k + 1]!r} "
            f"<= time_s[{k}] = {t[k]!r}"
        )
    return t


def _as_signal(x: ArrayLike, name: str, n: int, allow_2d: bool = False) -> NDArray[np.float64]:
    a = np.asarray(x, dtype=float)
    if a.ndim == 0 or a.ndim > (2 if allow_2d else 1):
        shapes = "(T,) or (T, k)" if allow_2d else "(T,)"
        raise ValueError(f"{name} must have shape {shapes}, got shape {a.shape}")
    if a.shape[0] != n:
        raise ValueError(f"{name} has {a.shape[0]} samples but time_s has {n} (length mismatch)")
    if a.ndim == 2 and a.shape[1] == 0:
        raise ValueError(f"{name} has no columns (shape {a.shape})")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains non-finite values (NaN or inf)")
    return a


# --------------------------------------------------------------- piecewise-linear calculus


def _frac_above(
    a: NDArray[np.float64], c: NDArray[np.float64], level: float, *, inclusive: bool
) -> NDArray[np.float64]:
    """Fraction of each interval where the linear segment from ``a`` to ``c`` exceeds ``level``.

    ``inclusive`` only matters for segments lying exactly on the level.
    """
    d = c - a
    flat = d == 0.0
    safe_d = np.where(flat, 1.0, d)
    with np.errstate(over="ignore"):  # a denormal slope gives +-inf: clipped below
        s = (level - a) / safe_d  # parameter in [0, 1] where the segment meets the level
    rising = np.clip(1.0 - s, 0.0, 1.0)
    falling = np.clip(s, 0.0, 1.0)
    on_flat = (a >= level) if inclusive else (a > level)
    return np.where(flat, on_flat.astype(float), np.where(d > 0.0, rising, falling))


def _integral_abs(e: NDArray[np.float64], dt: NDArray[np.float64]) -> float:
    """Exact integral of ``|e|`` for the piecewise-linear interpolant of ``e``."""
    e0, e1 = e[:-1], e[1:]
    a0, a1 = np.abs(e0), np.abs(e1)
    same = e0 * e1 >= 0.0
    denom = np.where(same, 1.0, a0 + a1)
    seg = np.where(same, 0.5 * (a0 + a1), 0.5 * (e0 * e0 + e1 * e1) / denom)
    return float(np.sum(seg * dt))


def _integral_sq(e: NDArray[np.float64], dt: NDArray[np.float64]) -> float:
    """Exact integral of ``e**2`` for the piecewise-linear interpolant of ``e``."""
    e0, e1 = e[:-1], e[1:]
    return float(np.sum(dt * (e0 * e0 + e0 * e1 + e1 * e1)) / 3.0)


def _trapezoid(x: NDArray[np.float64], dt: NDArray[np.float64]) -> float:
    """Trapezoid integral of ``x`` (shape (T,) or (T, k), columns summed)."""
    seg = 0.5 * (x[:-1] + x[1:])
    if seg.ndim == 2:
        seg = seg.sum(axis=1)
    return float(np.sum(seg * dt))


def _first_crossing(
    t: NDArray[np.float64], y: NDArray[np.float64], level: float, direction: float
) -> float:
    """First time the linear interpolant of ``y`` reaches ``level`` going in ``direction``.

    Returns ``t[0]`` if ``y[0]`` is already at or beyond the level, NaN if never reached.
    """
    beyond = direction * (y - level) >= 0.0
    if not np.any(beyond):
        return math.nan
    k = int(np.argmax(beyond))
    if k == 0:
        return float(t[0])
    y0, y1 = y[k - 1], y[k]
    return float(t[k - 1] + (level - y0) / (y1 - y0) * (t[k] - t[k - 1]))
