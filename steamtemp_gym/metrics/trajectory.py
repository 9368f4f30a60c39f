"""Engineering KPIs of one steam temperature trajectory: :func:`trajectory_metrics` (the
table of :mod:`steamtemp_gym.metrics`), with its setpoint-step and valve measures."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from steamtemp_gym.metrics.calculus import (
    as_signal,
    as_time,
    first_crossing,
    frac_above_each,
    frac_outside_each,
    integral_abs,
    integral_sq,
    trapezoid,
)
from steamtemp_gym.metrics.names import DEFAULT_BANDS_K, band_key

#: Smallest setpoint jump (K) between two samples treated as a setpoint step.
STEP_MIN_K: float = 1.0
#: Valve openings at or below this count as saturated (closed).
SATURATION_LOW: float = 0.005
#: Valve openings at or above this count as saturated (fully open).
SATURATION_HIGH: float = 0.995
#: Default backlash width (fraction of full stroke) for counting valve reversals.
REVERSAL_DEADBAND: float = 0.002
#: Tolerance on valve openings outside [0, 1] before the input is rejected.
_VALVE_RANGE_TOL: float = 1e-6


# ------------------------------------------------------------------------ setpoint step


def find_setpoint_step(setpoint_C: ArrayLike, min_step_K: float = STEP_MIN_K) -> tuple[int, float]:
    """Locate the setpoint step used by :func:`trajectory_metrics`.

    Args:
        setpoint_C: Setpoint samples, shape (T,).
        min_step_K: Smallest jump between consecutive samples that counts as a step.

    Returns:
        ``(m, jump)``: index of the first sample carrying the new setpoint and the signed
        jump in K, for the largest jump of at least ``min_step_K``; ``(-1, nan)`` if
        there is none.
    """
    sp = np.asarray(setpoint_C, dtype=float)
    if sp.size < 2:
        return -1, math.nan
    d = np.diff(sp)
    i = int(np.argmax(np.abs(d)))
    if not abs(d[i]) >= min_step_K:
        return -1, math.nan
    return i + 1, float(d[i])


def _step_metrics(
    t: NDArray[np.float64],
    y: NDArray[np.float64],
    sp: NDArray[np.float64],
    settle_band_K: float | None,
) -> tuple[float, float, float]:
    """Overshoot (%), settling time (s) and 10-90 % rise time (s) after the setpoint step."""
    m, jump = find_setpoint_step(sp)
    if m < 0:
        return math.nan, math.nan, math.nan
    big = np.flatnonzero(np.abs(np.diff(sp)[m:]) >= STEP_MIN_K)
    end = m + int(big[0]) + 1 if big.size else t.size  # window is [m, end)
    tw, yw, spw = t[m:end], y[m:end], sp[m:end]
    ew = yw - spw
    size = abs(jump)
    direction = math.copysign(1.0, jump)
    t_step = float(t[m])

    overshoot = max(0.0, float(np.max(direction * ew))) / size * 100.0

    band = max(1.0, 0.02 * size) if settle_band_K is None else float(settle_band_K)
    outside = np.flatnonzero(np.abs(ew) > band)
    if outside.size == 0:
        settling = 0.0
    elif outside[-1] == ew.size - 1:
        settling = math.nan
    else:
        j = int(outside[-1])
        e0, e1 = ew[j], ew[j + 1]
        target = math.copysign(band, e0)
        frac = (target - e0) / (e1 - e0)
        settling = float(tw[j] + frac * (tw[j + 1] - tw[j])) - t_step

    sp_old = float(sp[m - 1])
    t10 = first_crossing(tw, yw, sp_old + 0.1 * jump, direction)
    t90 = first_crossing(tw, yw, sp_old + 0.9 * jump, direction)
    rise = t90 - t10 if np.isfinite(t90) else math.nan
    return overshoot, settling, rise


# -------------------------------------------------------------------------------- valves


def _play_operator(x: NDArray[np.float64], half_width: float) -> NDArray[np.float64]:
    """Backlash (play) operator ``y_k = clip(y_(k-1), x_k - h, x_k + h)``, ``y_0 = x_0``.

    Each step is the clamp map ``y -> clip(y, a_k, b_k)``; clamp maps are closed under
    composition, ``clip(clip(y, a1, b1), a2, b2) = clip(y, clip(a1, a2, b2), clip(b1, a2,
    b2))``, so the prefix compositions follow from a Hillis-Steele scan in log2(T)
    vectorized passes. Works along axis 0 of a (T,) or (T, k) array.
    """
    lo = x - half_width
    hi = x + half_width
    n = x.shape[0]
    shift = 1
    while shift < n:
        new_lo = np.clip(lo[:-shift], lo[shift:], hi[shift:])
        new_hi = np.clip(hi[:-shift], lo[shift:], hi[shift:])
        lo[shift:] = new_lo
        hi[shift:] = new_hi
        shift *= 2
    return np.clip(x[0], lo, hi)


def _count_reversals(valve: NDArray[np.float64], deadband: float) -> int:
    """Direction changes of the valve movement, ignoring retraces up to ``deadband``."""
    v2 = valve.reshape(valve.shape[0], -1)
    y = _play_operator(v2.copy(), 0.5 * deadband) if deadband > 0.0 else v2
    sgn = np.sign(np.diff(y, axis=0))
    total = 0
    for col in sgn.T:  # loop over valves, not samples
        moves = col[col != 0.0]
        total += int(np.count_nonzero(moves[1:] != moves[:-1]))
    return total


# ------------------------------------------------------------------------- public API


def trajectory_metrics(
    time_s: ArrayLike,
    outlet_temp_C: ArrayLike,
    setpoint_C: ArrayLike,
    spray_valve: ArrayLike,
    spray_flow_kg_s: ArrayLike,
    *,
    bands_K: tuple[float, ...] | list[float] = DEFAULT_BANDS_K,
    settle_band_K: float | None = None,
    reversal_deadband: float = REVERSAL_DEADBAND,
) -> dict[str, float]:
    """Engineering KPIs of one steam temperature trajectory (see the module table).

    Args:
        time_s: Sample times in s, shape (T,), strictly increasing, not necessarily
            uniform. T >= 2.
        outlet_temp_C: Controlled (outlet) steam temperature in degC, shape (T,).
        setpoint_C: Temperature setpoint in degC, shape (T,).
        spray_valve: Spray valve opening(s) in [0, 1], shape (T,) or (T, k) for k valves.
        spray_flow_kg_s: Spray water flow in kg/s, shape (T,) or (T, k); columns summed.
        bands_K: Deviation bands; one ``time_outside_<b>K_s`` key per band.
        settle_band_K: Settling band in K; default ``max(1 K, 2 % of the step size)``.
        reversal_deadband: Valve retraces up to this opening fraction are not counted
            as reversals (default 0.002 = 0.2 % of the stroke).

    Returns:
        Dict of floats keyed by :func:`metric_names` ``(bands_K)`` (equal to
        :data:`METRIC_NAMES` with the default bands), in table order.

    Raises:
        ValueError: On mismatched lengths, fewer than 2 samples, non-finite values,
            non-increasing time, valve openings outside [0, 1], or non-positive bands.
    """
    t, y, sp, valve, flow = _as_signals(
        time_s, outlet_temp_C, setpoint_C, spray_valve, spray_flow_kg_s
    )
    bands = _checked_options(bands_K, settle_band_K, reversal_deadband)
    _check_valve_range(valve)
    dt = np.diff(t)
    out = _deviation_metrics(t, y - sp, dt, bands)
    overshoot, settling, rise = _step_metrics(t, y, sp, settle_band_K)
    out["overshoot_pct"] = overshoot
    out["settling_time_s"] = settling
    out["rise_time_s"] = rise
    out.update(_spray_metrics(valve, flow, dt, reversal_deadband))
    return out


def _as_signals(
    time_s: ArrayLike,
    outlet_temp_C: ArrayLike,
    setpoint_C: ArrayLike,
    spray_valve: ArrayLike,
    spray_flow_kg_s: ArrayLike,
) -> tuple[NDArray[np.float64], ...]:
    """The checked arrays ``(t, y, sp, valve, flow)`` of :func:`trajectory_metrics`."""
    t = as_time(time_s)
    n = t.size
    y = as_signal(outlet_temp_C, "outlet_temp_C", n)
    sp = as_signal(setpoint_C, "setpoint_C", n)
    valve = as_signal(spray_valve, "spray_valve", n, allow_2d=True)
    flow = as_signal(spray_flow_kg_s, "spray_flow_kg_s", n, allow_2d=True)
    return t, y, sp, valve, flow


def _checked_options(
    bands_K: tuple[float, ...] | list[float],
    settle_band_K: float | None,
    reversal_deadband: float,
) -> tuple[float, ...]:
    """The bands of :func:`trajectory_metrics` as floats, after checking its options."""
    bands = tuple(float(b) for b in bands_K)
    if any(not (math.isfinite(b) and b > 0.0) for b in bands):
        raise ValueError(f"bands_K must be finite and positive, got {bands_K!r}")
    if settle_band_K is not None and not (math.isfinite(settle_band_K) and settle_band_K > 0.0):
        raise ValueError(f"settle_band_K must be finite and positive, got {settle_band_K!r}")
    if not (math.isfinite(reversal_deadband) and reversal_deadband >= 0.0):
        raise ValueError(f"reversal_deadband must be >= 0, got {reversal_deadband!r}")
    return bands


def _check_valve_range(valve: NDArray[np.float64]) -> None:
    """Raise ValueError unless every opening lies in [0, 1] (within _VALVE_RANGE_TOL)."""
    vmin, vmax = float(valve.min()), float(valve.max())
    if vmin < -_VALVE_RANGE_TOL or vmax > 1.0 + _VALVE_RANGE_TOL:
        raise ValueError(
            f"spray_valve openings must lie in [0, 1] (got range [{vmin:g}, {vmax:g}]; "
            "percent instead of fraction?)"
        )


def _deviation_metrics(
    t: NDArray[np.float64],
    e: NDArray[np.float64],
    dt: NDArray[np.float64],
    bands: tuple[float, ...],
) -> dict[str, float]:
    """IAE, ISE, RMSE, peak and mean deviation and the time outside each band of ``e``."""
    duration = float(t[-1] - t[0])
    e0, e1 = e[:-1], e[1:]

    ise = integral_sq(e, dt)
    out: dict[str, float] = {
        "iae_K_s": integral_abs(e, dt),
        "ise_K2_s": ise,
        "rmse_K": math.sqrt(ise / duration),
        "max_abs_dev_K": float(np.max(np.abs(e))),
        "mean_dev_K": trapezoid(e, dt) / duration,
    }
    for b in bands:
        frac = frac_outside_each(e0, e1, b)
        out[band_key(b)] = float(np.sum(frac * dt))
    return out


def _spray_metrics(
    valve: NDArray[np.float64],
    flow: NDArray[np.float64],
    dt: NDArray[np.float64],
    reversal_deadband: float,
) -> dict[str, float]:
    """Spray water used, valve travel, reversals and time saturated."""
    out: dict[str, float] = {}
    out["spray_used_kg"] = trapezoid(flow, dt)
    out["valve_travel"] = float(np.sum(np.abs(np.diff(valve, axis=0))))
    out["valve_reversals"] = float(_count_reversals(valve, reversal_deadband))
    v0, v1 = valve[:-1], valve[1:]
    sat = frac_above_each(-v0, -v1, -SATURATION_LOW, inclusive=True) + frac_above_each(
        v0, v1, SATURATION_HIGH, inclusive=True
    )
    if sat.ndim == 2:
        sat = sat.sum(axis=1)
    out["valve_saturated_s"] = float(np.sum(sat * dt))
    return out
