"""The compiled per-row work of an env step, for every row of the batched core
(envs/core.py). The env composes plant + scenario + sensors + reward; per control step:

1. the plant kernel advances every row by dt with the commands held (ZOH) and
   the disturbances evaluated at the start of the step, and fills its outputs;
2. :func:`advance` (one compiled call) moves time, evaluates the scenario
   schedules at the new time (disturbances for the next step, setpoint, noise
   level), adds sensor noise, builds the normalized observation, the reward
   (rewards.py), ``terminated`` (trip band) and ``truncated`` (scenario end).

The coloured heat-absorption disturbance of the scenario (an Ornstein-Uhlenbeck
process, scenarios/__init__.py) is a per-row state ``ou`` advanced by its exact
discretization, x_k+1 = a x_k + s sqrt(1 - a^2) n_k with a = exp(-dt/tau), and added
to the heat-absorption bias the plant receives.

Sensor noise is counter-based (steamtemp_gym/rng.py: a pure function of the
row's key, the step counter and the channel), so a row's noise depends only on
its seed: the vector env reproduces the single env bit for bit, whatever the
batch size. Plants with internal random disturbances get the same key through
``Plant.seed_rows``.
"""

from __future__ import annotations

import numpy as np

from steamtemp_gym import scenarios as sc
from steamtemp_gym._jit import njit
from steamtemp_gym.envs.cost import interval_cost
from steamtemp_gym.plants.base import D_FOULING, D_HEAT_BIAS, D_LOAD, D_LOAD_RATE, D_SPRAY_T
from steamtemp_gym.rewards import N_WEIGHTS, non_finite_reward, row_reward
from steamtemp_gym.rng import gauss
from steamtemp_gym.signals import OBS_LIMIT, T0_K
from steamtemp_gym.slots import slots

N_CH = len(sc.CHANNELS)
# channel indices (order of scenarios.CHANNELS)
C_LOAD, C_SP, C_BIAS, C_FOUL, C_SPRAYT = 0, 1, 2, 3, 4
MIN_BREAKPOINTS = 64
#: per-row episode values in EnvState.ep (envs/state.py)
E_TIME, E_DUR, E_NOISE, E_OU_A, E_OU_B = 0, 1, 2, 3, 4
#: EnvState.ints: the output indices of the outlet, its measurement and the design spray (-1:
#: the plant declares none), then where each index list of ints starts (``end``: where the
#: last one ends); the lists are output indices of the observed signals, valves, sprays,
#: secondary temperatures and info values.
H = slots(
    "IntsHeader",
    "outlet",
    "measured",
    "design_spray",
    "obs",
    "valves",
    "sprays",
    "secondary",
    "info",
    "end",
)
#: EnvState.cfg: these scalars, then the reward weights (rewards.W) and the secondary setpoints.
CFG = slots("Config", "dt", "setpoint", "trip_below_K", "trip_above_K", "spray_scale")
N_CFG = len(CFG)
#: Why an episode terminated (``info["trip_reason"]``; EnvState.trip holds the index): the
#: true outlet above or below the plant's trip band, or the plant left its valid region (a
#: non-finite state or output; its observation is then 0 and its reward that of a trip at
#: the lower band edge).
TRIP_REASONS = ("", "outlet_above_trip_band", "outlet_below_trip_band", "non_finite_state")
TRIP_ABOVE, TRIP_BELOW, TRIP_NON_FINITE = 1, 2, 3
#: counter-based random channel of the coloured heat-absorption disturbance (observation
#: noise uses channels 0 .. n_obs - 1)
OU_CHANNEL = 31


@njit(cache=True, error_model="numpy")
def _interp(bt, bv, n, t):
    """Piecewise-linear schedule value and slope at t (held constant at the ends)."""
    if t <= bt[0] or n == 1:
        return bv[0], 0.0
    if t >= bt[n - 1]:
        return bv[n - 1], 0.0
    k = 1
    while bt[k] < t:
        k += 1
    # bt[k-1] < t <= bt[k]; a jump (equal times) is taken at its time
    dt = bt[k] - bt[k - 1]
    if dt <= 0.0:
        return bv[k], 0.0
    slope = (bv[k] - bv[k - 1]) / dt
    return bv[k - 1] + slope * (t - bt[k - 1]), slope


