"""Tests for :mod:`steamtemp_gym.metrics` against analytically known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.typing import NDArray
from scipy.optimize import brentq
from scipy.special import gammainc
from scipy.stats import gamma

from steamtemp_gym import metrics
from steamtemp_gym.metrics import (
    METRIC_NAMES,
    METRIC_UNITS,
    STEP_RESPONSE_NAMES,
    STEP_RESPONSE_UNITS,
    find_setpoint_step,
    metric_names,
    step_response_metrics,
    trajectory_metrics,
)

SP = 540.0


def _metrics(
    t: NDArray,
    y: NDArray,
    sp: NDArray | float = SP,
    valve: NDArray | None = None,
    flow: NDArray | None = None,
    **kw: object,
) -> dict[str, float]:
    """trajectory_metrics with neutral defaults for the signals a test does not care about."""
    n = len(t)
    sp_arr = np.broadcast_to(np.asarray(sp, dtype=float), (n,))
    valve_arr = np.full(n, 0.5) if valve is None else valve
    flow_arr = np.zeros(n) if flow is None else flow
    return trajectory_metrics(t, y, sp_arr, valve_arr, flow_arr, **kw)


# ----------------------------------------------------------------------------- keys / units


def test_keys_units_and_order() -> None:
    t = np.linspace(0.0, 10.0, 11)
    m = _metrics(t, np.full(11, SP))
    assert tuple(m) == METRIC_NAMES
    assert set(METRIC_UNITS) == set(METRIC_NAMES)
    assert all(isinstance(v, float) for v in m.values())
    assert "time_outside_5K_s" in METRIC_NAMES and "time_outside_8K_s" in METRIC_NAMES
    assert set(STEP_RESPONSE_UNITS) == set(STEP_RESPONSE_NAMES)
    custom = _metrics(t, np.full(11, SP), bands_K=(2.5, 10.0))
    assert tuple(custom) == metric_names((2.5, 10.0))
    assert "time_outside_2.5K_s" in custom and "time_outside_10K_s" in custom


def test_perfect_tracking_is_zero() -> None:
    t = np.linspace(0.0, 100.0, 101)
    m = _metrics(t, np.full(101, SP))
    for key in METRIC_NAMES:
        if key in ("overshoot_pct", "settling_time_s", "rise_time_s"):
            assert math.isnan(m[key])  # no setpoint step
        else:
            assert m[key] == 0.0, key


# ----------------------------------------------------------------------- error integrals


@pytest.mark.parametrize("offset", [6.0, -3.0])
def test_constant_offset_nonuniform_time(offset: float) -> None:
    rng = np.random.default_rng(0)
    t = np.concatenate([[0.0], np.sort(rng.uniform(0.0, 250.0, 40)), [250.0]])
    m = _metrics(t, np.full(t.size, SP + offset))
    duration = 250.0
    assert m["iae_K_s"] == pytest.approx(abs(offset) * duration, rel=1e-12)
    assert m["ise_K2_s"] == pytest.approx(offset**2 * duration, rel=1e-12)
    assert m["rmse_K"] == pytest.approx(abs(offset), rel=1e-12)
    assert m["max_abs_dev_K"] == pytest.approx(abs(offset), rel=1e-12)
    assert m["mean_dev_K"] == pytest.approx(offset, rel=1e-12)
    assert m["time_outside_5K_s"] == pytest.approx(duration if abs(offset) > 5 else 0.0)
    assert m["time_outside_8K_s"] == 0.0


def test_sine_error() -> None:
    amp, period, n_periods = 4.0, 60.0, 5
    duration = n_periods * period
    t = np.linspace(0.0, duration, 20001)
    m = _metrics(t, SP + amp * np.sin(2 * np.pi * t / period))
    assert m["ise_K2_s"] == pytest.approx(amp**2 * duration / 2, rel=1e-6)
    assert m["iae_K_s"] == pytest.approx(2 * amp * duration / np.pi, rel=1e-6)
    assert m["rmse_K"] == pytest.approx(amp / np.sqrt(2), rel=1e-6)
    assert m["mean_dev_K"] == pytest.approx(0.0, abs=1e-9)
    assert m["max_abs_dev_K"] == pytest.approx(amp, rel=1e-6)
    # |A sin| > b for a fraction 1 - 2 asin(b/A)/pi of the time
    m3 = _metrics(t, SP + amp * np.sin(2 * np.pi * t / period), bands_K=(3.0,))
    expected = duration * (1 - 2 * np.arcsin(3.0 / amp) / np.pi)
    assert m3["time_outside_3K_s"] == pytest.approx(expected, rel=1e-5)
    assert m["time_outside_5K_s"] == 0.0


def test_ramp_crossing_bands_exact_on_coarse_grid() -> None:
    # e(t) = t - 10 on [0, 20]: |e| > 5 for 10 s, |e| > 8 for 4 s; coarse, irregular grid
    t = np.array([0.0, 1.3, 4.1, 7.7, 9.2, 12.9, 13.5, 17.0, 18.8, 20.0])
    m = _metrics(t, SP + t - 10.0)
    assert m["time_outside_5K_s"] == pytest.approx(10.0, rel=1e-12)
    assert m["time_outside_8K_s"] == pytest.approx(4.0, rel=1e-12)
    assert m["iae_K_s"] == pytest.approx(100.0, rel=1e-12)  # zero crossing inside a sample
    assert m["ise_K2_s"] == pytest.approx(2000.0 / 3.0, rel=1e-12)
    assert m["mean_dev_K"] == pytest.approx(0.0, abs=1e-12)
    assert m["max_abs_dev_K"] == pytest.approx(10.0)


def test_setpoint_sliding_is_tracked() -> None:
    # the error is taken against the instantaneous setpoint
    t = np.linspace(0.0, 100.0, 201)
    sp = 530.0 + 0.1 * t
    m = _metrics(t, sp - 2.0, sp=sp)
    assert m["iae_K_s"] == pytest.approx(200.0)
    assert m["mean_dev_K"] == pytest.approx(-2.0)
    assert math.isnan(m["settling_time_s"])  # 0.05 K per sample is no step


# ----------------------------------------------------------------------- setpoint step


def _second_order(tau: NDArray, zeta: float, wn: float) -> NDArray:
    """Unit step response of wn^2 / (s^2 + 2 zeta wn s + wn^2), tau >= 0."""
    wd = wn * np.sqrt(1 - zeta**2)
    phi = np.arccos(zeta)
    return 1 - np.exp(-zeta * wn * tau) / np.sqrt(1 - zeta**2) * np.sin(wd * tau + phi)


def _exact_settling(zeta: float, wn: float, band: float) -> float:
    """Last time |y - 1| = band for the unit second-order response (band as fraction)."""
    sigma, wd = zeta * wn, wn * np.sqrt(1 - zeta**2)
    phi = np.arccos(zeta)
    # extrema of y at k pi / wd with |y - 1| = exp(-sigma k pi / wd); last one above band:
    k = math.floor(math.log(1 / band) / (sigma * np.pi / wd))
    t_ext = k * np.pi / wd
    t_zero = ((k + 1) * np.pi - phi) / wd  # next zero crossing of the error
    return brentq(
        lambda s: abs(_second_order(np.array(s), zeta, wn) - 1) - band, t_ext, t_zero, xtol=1e-12
    )


@pytest.mark.parametrize("direction", [1.0, -1.0])
@pytest.mark.parametrize("zeta", [0.3, 0.6])
def test_underdamped_setpoint_step(direction: float, zeta: float) -> None:
    wn, step, t0, dt = 0.1, 10.0, 50.0, 0.05
    t = np.arange(0.0, 500.0 + dt / 2, dt)
    sp_old, sp_new = 535.0, 535.0 + direction * step
    sp = np.where(t >= t0, sp_new, sp_old)
    tau = np.clip(t - t0, 0.0, None)
    y = sp_old + direction * step * _second_order(tau, zeta, wn)
    assert find_setpoint_step(sp) == (int(round(t0 / dt)), direction * step)

    m = _metrics(t, y, sp=sp, settle_band_K=0.02 * step)
    overshoot = 100 * np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2))
    assert m["overshoot_pct"] == pytest.approx(overshoot, rel=1e-5)

    ts = _exact_settling(zeta, wn, 0.02)
    assert m["settling_time_s"] == pytest.approx(ts, abs=1e-3)
    envelope = math.log(1 / (0.02 * math.sqrt(1 - zeta**2))) / (zeta * wn)
    assert m["settling_time_s"] <= envelope  # the envelope bounds the true settling time

    # default band: max(1 K, 2 % of 10 K) = 1 K = 10 % of the step
    m_default = _metrics(t, y, sp=sp)
    assert m_default["settling_time_s"] == pytest.approx(_exact_settling(zeta, wn, 0.1), abs=1e-3)

    def y_unit(s: float) -> float:
        return float(_second_order(np.array(s), zeta, wn))

    t_peak = np.pi / (wn * np.sqrt(1 - zeta**2))
    t10 = brentq(lambda s: y_unit(s) - 0.1, 0.0, t_peak, xtol=1e-12)
    t90 = brentq(lambda s: y_unit(s) - 0.9, 0.0, t_peak, xtol=1e-12)
    assert m["rise_time_s"] == pytest.approx(t90 - t10, abs=1e-3)


def test_first_order_step_no_overshoot() -> None:
    tau_c, step, t0 = 40.0, 8.0, 20.0
    t = np.arange(0.0, 600.0, 0.1)
    sp = np.where(t >= t0, SP + step, SP)
    y = SP + step * (1 - np.exp(-np.clip(t - t0, 0.0, None) / tau_c))
    m = _metrics(t, y, sp=sp)
    assert m["overshoot_pct"] == 0.0
    # default band max(1, 0.16) = 1 K: exp(-ts/tau) = 1/8
    assert m["settling_time_s"] == pytest.approx(tau_c * math.log(8.0), abs=1e-4)
    assert m["rise_time_s"] == pytest.approx(tau_c * math.log(9.0), abs=1e-4)


def test_step_never_settles_is_nan() -> None:
    t = np.arange(0.0, 100.0, 0.5)
    sp = np.where(t >= 10.0, SP + 10.0, SP)
    y = SP + 5.0 * (t >= 10.0)  # gets half way and stays there
    m = _metrics(t, y, sp=sp)
    assert math.isnan(m["settling_time_s"])
    assert math.isnan(m["rise_time_s"])  # never reaches 90 %
    assert m["overshoot_pct"] == 0.0


def test_step_window_ends_at_next_step() -> None:
    # +10 K at t=10 s (largest), -4 K at t=300 s, output never follows the second step
    tau_c = 30.0
    t = np.arange(0.0, 400.0, 0.1)
    sp = np.where(t >= 10.0, SP + 10.0, SP)
    sp = np.where(t >= 300.0, SP + 6.0, sp)
    y = SP + 10.0 * (1 - np.exp(-np.clip(t - 10.0, 0.0, None) / tau_c))
    m = _metrics(t, y, sp=sp)
    assert m["settling_time_s"] == pytest.approx(tau_c * math.log(10.0), abs=1e-4)


def test_no_step_or_small_step_gives_nan() -> None:
    t = np.arange(0.0, 50.0, 1.0)
    sp = np.where(t >= 10.0, SP + 0.5, SP)  # 0.5 K < 1 K
    m = _metrics(t, np.full(t.size, SP), sp=sp)
    for key in ("overshoot_pct", "settling_time_s", "rise_time_s"):
        assert math.isnan(m[key])
    assert find_setpoint_step(sp) == (-1, pytest.approx(float("nan"), nan_ok=True))


# ------------------------------------------------------------------------------- valves


def _reversals_reference(v: NDArray, deadband: float) -> int:
    """Sequential backlash reversal counter (the obvious loop) for cross-checking."""
    h = deadband / 2
    y = v[0]
    last_dir = 0
    count = 0
    for x in v[1:]:
        new = min(max(y, x - h), x + h)
        if new != y:
            d = 1 if new > y else -1
            if last_dir and d != last_dir:
                count += 1
            last_dir = d
            y = new
    return count


def _triangle(t: NDArray, lo: float, hi: float, period: float) -> NDArray:
    phase = (t % period) / period
    return lo + (hi - lo) * (1 - np.abs(2 * phase - 1))  # starts at lo, peak at mid-period


def test_valve_sawtooth_travel_and_reversals() -> None:
    n_periods, period = 7, 40.0
    t = np.arange(0.0, n_periods * period + 0.5, 1.0)
    v = _triangle(t, 0.2, 0.8, period)
    m = _metrics(t, np.full(t.size, SP), valve=v)
    assert m["valve_travel"] == pytest.approx(2 * 0.6 * n_periods, rel=1e-12)
    assert m["valve_reversals"] == 2 * n_periods - 1  # N peaks, N-1 interior troughs
    assert m["valve_saturated_s"] == 0.0

    # jitter below the deadband (peak-to-peak 0.0016 < 0.002) adds no reversals, even
    # on a fine grid where the jitter exceeds the per-sample movement (0.0003) ...
    rng = np.random.default_rng(1)
    tf = np.arange(0.0, n_periods * period + 0.005, 0.01)
    noisy = _triangle(tf, 0.2, 0.8, period) + rng.uniform(-0.0008, 0.0008, tf.size)
    m_noisy = _metrics(tf, np.full(tf.size, SP), valve=noisy)
    assert m_noisy["valve_reversals"] == 2 * n_periods - 1
    # ... while counting every sign change would see hundreds
    raw = _metrics(tf, np.full(tf.size, SP), valve=noisy, reversal_deadband=0.0)
    assert raw["valve_reversals"] > 10 * n_periods


def test_slow_valve_oscillation_with_tiny_moves_counts() -> None:
    # 0.05 % per sample (below the 0.2 % deadband) but 10 % swings: reversals must count
    t = np.arange(0.0, 2000.0 + 0.5, 1.0)
    v = _triangle(t, 0.4, 0.5, 400.0)
    assert np.max(np.abs(np.diff(v))) < 0.002
    m = _metrics(t, np.full(t.size, SP), valve=v)
    assert m["valve_reversals"] == 2 * 5 - 1


def test_pure_noise_valve_has_no_reversals() -> None:
    rng = np.random.default_rng(2)
    t = np.arange(0.0, 1000.0, 1.0)
    v = 0.3 + rng.uniform(-0.0009, 0.0009, t.size)
    assert _metrics(t, np.full(t.size, SP), valve=v)["valve_reversals"] == 0.0


@pytest.mark.parametrize("deadband", [0.0, 0.002, 0.01, 0.05])
def test_reversals_match_sequential_reference(deadband: float) -> None:
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 3000.0, 1.0)
    v = np.clip(0.5 + np.cumsum(rng.normal(0.0, 0.004, t.size)), 0.0, 1.0)
    m = _metrics(t, np.full(t.size, SP), valve=v, reversal_deadband=deadband)
    assert m["valve_reversals"] == _reversals_reference(v, deadband)


def test_valve_pinned_closed_and_open() -> None:
    # 0 for t in [0, 30], ramp 0.02/s to 1 at t = 80, held open until t = 99
    t = np.arange(0.0, 100.0, 1.0)
    v = np.clip((t - 30.0) * 0.02, 0.0, 1.0)
    m = _metrics(t, np.full(t.size, SP), valve=v)
    # <= 0.005 until t = 30.25, >= 0.995 from t = 79.75 to 99
    assert m["valve_saturated_s"] == pytest.approx(30.25 + 19.25, rel=1e-12)
    assert m["valve_travel"] == pytest.approx(1.0)
    assert m["valve_reversals"] == 0.0


def test_valve_pinned_at_zero_then_step() -> None:
    t = np.arange(0.0, 60.0, 0.5)
    v = np.where(t < 20.0, 0.0, 0.3)  # jump between t=19.5 and t=20
    m = _metrics(t, np.full(t.size, SP), valve=v)
    assert m["valve_saturated_s"] == pytest.approx(19.5 + 0.5 * 0.005 / 0.3, rel=1e-12)


def test_multiple_valves_are_summed() -> None:
    t = np.arange(0.0, 100.0, 1.0)
    v1 = np.clip((t - 30.0) * 0.02, 0.0, 1.0)
    v2 = _triangle(t, 0.2, 0.8, 33.0)
    m1 = _metrics(t, np.full(t.size, SP), valve=v1)
    m2 = _metrics(t, np.full(t.size, SP), valve=v2)
    both = _metrics(t, np.full(t.size, SP), valve=np.column_stack([v1, v2]))
    for key in ("valve_travel", "valve_reversals", "valve_saturated_s"):
        assert both[key] == pytest.approx(m1[key] + m2[key], rel=1e-12), key


def test_spray_used() -> None:
    t = np.array([0.0, 10.0, 25.0, 60.0, 100.0])
    flow = 0.5 + 0.02 * t  # linear: the trapezoid rule is exact
    m = _metrics(t, np.full(t.size, SP), flow=flow)
    assert m["spray_used_kg"] == pytest.approx(0.5 * 100 + 0.01 * 100**2, rel=1e-12)
    m2 = _metrics(t, np.full(t.size, SP), flow=np.column_stack([flow, np.full(t.size, 2.0)]))
    assert m2["spray_used_kg"] == pytest.approx(m["spray_used_kg"] + 200.0, rel=1e-12)


# ------------------------------------------------------------------------- bad input


def _good(n: int = 10) -> list[NDArray]:
    t = np.arange(float(n))
    return [t, np.full(n, SP), np.full(n, SP), np.full(n, 0.5), np.zeros(n)]


NAMES = ["time_s", "outlet_temp_C", "setpoint_C", "spray_valve", "spray_flow_kg_s"]


@pytest.mark.parametrize("which", range(5))
def test_mismatched_length_raises(which: int) -> None:
    args = _good()
    args[which] = args[which][:-1]
    match = "has 10 samples but" if which == 0 else f"{NAMES[which]} has 9 samples"
    with pytest.raises(ValueError, match=match):
        trajectory_metrics(*args)


@pytest.mark.parametrize("which", range(5))
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_raises(which: int, bad: float) -> None:
    args = _good()
    args[which] = args[which].copy()
    args[which][3] = bad
    with pytest.raises(ValueError, match=f"{NAMES[which]} contains non-finite"):
        trajectory_metrics(*args)


def test_too_few_samples_raises() -> None:
    with pytest.raises(ValueError, match="at least 2 samples"):
        trajectory_metrics(*_good(1))


@pytest.mark.parametrize("bad_time", [[0.0, 1.0, 1.0, 2.0], [0.0, 2.0, 1.0, 3.0]])
def test_non_increasing_time_raises(bad_time: list[float]) -> None:
    args = _good(4)
    args[0] = np.array(bad_time)
    with pytest.raises(ValueError, match="strictly increasing"):
        trajectory_metrics(*args)


def test_other_bad_inputs_raise() -> None:
    args = _good()
    with pytest.raises(ValueError, match="one-dimensional"):
        trajectory_metrics(args[0][:, None], *args[1:])
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        trajectory_metrics(*args[:3], np.full(10, 50.0), args[4])  # percent, not fraction
    with pytest.raises(ValueError, match="bands_K"):
        trajectory_metrics(*args, bands_K=(5.0, -1.0))
    with pytest.raises(ValueError, match="settle_band_K"):
        trajectory_metrics(*args, settle_band_K=0.0)


# ------------------------------------------------------------------- step response


TABLE = {  # Tu/T, Tg/T, t50/T, t90/T of 1 / (1 + T s)^n (tabulated values of the lags)
    2: (0.282, 2.718, 1.679, 3.890),
    3: (0.805, 3.695, 2.675, 5.323),
    4: (1.425, 4.463, 3.673, 6.681),
    6: (2.811, 5.699, 5.671, 9.275),
}


def _ptn(t: NDArray, gain: float, T: float, n: int, t_step: float = 0.0) -> NDArray:
    """Step response of gain / (1 + T s)^n: gain * P(n, (t - t_step) / T)."""
    return gain * gammainc(n, np.clip(t - t_step, 0.0, None) / T)


@pytest.mark.parametrize("n", sorted(TABLE))
def test_step_response_ptn_table(n: int) -> None:
    T = 10.0
    t = np.arange(0.0, (n + 12 * np.sqrt(n) + 20) * T, T / 20)
    m = step_response_metrics(t, _ptn(t, 1.0, T, n))
    tu, tg, t50, t90 = TABLE[n]
    assert m["gain"] == pytest.approx(1.0, abs=1e-6)
    assert m["Tu_s"] / T == pytest.approx(tu, rel=5e-3)
    assert m["Tg_s"] / T == pytest.approx(tg, rel=5e-3)
    assert m["t50_s"] / T == pytest.approx(t50, rel=5e-3)
    assert m["t90_s"] / T == pytest.approx(t90, rel=5e-3)

    # analytic: inflection at (n-1) T with slope (n-1)^(n-1) e^-(n-1) / (n-1)! / T
    tg_exact = math.factorial(n - 1) / (n - 1) ** (n - 1) * math.e ** (n - 1)
    tu_exact = (n - 1) - gammainc(n, n - 1) * tg_exact
    assert m["Tg_s"] / T == pytest.approx(tg_exact, rel=1e-4)
    assert m["Tu_s"] / T == pytest.approx(tu_exact, rel=1e-4)
    assert m["t50_s"] / T == pytest.approx(gamma.ppf(0.5, n), rel=1e-4)
    assert m["t90_s"] / T == pytest.approx(gamma.ppf(0.9, n), rel=1e-4)


@pytest.mark.parametrize(
    ("gain", "T", "n", "tu", "tg", "t90"),
    [(2.09, 22.3, 4, 31.8, 99.5, 149.0), (-2.01, 16.0, 2, 4.5, 43.5, 62.2)],
)
def test_step_response_reference_examples(
    gain: float, T: float, n: int, tu: float, tg: float, t90: float
) -> None:
    # the sections of Zhang et al. 2012 at rated load (docs/references.md, Cascade300MW-v0),
    # with an offset, pre-step samples and t_step off the grid
    t_step = 100.3
    t = np.arange(0.0, t_step + 40 * T, 0.25)
    y = 480.0 + _ptn(t, gain, T, n, t_step)
    m = step_response_metrics(t, y, t_step=t_step)
    assert m["gain"] == pytest.approx(gain, rel=1e-6)
    assert m["Tu_s"] == pytest.approx(tu, rel=5e-3)
    assert m["Tg_s"] == pytest.approx(tg, rel=5e-3)
    assert m["t90_s"] == pytest.approx(t90, rel=5e-3)


def test_step_response_nonuniform_and_first_order() -> None:
    rng = np.random.default_rng(4)
    T = 5.0
    t = np.concatenate([[0.0], np.sort(rng.uniform(0.0, 30 * T, 6000))])
    m = step_response_metrics(t, _ptn(t, 3.0, T, 3))
    assert m["Tg_s"] / T == pytest.approx(TABLE[3][1], rel=1e-3)
    assert m["Tu_s"] / T == pytest.approx(TABLE[3][0], rel=1e-3)
    # first order: tangent at the step, Tu = 0, Tg = T
    t1 = np.arange(0.0, 20 * T, T / 50)
    m1 = step_response_metrics(t1, _ptn(t1, 1.0, T, 1))
    assert m1["Tu_s"] == pytest.approx(0.0, abs=1e-4 * T)
    assert m1["Tg_s"] == pytest.approx(T, rel=1e-4)
    assert m1["t50_s"] == pytest.approx(T * math.log(2), rel=1e-4)


def test_step_response_bad_input() -> None:
    t = np.arange(0.0, 10.0)
    with pytest.raises(ValueError, match="zero gain"):
        step_response_metrics(t, np.ones(10))
    with pytest.raises(ValueError, match="t_step"):
        step_response_metrics(t, t, t_step=20.0)
    with pytest.raises(ValueError, match="y has 9 samples"):
        step_response_metrics(t, t[:-1])
    with pytest.raises(ValueError, match="non-finite"):
        step_response_metrics(t, np.where(t == 3.0, np.nan, t))
    with pytest.raises(ValueError, match="strictly increasing"):
        step_response_metrics(t[::-1], t)


def test_quiet_peak_to_peak_reads_the_swing_after_the_quiet_start():
    t = np.arange(0.0, 3600.0, 2.0)
    e = np.where(t < 1800.0, 20.0 * np.sin(t / 50.0), 1.5 * np.sin(2 * np.pi * t / 240.0))
    p2p = metrics.quiet_peak_to_peak(t, e, 1800.0)
    assert p2p == pytest.approx(3.0, abs=1e-3)  # the cycle's swing, not the transient's
    assert metrics.quiet_peak_to_peak(t, e, 0.0) == pytest.approx(40.0, abs=0.1)


def test_quiet_peak_to_peak_does_not_apply_to_a_short_stretch():
    t = np.arange(0.0, 3600.0, 2.0)
    e = np.sin(t)
    assert np.isnan(metrics.quiet_peak_to_peak(t, e, 3600.0 - 500.0))
    assert np.isnan(metrics.quiet_peak_to_peak(t, e, 5000.0))
    assert np.isfinite(metrics.quiet_peak_to_peak(t, e, 3600.0 - 700.0))
    with pytest.raises(ValueError, match="finite"):
        metrics.quiet_peak_to_peak(t, e, float("nan"))


def _frac_above_numpy(
    a: NDArray[np.float64], c: NDArray[np.float64], level: float, inclusive: bool
) -> NDArray[np.float64]:
    """The fraction above ``level`` of each linear segment, in numpy (the reference)."""
    d = c - a
    flat = d == 0.0
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        s = (level - a) / np.where(flat, 1.0, d)
    on_flat = (a >= level) if inclusive else (a > level)
    crossed = np.where(d > 0.0, np.clip(1.0 - s, 0.0, 1.0), np.clip(s, 0.0, 1.0))
    return np.where(flat, on_flat.astype(float), crossed)


def test_compiled_band_fractions_equal_the_numpy_formula_bit_for_bit() -> None:
    """The compiled per-interval fractions (which the env's cost reads too) give the bits
    of the numpy formula, denormal slopes and segments on a level included, up to the sign
    of a zero: numpy's clip returns +0.0 for -0.0 before numpy 2.1 (the oldest accepted
    numpy, 2.0, does) and keeps -0.0 after, so the formula's zeros differ across versions
    while every sum of them is the same number."""

    def bits(x: np.ndarray) -> np.ndarray:
        return (x + 0.0).view(np.int64)  # -0.0 + 0.0 is +0.0; every other value unchanged

    from steamtemp_gym.metrics.calculus import frac_above_each, frac_outside_each

    edge = np.array([5.0, -5.0, 0.0, -0.0, 1e-310, -1e-310, 5 + 1e-15, 5 - 1e-15, 1e300, 0.995])
    a, c = (x.ravel() for x in np.meshgrid(edge, edge))
    e = np.random.default_rng(0).normal(0.0, 8.0, 20_000)
    for e0, e1 in ((a, c), (e[:-1], e[1:])):
        for level in (5.0, 8.0, 0.995, -0.005, 0.0):
            for inclusive in (False, True):
                want = _frac_above_numpy(e0, e1, level, inclusive)
                got = frac_above_each(e0, e1, level, inclusive=inclusive)
                assert np.array_equal(bits(got), bits(want))
        want = _frac_above_numpy(e0, e1, 5.0, False) + _frac_above_numpy(-e0, -e1, 5.0, False)
        assert np.array_equal(bits(frac_outside_each(e0, e1, 5.0)), bits(want))
