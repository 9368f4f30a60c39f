"""Engineering KPIs of a superheated-steam temperature trajectory.

This module is the single source of truth for the numbers plant engineers read
when they judge a steam temperature controller (``/work/shared/REFERENCE_DATA.md``,
section "Operating practice and test scenarios"): peak deviation and IAE during
load ramps, settling time and overshoot after a setpoint step, time outside the
+-5 / +-8 K bands, spray water used, valve travel and reversals, and the time the
spray valve sits saturated.  The environment's episode ``info``, the tests and
the leaderboard all call :func:`trajectory_metrics`.

:func:`step_response_metrics` gives the gain-free characteristics of an open-loop
step response (dead time ``Tu`` and balance time ``Tg`` from the inflection
tangent, ``t50``, ``t90``), the form in which REFERENCE_DATA.md ("Transfer-function
forms") tabulates K/(1+Ts)^n and in which field step tests are reported.

Sampling convention (first-order hold): every sampled signal is read as the
piecewise-*linear* curve through its samples, and each time integral is the exact
integral of that curve.  For quantities linear in the signal (spray used, mean
deviation) this is the trapezoid rule; for ``|e|``, ``e**2``, band and saturation
indicators it is the exact value for the linear interpolant, i.e. zero crossings
and band crossings inside a sample interval are located by linear interpolation.
Sample times may be non-uniform.  A ramp through a band therefore gives the exact
time outside the band however coarse the sampling.

``trajectory_metrics`` keys (with the default ``bands_K=(5.0, 8.0)``),
``e = outlet_temp_C - setpoint_C``:

=====================  ========  ===========================================================
key                    unit      definition
=====================  ========  ===========================================================
``iae_K_s``            K s       integral of ``|e|``
``ise_K2_s``           K^2 s     integral of ``e**2``
``rmse_K``             K         ``sqrt(ise / duration)``
``max_abs_dev_K``      K         largest ``|e|`` over the samples (peak deviation)
``mean_dev_K``         K         time mean of the signed ``e``
``time_outside_5K_s``  s         time with ``|e| > 5 K`` (one key per entry of ``bands_K``)
``time_outside_8K_s``  s         time with ``|e| > 8 K``
``overshoot_pct``      %         setpoint step only: largest excursion beyond the new
                                 setpoint in the step direction, in percent of the step
                                 size; 0 if none
``settling_time_s``    s         setpoint step only: time from the step until ``|e|`` stays
                                 within ``settle_band_K`` (default ``max(1 K, 2 % of the
                                 step)``) for good; NaN if it is outside at the end
``rise_time_s``        s         setpoint step only: time from crossing 10 % to crossing
                                 90 % of the way from the old to the new setpoint; NaN if
                                 90 % is never reached
``spray_used_kg``      kg        integral of the spray water flow (summed over columns)
``valve_travel``       1         sum of ``|delta opening|`` (openings in [0, 1]; 1 = one
                                 full stroke), summed over valves
``valve_reversals``    1         number of direction changes of the valve movement, moves
                                 reversing by no more than ``reversal_deadband`` (default
                                 0.2 % opening) ignored; summed over valves
``valve_saturated_s``  s         time at ``<= 0.5 %`` or ``>= 99.5 %`` opening, summed over
                                 valves (valve-seconds)
=====================  ========  ===========================================================

Setpoint step: the largest jump ``|setpoint_C[i+1] - setpoint_C[i]|`` of at least
1 K.  The step time is ``time_s[i+1]``, the first sample carrying the new setpoint;
the analysis window runs from there to the sample before the next jump of at least
1 K (or the end of the record).  Without such a jump the three step keys are NaN.

Valve reversals are counted on the output of a backlash (play) operator of total
width ``reversal_deadband`` driven by the opening: a reversal is counted when the
valve retraces more than the deadband from its last extreme, however small the
individual per-sample moves are.  Sensor-like jitter below the deadband is never
counted, while a slow oscillation made of many tiny moves is.  The play operator is
evaluated without a per-sample Python loop by a parallel prefix (Hillis-Steele)
composition of clamp maps, O(T log T).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "METRIC_NAMES",
    "METRIC_UNITS",
    "STEP_RESPONSE_NAMES",
    "STEP_RESPONSE_UNITS",
    "REVERSAL_DEADBAND",
    "SATURATION_LOW",
    "SATURATION_HIGH",
    "STEP_MIN_K",
    "find_setpoint_step",
    "QUIET_SETTLE_S",
    "QUIET_MIN_S",
    "LIMIT_CYCLE_RATIO",
    "LIMIT_CYCLE_FLOOR_K",
    "limit_cycles",
    "metric_names",
    "quiet_peak_to_peak",
    "step_response_metrics",
    "trajectory_metrics",
]

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

_DEFAULT_BANDS_K: tuple[float, ...] = (5.0, 8.0)
#: The quiet stretch of :func:`quiet_peak_to_peak` starts this long after a scenario's last
#: scheduled change (s): the time a well-damped loop needs to settle after it.
QUIET_SETTLE_S: float = 600.0
#: Shortest quiet stretch (s) on which the peak-to-peak is read: a limit cycle of the slowest
#: loops (periods of 4-8 min) shows in it at least once.
QUIET_MIN_S: float = 600.0
#: A loop limit-cycles when its quiet peak-to-peak exceeds this multiple of the industrial
#: reference's on the same episode (:func:`limit_cycles`) ...
LIMIT_CYCLE_RATIO: float = 2.0
#: ... and this floor (K): the sensor noise and coloured disturbance alone swing a settled
#: loop by about 1 K peak to peak.
LIMIT_CYCLE_FLOOR_K: float = 1.5


def _band_key(band_K: float) -> str:
    return f"time_outside_{band_K:g}K_s"


def metric_names(bands_K: tuple[float, ...] | list[float] = _DEFAULT_BANDS_K) -> tuple[str, ...]:
    """Keys of :func:`trajectory_metrics` for the given bands, in table order.

    Args:
        bands_K: Deviation bands in K, as passed to :func:`trajectory_metrics`.

    Returns:
        The metric names, in the order of the module-level table.
    """
    return (
        "iae_K_s",
        "ise_K2_s",
        "rmse_K",
        "max_abs_dev_K",
        "mean_dev_K",
        *(_band_key(float(b)) for b in bands_K),
        "overshoot_pct",
        "settling_time_s",
        "rise_time_s",
        "spray_used_kg",
        "valve_travel",
        "valve_reversals",
        "valve_saturated_s",
    )


#: Keys of :func:`trajectory_metrics` with the default bands, in table order.
METRIC_NAMES: tuple[str, ...] = metric_names(_DEFAULT_BANDS_K)

#: Unit of each metric in :data:`METRIC_NAMES` ("1" = dimensionless).
METRIC_UNITS: dict[str, str] = {
    "iae_K_s": "K s",
    "ise_K2_s": "K^2 s",
    "rmse_K": "K",
    "max_abs_dev_K": "K",
    "mean_dev_K": "K",
    **{_band_key(b): "s" for b in _DEFAULT_BANDS_K},
    "overshoot_pct": "%",
    "settling_time_s": "s",
    "rise_time_s": "s",
    "spray_used_kg": "kg",
    "valve_travel": "1",
    "valve_reversals": "1",
    "valve_saturated_s": "s",
}

#: Keys of :func:`step_response_metrics`.
STEP_RESPONSE_NAMES: tuple[str, ...] = ("gain", "Tu_s", "Tg_s", "t50_s", "t90_s")

#: Units of :data:`STEP_RESPONSE_NAMES` (the gain is in the units of ``y``).
STEP_RESPONSE_UNITS: dict[str, str] = {
    "gain": "units of y",
    "Tu_s": "s",
    "Tg_s": "s",
    "t50_s": "s",
    "t90_s": "s",
}


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
    t10 = _first_crossing(tw, yw, sp_old + 0.1 * jump, direction)
    t90 = _first_crossing(tw, yw, sp_old + 0.9 * jump, direction)
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
    bands_K: tuple[float, ...] | list[float] = _DEFAULT_BANDS_K,
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
    t = _as_time(time_s)
    n = t.size
    y = _as_signal(outlet_temp_C, "outlet_temp_C", n)
    sp = _as_signal(setpoint_C, "setpoint_C", n)
    valve = _as_signal(spray_valve, "spray_valve", n, allow_2d=True)
    flow = _as_signal(spray_flow_kg_s, "spray_flow_kg_s", n, allow_2d=True)
    bands = tuple(float(b) for b in bands_K)
    if any(not (math.isfinite(b) and b > 0.0) for b in bands):
        raise ValueError(f"bands_K must be finite and positive, got {bands_K!r}")
    if settle_band_K is not None and not (math.isfinite(settle_band_K) and settle_band_K > 0.0):
        raise ValueError(f"settle_band_K must be finite and positive, got {settle_band_K!r}")
    if not (math.isfinite(reversal_deadband) and reversal_deadband >= 0.0):
        raise ValueError(f"reversal_deadband must be >= 0, got {reversal_deadband!r}")
    vmin, vmax = float(valve.min()), float(valve.max())
    if vmin < -_VALVE_RANGE_TOL or vmax > 1.0 + _VALVE_RANGE_TOL:
        raise ValueError(
            f"spray_valve openings must lie in [0, 1] (got range [{vmin:g}, {vmax:g}]; "
            "percent instead of fraction?)"
        )

    dt = np.diff(t)
    duration = float(t[-1] - t[0])
    e = y - sp
    e0, e1 = e[:-1], e[1:]

    ise = _integral_sq(e, dt)
    out: dict[str, float] = {
        "iae_K_s": _integral_abs(e, dt),
        "ise_K2_s": ise,
        "rmse_K": math.sqrt(ise / duration),
        "max_abs_dev_K": float(np.max(np.abs(e))),
        "mean_dev_K": _trapezoid(e, dt) / duration,
    }
    for b in bands:
        frac = _frac_above(e0, e1, b, inclusive=False) + _frac_above(-e0, -e1, b, inclusive=False)
        out[_band_key(b)] = float(np.sum(frac * dt))

    overshoot, settling, rise = _step_metrics(t, y, sp, settle_band_K)
    out["overshoot_pct"] = overshoot
    out["settling_time_s"] = settling
    out["rise_time_s"] = rise

    out["spray_used_kg"] = _trapezoid(flow, dt)
    out["valve_travel"] = float(np.sum(np.abs(np.diff(valve, axis=0))))
    out["valve_reversals"] = float(_count_reversals(valve, reversal_deadband))
    v0, v1 = valve[:-1], valve[1:]
    sat = _frac_above(-v0, -v1, -SATURATION_LOW, inclusive=True) + _frac_above(
        v0, v1, SATURATION_HIGH, inclusive=True
    )
    if sat.ndim == 2:
        sat = sat.sum(axis=1)
    out["valve_saturated_s"] = float(np.sum(sat * dt))
    return out


def quiet_peak_to_peak(
    time_s: ArrayLike,
    error_K: ArrayLike,
    quiet_from_s: float,
    min_length_s: float = QUIET_MIN_S,
) -> float:
    """Peak-to-peak of the control error (K) over the quiet stretch ``time_s >= quiet_from_s``.

    The limit-cycle measure: after a scenario's last scheduled change (plus
    :data:`QUIET_SETTLE_S`), a loop that settles shows only the response to noise and the
    coloured disturbance; one that limit-cycles shows the cycle's full swing.

    Returns:
        ``max(e) - min(e)`` over the samples in the stretch, or NaN if it is shorter than
        ``min_length_s`` (the measure does not apply).

    Raises:
        ValueError: On mismatched lengths, fewer than 2 samples, non-finite values or
            non-increasing time.
    """
    t = _as_time(time_s)
    e = _as_signal(error_K, "error_K", t.size)
    if not math.isfinite(quiet_from_s) or not math.isfinite(min_length_s):
        raise ValueError(f"quiet_from_s and min_length_s must be finite, got "
                         f"{quiet_from_s!r}, {min_length_s!r}")  # fmt: skip
    quiet = t >= quiet_from_s
    if not quiet.any() or t[-1] - t[quiet][0] < min_length_s:
        return math.nan
    return float(np.max(e[quiet]) - np.min(e[quiet]))


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
    t = _as_time(time_s)
    ya = _as_signal(y, "y", t.size)
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
    t50 = _first_crossing(tw, zw, 0.5, 1.0) - t_step
    t90 = _first_crossing(tw, zw, 0.9, 1.0) - t_step
    return {"gain": gain, "Tu_s": float(tu), "Tg_s": float(tg), "t50_s": t50, "t90_s": t90}


def limit_cycles(quiet_p2p_K: float, reference_p2p_K: float) -> bool:
    """Whether a quiet peak-to-peak (:func:`quiet_peak_to_peak`) shows a sustained oscillation:
    above ``max(LIMIT_CYCLE_RATIO * reference_p2p_K, LIMIT_CYCLE_FLOOR_K)``, the reference's
    on the same episode. False where the measure does not apply (NaN)."""
    if np.isnan(quiet_p2p_K):
        return False
    return bool(quiet_p2p_K > max(LIMIT_CYCLE_RATIO * reference_p2p_K, LIMIT_CYCLE_FLOOR_K))