@njit(cache=True, error_model="numpy")
def schedules(b, s, t, bp_t, bp_v, bp_n, sp_nom, ou, D, sp):
    """Disturbances D[b] and setpoint sp[b] of row b at time t from schedule table slot s
    (ou: coloured heat-absorption bias, added)."""
    load, rate = _interp(bp_t[s, C_LOAD], bp_v[s, C_LOAD], bp_n[s, C_LOAD], t)
    D[b, D_LOAD] = load
    D[b, D_LOAD_RATE] = rate
    D[b, D_HEAT_BIAS] = _interp(bp_t[s, C_BIAS], bp_v[s, C_BIAS], bp_n[s, C_BIAS], t)[0] + ou[b]
    D[b, D_FOULING] = _interp(bp_t[s, C_FOUL], bp_v[s, C_FOUL], bp_n[s, C_FOUL], t)[0]
    D[b, D_SPRAY_T] = _interp(bp_t[s, C_SPRAYT], bp_v[s, C_SPRAYT], bp_n[s, C_SPRAYT], t)[0]
    sp[b] = sp_nom + _interp(bp_t[s, C_SP], bp_v[s, C_SP], bp_n[s, C_SP], t)[0]


@njit(cache=True, error_model="numpy")
def observe(b, Z, D, sp, ep, key, counter, obs_cs, obs_idx, i_meas, obs, meas):
    """Write the normalized observation ``obs[b]`` of row b (noisy measurements, setpoint,
    error, load) from the state's arrays (envs/state.py: EnvState), its noise of standard
    deviation ``ep[b, E_NOISE]`` (K); ``obs_idx``: the observed outputs, ``i_meas``: the
    outlet thermocouple's (:func:`obs_indices`). It takes only the arrays it reads and
    writes: each array of a compiled function's signature costs compile time.

    ``meas[b]`` receives what the outlet thermocouple reported (noise included). A
    non-finite value (a plant that left its valid region; the step then trips) is observed
    as 0 (the signal's centre), so no NaN ever reaches an agent.
    """
    noise = ep[b, E_NOISE]
    n = obs_idx.shape[0]
    v_meas = 0.0
    for j in range(n):
        v = Z[b, obs_idx[j]]
        if obs_cs[j, 2] > 0.0 and noise > 0.0:
            v += noise * gauss(key[b], counter[b], j)
        if obs_idx[j] == i_meas:
            v_meas = v
        obs[b, j] = _normalized(v, obs_cs[j, 0], obs_cs[j, 1])
    meas[b] = v_meas
    obs[b, n] = _normalized(sp[b], obs_cs[n, 0], obs_cs[n, 1])
    obs[b, n + 1] = _normalized(sp[b] - v_meas, 0.0, T0_K)
    obs[b, n + 2] = _normalized(D[b, D_LOAD], 0.75, 0.25)


@njit(cache=True, error_model="numpy")
def _normalized(v, center, scale):
    """(v - center) / scale clipped to the transmitter range; 0 for a non-finite v."""
    o = (v - center) / scale
    if not np.isfinite(o):
        return 0.0
    return min(max(o, -OBS_LIMIT), OBS_LIMIT)


def ou_coefficients(std: float, tau_s: float, dt: float) -> tuple[float, float]:
    """(a, b) of the exact OU step x_k+1 = a x_k + b n_k (stationary std, correlation tau)."""
    a = float(np.exp(-dt / tau_s))
    return a, std * float(np.sqrt(1.0 - a * a))


