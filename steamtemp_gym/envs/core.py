"""The batched simulation core shared by SteamTempEnv (a batch of one) and the vector env.

Composition (DESIGN.md): plant + scenario + sensors + reward. Per control step:

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
from numba import njit

from steamtemp_gym import scenarios as sc
from steamtemp_gym.plants.base import N_DIST, Plant
from steamtemp_gym.rewards import N_WEIGHTS, RewardConfig, reward, temperature_cost
from steamtemp_gym.rng import gauss
from steamtemp_gym.signals import OBS_LIMIT, T0_K, for_plant

N_CH = len(sc.CHANNELS)
# channel indices (order of scenarios.CHANNELS)
C_LOAD, C_SP, C_BIAS, C_FOUL, C_SPRAYT = 0, 1, 2, 3, 4
MIN_BREAKPOINTS = 64
#: per-row episode values in Core.ep
E_TIME, E_DUR, E_NOISE, E_OU_A, E_OU_B = 0, 1, 2, 3, 4
#: length of the header of Core.ints (before the index lists)
N_HEAD = 7
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
def eval_schedules(b, t, bp_t, bp_v, bp_n, sp_nom, ou, D, sp):
    """Disturbances D[b] and setpoint sp[b] of row b at time t (ou: coloured bias, added)."""
    load, rate = _interp(bp_t[b, C_LOAD], bp_v[b, C_LOAD], bp_n[b, C_LOAD], t)
    D[b, 0] = load
    D[b, 1] = rate
    D[b, 2] = _interp(bp_t[b, C_BIAS], bp_v[b, C_BIAS], bp_n[b, C_BIAS], t)[0] + ou[b]
    D[b, 3] = _interp(bp_t[b, C_FOUL], bp_v[b, C_FOUL], bp_n[b, C_FOUL], t)[0]
    D[b, 4] = _interp(bp_t[b, C_SPRAYT], bp_v[b, C_SPRAYT], bp_n[b, C_SPRAYT], t)[0]
    sp[b] = sp_nom + _interp(bp_t[b, C_SP], bp_v[b, C_SP], bp_n[b, C_SP], t)[0]


@njit(cache=True, error_model="numpy")
def observe(b, Z, obs_idx, obs_cs, i_meas, key, counter, noise, sp, D, obs):
    """Write the normalized observation of row b (noisy measurements, setpoint, error, load)."""
    n = obs_idx.shape[0]
    meas = 0.0
    for j in range(n):
        v = Z[b, obs_idx[j]]
        if obs_cs[j, 2] > 0.0 and noise[b] > 0.0:
            v += noise[b] * gauss(key[b], counter[b], j)
        if obs_idx[j] == i_meas:
            meas = v
        o = (v - obs_cs[j, 0]) / obs_cs[j, 1]
        obs[b, j] = min(max(o, -OBS_LIMIT), OBS_LIMIT)
    extra = ((sp[b] - obs_cs[n, 0]) / obs_cs[n, 1], (sp[b] - meas) / T0_K, (D[b, 0] - 0.75) / 0.25)
    for j in range(3):
        obs[b, n + j] = min(max(extra[j], -OBS_LIMIT), OBS_LIMIT)


def ou_coefficients(std: float, tau_s: float, dt: float) -> tuple[float, float]:
    """(a, b) of the exact OU step x_k+1 = a x_k + b n_k (stationary std, correlation tau)."""
    a = float(np.exp(-dt / tau_s))
    return a, std * float(np.sqrt(1.0 - a * a))


@njit(cache=True, error_model="numpy")
def advance(Z, U, U_prev, bp_t, bp_v, bp_n, ep, ou, key, counter, ints, cfg, obs_cs, D, sp, obs,
            out):  # fmt: skip
    """Everything after the plant step, for every row (see module docstring).

    Args:
        ep: (B, 5) per-row [time_s, duration_s, noise_std_C, ou_a, ou_b] (ou_coefficients);
            time advanced in place.
        ou: (B,) coloured heat-absorption disturbance, advanced in place.
        ints: [i_outlet, i_measured, n_obs_plant, n_valves, n_sprays, n_secondary, i_design,
            obs idx..., valve idx..., spray idx..., secondary idx...] (output indices;
            i_design < 0: the plant declares no design spray).
        cfg: [dt, sp_nom, trip_below_K, trip_above_K, spray_scale, reward weights...,
            secondary setpoints...].
        out: (B, 3) written: [reward, terminated, truncated].
    """
    i_out, i_meas, n_obs, n_v, n_s, n_sec = ints[0], ints[1], ints[2], ints[3], ints[4], ints[5]
    i_design = ints[6]
    o = N_HEAD
    obs_idx = ints[o : o + n_obs]
    s_idx = ints[o + n_obs + n_v : o + n_obs + n_v + n_s]
    sec_idx = ints[o + n_obs + n_v + n_s : o + n_obs + n_v + n_s + n_sec]
    dt, sp_nom, trip_lo, trip_hi, s_scale = cfg[0], cfg[1], cfg[2], cfg[3], cfg[4]
    w = cfg[5 : 5 + N_WEIGHTS]
    sec_sp = cfg[5 + N_WEIGHTS :]
    noise = ep[:, E_NOISE]
    for b in range(Z.shape[0]):
        ep[b, E_TIME] += dt
        counter[b] += 1
        if ep[b, E_OU_B] > 0.0:
            ou[b] = ep[b, E_OU_A] * ou[b] + ep[b, E_OU_B] * gauss(key[b], counter[b], OU_CHANNEL)
        eval_schedules(b, ep[b, E_TIME], bp_t, bp_v, bp_n, sp_nom, ou, D, sp)
        observe(b, Z, obs_idx, obs_cs, i_meas, key, counter, noise, sp, D, obs)
        e = sp[b] - Z[b, i_out]
        term = not (-trip_hi <= e <= trip_lo)  # also catches NaN
        spray = 0.0
        for j in range(n_s):
            spray += Z[b, s_idx[j]]
        if i_design >= 0:  # only spray above the design spray of this operating point
            spray = max(spray - Z[b, i_design], 0.0)
        spray /= s_scale
        move = 0.0
        for j in range(U.shape[1]):
            move += abs(U[b, j] - U_prev[b, j])
            U_prev[b, j] = U[b, j]
        sec = 0.0
        for j in range(n_sec):
            sec += temperature_cost(sec_sp[j] - Z[b, sec_idx[j]], w)
        out[b, 0] = reward(e, sec, spray, move, term, w)
        out[b, 1] = 1.0 if term else 0.0
        out[b, 2] = 1.0 if ep[b, E_TIME] >= ep[b, E_DUR] - 1e-9 else 0.0


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


class Core:
    """Batched state of B copies of one plant under per-row scenarios.

    Args:
        plant: The plant instance (parameters fixed).
        batch: Number of rows.
        reward_cfg: Reward weights.
    """

    def __init__(self, plant: Plant, batch: int, reward_cfg: RewardConfig) -> None:
        self.plant = plant
        self.B = batch
        self.signals = for_plant(plant)
        B, n_x, n_z, n_u = batch, plant.n_x, plant.n_z, plant.n_u
        self.X = np.zeros((B, n_x))
        self.Z = np.zeros((B, n_z))
        self.U = np.zeros((B, n_u))
        self.U_prev = np.zeros((B, n_u))
        self.D = np.zeros((B, N_DIST))
        self.sp = np.zeros(B)
        self.ep = np.zeros((B, 5))
        self.ou = np.zeros(B)
        self.key = np.zeros(B, dtype=np.uint64)
        self.counter = np.zeros(B, dtype=np.int64)
        self.out = np.zeros((B, 3))
        self._alloc_schedules(MIN_BREAKPOINTS)
        observed = [i for i, s in enumerate(plant.outputs) if s.observed]
        if len(observed) >= OU_CHANNEL:
            raise ValueError(f"{plant.id}: at most {OU_CHANNEL - 1} observed outputs")
        self.obs = np.zeros((B, len(observed) + 3), dtype=np.float64)
        self.obs_cs = np.array(
            [[s.center, s.scale, float(s.noisy)] for s in self.signals.observation],
            dtype=np.float64,
        )
        idx = plant.index
        self.i_out = idx[plant.outlet]
        self.valve_idx = [idx[v] for v in plant.valves]
        self.spray_idx = [idx[s] for s in plant.sprays]
        self.ints = np.array(
            [self.i_out, idx[plant.outlet_measured], len(observed), len(plant.valves),
             len(plant.sprays), len(plant.secondary),
             idx[plant.design_spray] if plant.design_spray else -1]
            + observed
            + self.valve_idx
            + self.spray_idx
            + [idx[name] for name, _ in plant.secondary],
            dtype=np.int64,
        )  # fmt: skip
        spray_scale = plant.outputs[self.spray_idx[0]].scale if self.spray_idx else 1.0
        trip_lo, trip_hi = plant.trip_band_K
        self.cfg = np.concatenate(
            [[plant.dt_s, plant.setpoint_C, trip_lo, trip_hi, spray_scale], reward_cfg.to_array(),
             [sp for _, sp in plant.secondary]]
        )  # fmt: skip
        self.scenario: list[sc.Scenario | None] = [None] * B
        self._info_idx = [("outlet_temp_C", self.i_out),
                          ("measured_temp_C", idx[plant.outlet_measured]),
                          ("spray_valve", self.valve_idx[0])]  # fmt: skip
        self._info_idx += [(name, idx[name]) for name in plant.extra_info]
        self._valves = self.valve_idx if len(self.valve_idx) > 1 else None

    def _alloc_schedules(self, k: int) -> None:
        self.bp_t = np.zeros((self.B, N_CH, k))
        self.bp_v = np.zeros((self.B, N_CH, k))
        self.bp_n = np.ones((self.B, N_CH), dtype=np.int64)

    def reset_row(self, b: int, scenario: sc.Scenario, key: int) -> None:
        """Start row b at t = 0 of ``scenario`` in steady state, with noise key ``key``."""
        need = sc.max_breakpoints([scenario])
        if need > self.bp_t.shape[2]:
            old = (self.bp_t, self.bp_v, self.bp_n)
            self._alloc_schedules(need)
            self.bp_t[:, :, : old[0].shape[2]] = old[0]
            self.bp_v[:, :, : old[1].shape[2]] = old[1]
            self.bp_n[:] = old[2]
        sc.pack(scenario, self.bp_t[b], self.bp_v[b], self.bp_n[b])
        self.scenario[b] = scenario
        ou_ab = ou_coefficients(
            scenario.heat_absorption_noise_std,
            scenario.heat_absorption_noise_tau_s,
            self.plant.dt_s,
        )
        self.ep[b] = (0.0, scenario.duration_s, scenario.noise_std_C, *ou_ab)
        self.ou[b] = scenario.heat_absorption_noise_std * gauss(np.uint64(key), 0, OU_CHANNEL)
        self.key[b] = np.uint64(key)
        self.counter[b] = 0
        self.out[b] = 0.0
        eval_schedules(
            b,
            0.0,
            self.bp_t,
            self.bp_v,
            self.bp_n,
            self.plant.setpoint_C,
            self.ou,
            self.D,
            self.sp,
        )
        self.plant.seed_rows(self.X[b : b + 1], self.key[b : b + 1])
        self.plant.steady_state(self.D[b : b + 1], self.sp[b : b + 1], self.X[b : b + 1])
        rows = slice(b, b + 1)  # outputs of the steady state: a zero-length step fills Z
        self.plant.step(self.X[rows], self.U[rows], self.D[rows], self.Z[rows], dt=0.0)
        self.U[b] = self.Z[b, self.valve_idx]
        self.U_prev[b] = self.U[b]
        observe(b, self.Z, self.ints[N_HEAD : N_HEAD + self.ints[2]], self.obs_cs, self.ints[1],
                self.key, self.counter, self.ep[:, E_NOISE], self.sp, self.D, self.obs)  # fmt: skip

    def step(self, A: np.ndarray) -> None:
        """Advance every row by one control interval with actions A (shape checked) in [-1, 1].

        Raises:
            ValueError: A holds NaN or infinite values (nothing is changed).
        """
        if not to_commands(A, self.U):
            raise ValueError(f"action contains NaN or infinite values: {A.tolist()!r}")
        self.plant.step(self.X, self.U, self.D, self.Z)
        advance(
            self.Z, self.U, self.U_prev, self.bp_t, self.bp_v, self.bp_n, self.ep, self.ou,
            self.key, self.counter, self.ints, self.cfg, self.obs_cs, self.D, self.sp, self.obs,
            self.out,
        )  # fmt: skip

    def info_row(self, b: int) -> dict[str, float | np.ndarray]:
        """Physical values of row b in engineering units (floats; an array for several valves)."""
        z = self.Z[b].tolist()
        info = {name: z[i] for name, i in self._info_idx}
        info["time_s"] = float(self.ep[b, 0])
        info["setpoint_C"] = float(self.sp[b])
        info["load"] = float(self.D[b, 0])
        spray = 0.0
        for i in self.spray_idx:
            spray += z[i]
        info["spray_flow_kg_s"] = spray
        if self._valves is not None:
            info["spray_valve"] = np.array([z[i] for i in self.valve_idx])
        return info

    def info_columns(self) -> dict[str, np.ndarray]:
        """Physical values of every row, in engineering units (arrays of shape (B,) or (B, k))."""
        Z = self.Z
        info = {name: Z[:, i].copy() for name, i in self._info_idx}  # same keys as info_row
        info["time_s"] = self.ep[:, 0].copy()
        info["setpoint_C"] = self.sp.copy()
        info["load"] = self.D[:, 0].copy()
        info["spray_flow_kg_s"] = Z[:, self.spray_idx].sum(axis=1)
        if self._valves is not None:
            info["spray_valve"] = Z[:, self._valves]
        return info


def check_action(action, shape: tuple[int, ...]) -> np.ndarray:
    """Check an action batch's shape; return it as a float array of ``shape``.

    Finiteness is checked by :meth:`Core.step` (compiled, before anything changes).
    """
    a = np.asarray(action)
    if a.dtype.kind != "f":
        try:
            a = a.astype(np.float64)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"action must be numeric, got {action!r}") from exc
    if a.shape != shape:
        if a.ndim <= len(shape) and a.size == shape[0] * shape[1]:
            a = a.reshape(shape)
        else:
            raise ValueError(
                f"action has shape {np.shape(action)}, "
                f"expected {shape[1:] if shape[0] == 1 else shape}"
            )
    return a
