"""Input checks of sampled signals and exact integrals of their piecewise-linear curves
(the first-order-hold convention of :mod:`steamtemp_gym.metrics`)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from steamtemp_gym._jit import njit

# --------------------------------------------------------------------------- validation


def as_time(time_s: ArrayLike) -> NDArray[np.float64]:
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


def as_signal(x: ArrayLike, name: str, n: int, allow_2d: bool = False) -> NDArray[np.float64]:
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


@njit(cache=True, error_model="numpy")
def frac_above(a: float, c: float, level: float, inclusive: bool) -> float:
    """Fraction of one sample interval where the linear segment from ``a`` to ``c`` exceeds
    ``level``, in [0, 1] (the first-order-hold convention of :mod:`steamtemp_gym.metrics`).

    ``inclusive`` only matters for a segment lying exactly on the level. The crossing is
    clipped to [0, 1] as ``numpy.clip`` (2.x) does, keeping the sign of a zero, so the
    metrics give the same bits as before they were compiled, alone, over arrays or inside
    the env's step.
    """
    d = c - a
    if d == 0.0:
        return 1.0 if (a >= level if inclusive else a > level) else 0.0
    s = (level - a) / d  # parameter in [0, 1] where the segment meets the level
    x = 1.0 - s if d > 0.0 else s  # rising: the part after the crossing; falling: before
    x = 0.0 if x < 0.0 else x  # a denormal slope gives +-inf: clipped here
    return 1.0 if x > 1.0 else x


@njit(cache=True, error_model="numpy")
def frac_outside(e0: float, e1: float, band: float) -> float:
    """Fraction of one sample interval where the linear segment from ``e0`` to ``e1`` lies
    outside ``[-band, band]``: the integrand of ``time_outside_<band>K_s``, which the env's
    constraint cost (``envs/cost.py``) reads per control interval."""
    return frac_above(e0, e1, band, False) + frac_above(-e0, -e1, band, False)


@njit(cache=True, error_model="numpy")
def _frac_above_rows(a, c, level, inclusive, out):
    """``out[i] = frac_above(a[i], c[i], level, inclusive)`` over flat arrays."""
    for i in range(a.shape[0]):
        out[i] = frac_above(a[i], c[i], level, inclusive)


@njit(cache=True, error_model="numpy")
def _frac_outside_rows(e0, e1, band, out):
    """``out[i] = frac_outside(e0[i], e1[i], band)`` over flat arrays."""
    for i in range(e0.shape[0]):
        out[i] = frac_outside(e0[i], e1[i], band)


def _flat_pair(a: ArrayLike, c: ArrayLike) -> tuple[NDArray[np.float64], ...]:
    """Contiguous float64 copies or views of two arrays of one shape, flattened."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    c = np.ascontiguousarray(c, dtype=np.float64)
    return a.reshape(-1), c.reshape(-1)


def frac_above_each(
    a: NDArray[np.float64], c: NDArray[np.float64], level: float, *, inclusive: bool
) -> NDArray[np.float64]:
    """:func:`frac_above` of each interval of the arrays ``a`` and ``c`` (the same shape)."""
    out = np.empty(np.shape(a))
    _frac_above_rows(*_flat_pair(a, c), float(level), bool(inclusive), out.reshape(-1))
    return out


def frac_outside_each(
    e0: NDArray[np.float64], e1: NDArray[np.float64], band: float
) -> NDArray[np.float64]:
    """:func:`frac_outside` of each interval of the arrays ``e0`` and ``e1`` (one shape)."""
    out = np.empty(np.shape(e0))
    _frac_outside_rows(*_flat_pair(e0, e1), float(band), out.reshape(-1))
    return out


def integral_abs(e: NDArray[np.float64], dt: NDArray[np.float64]) -> float:
    """Exact integral of ``|e|`` for the piecewise-linear interpolant of ``e``."""
    e0, e1 = e[:-1], e[1:]
    a0, a1 = np.abs(e0), np.abs(e1)
    same = e0 * e1 >= 0.0
    denom = np.where(same, 1.0, a0 + a1)
    seg = np.where(same, 0.5 * (a0 + a1), 0.5 * (e0 * e0 + e1 * e1) / denom)
    return float(np.sum(seg * dt))


def integral_sq(e: NDArray[np.float64], dt: NDArray[np.float64]) -> float:
    """Exact integral of ``e**2`` for the piecewise-linear interpolant of ``e``."""
    e0, e1 = e[:-1], e[1:]
    return float(np.sum(dt * (e0 * e0 + e0 * e1 + e1 * e1)) / 3.0)


def trapezoid(x: NDArray[np.float64], dt: NDArray[np.float64]) -> float:
    """Trapezoid integral of ``x`` (shape (T,) or (T, k), columns summed)."""
    seg = 0.5 * (x[:-1] + x[1:])
    if seg.ndim == 2:
        seg = seg.sum(axis=1)
    return float(np.sum(seg * dt))


def first_crossing(
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