@njit(cache=True, error_model="numpy", nogil=True)  # threads: plants/threads.py
def advance(s):
    """Everything after the plant step, for every row of the state ``s`` (envs/state.py:
    EnvState; see module docstring): time (``s.ep``), the coloured disturbance (``s.ou``)
    and the counter advanced in place; the schedules, observation, thermocouple reading,
    info values (:func:`fill_info`; the previous error read from ``s.info`` first for the
    interval's cost, envs/cost.py), reward, trip code (:data:`TRIP_REASONS` index; 0:
    running) and truncation written; the commands kept in ``s.U_prev``.
    """
    X, Z, U, U_prev, ep, ints, cfg = s.X, s.Z, s.U, s.U_prev, s.ep, s.ints, s.cfg
    i_out, i_design = ints[H.outlet], ints[H.design_spray]
    obs_idx, i_meas = obs_indices(ints)
    info_idx, s_idx = info_indices(ints)
    sec_idx = ints[ints[H.secondary] : ints[H.info]]
    n_info = info_idx.shape[0]
    dt, sp_nom, s_scale = cfg[CFG.dt], cfg[CFG.setpoint], cfg[CFG.spray_scale]
    trip_lo, trip_hi = cfg[CFG.trip_below_K], cfg[CFG.trip_above_K]
    w = cfg[N_CFG : N_CFG + N_WEIGHTS]
    sec_sp = cfg[N_CFG + N_WEIGHTS :]
    # every array taken out of the state once: a field read inside the loop takes and
    # drops a reference per row (22 % of Cascade300MW's step at 4096 rows)
    counter, ou, sp, D, key, slot = s.counter, s.ou, s.sp, s.D, s.key, s.slot
    bp_t, bp_v, bp_n, obs_cs = s.bp_t, s.bp_v, s.bp_n, s.obs_cs
    obs, meas, info = s.obs, s.meas, s.info
    trip, truncated, reward = s.trip, s.truncated, s.reward
    for b in range(Z.shape[0]):
        counter[b] += 1
        ep[b, E_TIME] = counter[b] * dt  # counted, not summed: no drift over long episodes
        if ep[b, E_OU_B] > 0.0:
            ou[b] = ep[b, E_OU_A] * ou[b] + ep[b, E_OU_B] * gauss(key[b], counter[b], OU_CHANNEL)
        schedules(b, slot[b], ep[b, E_TIME], bp_t, bp_v, bp_n, sp_nom, ou, D, sp)
        observe(b, Z, D, sp, ep, key, counter, obs_cs, obs_idx, i_meas, obs, meas)
        # the cost of the interval from the last info's error to this step's (envs/cost.py)
        cost = interval_cost(_info_error(b, info, n_info), Z[b, i_out] - sp[b])
        fill_info(b, Z, D, sp, ep, meas, info_idx, s_idx, cost, info)
        e = sp[b] - Z[b, i_out]
        code = TRIP_ABOVE if e < -trip_hi else (TRIP_BELOW if e > trip_lo else 0)
        if not (_finite(X, b) and _finite(Z, b)):
            code = TRIP_NON_FINITE
        term = code != 0
        trip[b] = code
        truncated[b] = ep[b, E_TIME] >= ep[b, E_DUR] - 1e-9
        if code == TRIP_NON_FINITE:
            reward[b] = non_finite_reward(trip_lo, w)
        else:
            reward[b] = row_reward(
                b, Z, U, U_prev, e, term, s_idx, i_design, s_scale, sec_idx, sec_sp, w
            )
        for j in range(U.shape[1]):
            U_prev[b, j] = U[b, j]


@njit(cache=True, error_model="numpy")
def _finite(A, b):
    """True if every entry of row b of A is finite."""
    for i in range(A.shape[1]):
        if not np.isfinite(A[b, i]):
            return False
    return True


@njit(cache=True, error_model="numpy")
def fill_info(b, Z, D, sp, ep, meas, cols, sprays, cost, info):
    """Fill ``info[b]`` from the state's arrays: row b's outputs ``cols``, then
    (envs/state.py: INFO_TAIL) the measured temperature, time, setpoint, load, the sum of
    the spray outputs ``sprays`` and the interval's ``cost`` twice (the total and its one
    component, envs/cost.py); the index arrays of :func:`info_indices`."""
    k = cols.shape[0]
    for j in range(k):
        info[b, j] = Z[b, cols[j]]
    info[b, k] = meas[b]
    info[b, k + 1] = ep[b, E_TIME]
    info[b, k + 2] = sp[b]
    info[b, k + 3] = D[b, D_LOAD]
    spray = 0.0
    for j in range(sprays.shape[0]):
        spray += Z[b, sprays[j]]
    info[b, k + 4] = spray
    info[b, k + 5] = cost
    info[b, k + 6] = cost


@njit(cache=True, error_model="numpy")
def obs_indices(ints):
    """(the observed outputs, the outlet thermocouple's output) of the index table ``ints``."""
    return ints[ints[H.obs] : ints[H.valves]], ints[H.measured]


@njit(cache=True, error_model="numpy")
def info_indices(ints):
    """(the info columns' outputs, the spray outputs) of the index table ``ints``."""
    return ints[ints[H.info] : ints[H.end]], ints[ints[H.sprays] : ints[H.secondary]]


@njit(cache=True, error_model="numpy")
def _info_error(b, info, k):
    """``outlet_temp_C - setpoint_C`` of row b's info (k: the number of plant columns; the
    first is the outlet, state.info_sources), the error :func:`fill_info` last wrote."""
    return info[b, 0] - info[b, k + 2]


@njit(cache=True, error_model="numpy")
def to_commands(A, U):
    """Actuator commands U = (clip(A, -1, 1) + 1) / 2 (openings in [0, 1]).

    Returns False, leaving U untouched, if A holds a NaN or an infinity.
    """
    for b in range(A.shape[0]):
        for j in range(A.shape[1]):
            if not np.isfinite(A[b, j]):
                return False
    for b in range(A.shape[0]):
        for j in range(A.shape[1]):
            U[b, j] = 0.5 * (min(max(A[b, j], -1.0), 1.0) + 1.0)
    return True
