"""Gain-free characteristics of an open-loop step response: dead time ``Tu`` and balance
time ``Tg`` from the inflection tangent, ``t50`` and ``t90``."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from steamtemp_gym.metrics.calculus import as_signal, as_time, first_crossing


def _inflection(t: NDArray[np.float64], z: NDArray[np.float64]) -> tuple[float, float, float]:
    """Point ``(t, z)`` and slope of the steepest point of a sampled rising curve.

    The chord slope of a sample interval is the mean of ``dz/dt`` over it. Around the
    steepest chord, a quadratic ``q(u)`` (``u = t - t_j``) is fitted so that its means over
    three adjacent intervals (the steepest one and its neighbours, shifted inwards at the
    ends of the record) equal their chords; the maximum of ``q`` over those intervals
    gives the inflection (the start of the record for a first-order-like response), and
    integrating ``q`` gives ``z`` there. Exact for a locally cubic ``z``.
    """
    chord = np.diff(z) / np.diff(t)
    j = int(np.argmax(chord))
    if chord.size < 3:
        return 0.5 * float(t[j] + t[j + 1]), 0.5 * float(z[j] + z[j + 1]), float(chord[j])
    k = min(max(j - 1, 0), chord.size - 3)  # first of the three fitted intervals
    a = t[k : k + 3] - t[j]  # interval starts
    b = t[k + 1 : k + 4] - t[j]  # interval ends
    # mean of c0 + c1 u + c2 u^2 over [a, b] = c0 + c1 (a + b) / 2 + c2 (a^2 + a b + b^2) / 3
    mat = np.column_stack([np.ones(3), 0.5 * (a + b), (a * a + a * b + b * b) / 3.0])
    c0, c1, c2 = np.linalg.solve(mat, chord[k : k + 3])
    cand = [float(a[0]), float(b[2])]
    if c2 < 0.0:
        cand.append(float(np.clip(-c1 / (2.0 * c2), a[0], b[2])))
    u = max(cand, key=lambda v: c0 + c1 * v + c2 * v * v)
    slope = c0 + c1 * u + c2 * u * u
    z_u = z[j] + c0 * u + c1 * u * u / 2.0 + c2 * u**3 / 3.0
    return float(t[j] + u), float(z_u), float(slope)


def step_response_metrics(
    time_s: ArrayLike, y: ArrayLike, *, t_step: float = 0.0
) -> dict[str, float]:
    """Gain-free characteristics of a monotone step response of a stable process.

    The response is normalized to ``z = (y - y0) / gain``, so negative gains are handled
    like positive ones. ``y0`` is ``y`` at the last sample at or before ``t_step``; the final
    value is the mean of the last 2 % of the samples (at least one). The inflection
    point is the maximum of ``dz/dt`` over ``t >= t_step``: the sample interval with the
    steepest chord, refined by the quadratic slope whose interval means match the chords
    of that interval and its two neighbours (exact for a locally cubic response). A
    first-order response gets its tangent at ``t_step`` (``Tu = 0``, ``Tg = T``). All times
    are measured from ``t_step``.

    Args:
        time_s: Sample times, shape (T,), strictly increasing (may be non-uniform).
        y: Response samples, shape (T,); should have settled by the end.
        t_step: Time of the input step.

    Returns:
        ``gain`` (final minus initial value, units of ``y``), ``Tu_s`` (dead time: where
        the inflection tangent crosses the initial value), ``Tg_s`` (balance time: time
        the tangent takes from the initial to the final value), ``t50_s`` and ``t90_s``
        (first time 50 % / 90 % of the change is reached, linear interpolation; NaN if
        never).

    Raises:
        ValueError: On bad input (see :func:`trajectory_metrics`), ``t_step`` outside
            the record or fewer than 3 samples from ``t_step`` on, or zero gain.
    """
    t = as_time(time_s)
    ya = as_signal(y, "y", t.size)
    if not (math.isfinite(t_step) and t[0] <= t_step < t[-1]):
        raise ValueError(f"t_step = {t_step!r} must lie in [time_s[0], time_s[-1])")
    n_tail = max(1, math.ceil(0.02 * t.size))
    # initial value: last sample at or before the step (the process has not reacted yet)
    y0 = float(ya[int(np.searchsorted(t, t_step, side="right")) - 1])
    gain = float(np.mean(ya[-n_tail:])) - y0
    if gain == 0.0 or not math.isfinite(gain):
        raise ValueError("step response has zero gain (final value equals initial value)")

    first = int(np.searchsorted(t, t_step, side="left"))
    tw = t[first:]
    zw = (ya[first:] - y0) / gain
    if tw.size < 3:
        raise ValueError("step response needs at least 3 samples at or after t_step")

    t_i, z_i, s_i = _inflection(tw, zw)
    if not s_i > 0.0:
        raise ValueError("step response has no rising inflection (is it monotone?)")

    tu = t_i - z_i / s_i - t_step
    tg = 1.0 / s_i
    t50 = first_crossing(tw, zw, 0.5, 1.0) - t_step
    t90 = first_crossing(tw, zw, 0.9, 1.0) - t_step
    return {"gain": gain, "Tu_s": float(tu), "Tg_s": float(tg), "t50_s": t50, "t90_s": t90}
