"""Conventional cascade PI: the steam temperature control plants run today.

Every actuator gets the loop its plant declares in ``Plant.control_loops``
(inner, outer):

- cascade (inner and outer MAIN or another signal): an outer PI on the outer
  temperature (MAIN: the main-steam error against the setpoint) sets the setpoint
  of the inner (attemperator-outlet) temperature, an inner PI on that temperature
  moves the spray valve: the standard two-loop arrangement of spray attemperation
  (e.g. the cascade of Zhang et al. 2012, whose inner loop is a P controller);
- scheduled (inner, SCHEDULED): a PI holds the inner temperature at a setpoint
  scheduled on the load demand, as first-stage sprays are run: the function
  generator is set at commissioning from the plant's steady states at 40-110 % load
  (:func:`inner_schedule`), so the first stage does not integrate the main-steam
  error a second time;
- inner only (outer None): a PI holds the inner temperature at its start value;
- outer only (inner None): a PI on the outer signal moves the actuator directly (a
  gas recirculation damper holding the reheat temperature).

Actuators without a loop stay where the episode started. Loops are tuned by the
SIMC rules (Skogestad 2003, tau_c = theta) on first-order-plus-dead-time models
read from open-loop step tests of each actuator (baselines/identification.py) at
each load of :data:`GAIN_LOADS` (50, 75 and 100 %): the inner loop on actuator -> inner temperature,
the outer loop of a cascade on inner -> outer temperature (gain K_out/K_in, dead
time and balance time of the outer response less those of the inner one), a
single loop on actuator -> its temperature. The measurement filter's lag is added
to each loop's dead time. Where k loops share the main-steam error, each outer
gain is divided by k so that their sum has the SIMC loop gain. Fixed gains are
commissioned for the whole load range, as a unit without gain scheduling must be:
per loop, the smallest SIMC gain and the longest integral time of the step tests
at the three loads (:func:`commissioned_tuning`). A loop tuned at rated load alone
is poorly damped at half load, where the superheater's dead time and gain are
larger (decay ratios near 1 after a deep ramp). With ``gain_schedule=True`` the
gains follow the load instead (:class:`CascadePIFF`).

Measurement filter: every temperature the loops read goes through a first-order
filter of ``FILTER_S`` = 5 s (the input filter a DCS puts on thermocouples), so
sensor noise does not chatter the valves.

Optional load feed-forward (``load_feedforward=True``, used by
benchmarks/difficulty.py to show the benchmark's headroom; not the plain baseline):
each MAIN cascade adds r_ff = a (L - L_0) + b dL_f/dt + c (F - L) to its inner
(attemperator-outlet) setpoint, with L the load demand (observed), L_f its first-order
filter (time constant: the outer loops' integral time) and, where the plant measures
it, F the firing rate (the boiler-input feed-forward of drum units, whose pressure
loop makes firing overshoot the demand after a ramp). a, b and c are identified by least
squares from the inner-setpoint trend of the plain cascade during a commissioning
ramp (100 -> 60 -> 100 % at 3 %/min, no noise; not an evaluation scenario), the way
a feed-forward is set from a ramp test in auto; the firing term is kept only if the
cascade with it has the smaller peak deviation on that ramp (c = 0 otherwise).

Discrete PI in position form at the plant's control interval, bumpless start
(integrators initialized from the measured actuator positions and
temperatures), anti-windup by conditional integration when the actuator
saturates. The policy sees exactly the observation an agent sees.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from baselines.commissioned import commissioned
from baselines.identification import FOPDT, simc_pi, step_test
from baselines.loops import input_filter, observation_layout, pi_position, restart_rows
from baselines.tuning import Knob
from steamtemp_gym import plants
from steamtemp_gym.plants.base import MAIN, SCHEDULED
from steamtemp_gym.scenarios import Scenario

NO_LOOP = (0.0, np.inf, 0.0, np.inf)
#: Measurement filter time constant (s): a DCS input filter on thermocouples.
FILTER_S = 5.0
#: Loads (fraction) at which the first-stage schedules are read off the steady states.
SCHEDULE_LOADS = np.round(np.arange(0.4, 1.101, 0.1), 2)
#: Loads (fraction) of the step tests behind the load-scheduled gains (``gain_schedule``).
GAIN_LOADS = (0.5, 0.75, 1.0)


def _env(env_id: str, params_json: str, scenario: Any):
    import gymnasium as gym

    return gym.make(env_id, scenario=scenario, params=json.loads(params_json))


@commissioned(maxsize=64)
def _tuning(
    env_id: str, params_json: str, load: float = 1.0
) -> tuple[tuple[float, float, float, float], ...]:
    """(Kc_outer, Ti_outer, Kc_inner, Ti_inner) per action from step tests at ``load``."""
    params = json.loads(params_json)
    plant = plants.make(env_id, **params)
    out = []
    n_main = sum(outer == MAIN for _, outer in plant.control_loops)
    for j, (inner, outer) in enumerate(plant.control_loops):
        outer_sig = (
            None if outer == SCHEDULED else (plant.outlet_measured if outer == MAIN else outer)
        )
        m = step_test(env_id, j, [s for s in (inner, outer_sig) if s], load=load, params=params)
        m = {k: FOPDT(f.K, f.tau_s, f.theta_s + FILTER_S) for k, f in m.items()}
        kc_o, ti_o, kc_i, ti_i = NO_LOOP
        if inner:
            kc_i, ti_i = simc_pi(m[inner])
        if outer_sig and inner:
            mi, mo = m[inner], m[outer_sig]
            kc_o, ti_o = simc_pi(
                FOPDT(
                    K=mo.K / mi.K,
                    tau_s=max(mo.tau_s - mi.tau_s, 0.2 * mo.tau_s),
                    theta_s=max(mo.theta_s - mi.theta_s, plant.dt_s),
                )
            )
        elif outer_sig:
            kc_o, ti_o = simc_pi(m[outer_sig])
        if outer == MAIN:  # loops sharing the main-steam error share its loop gain
            kc_o /= n_main
        out.append((kc_o, ti_o, kc_i, ti_i))
    return tuple(out)


@commissioned(maxsize=16)
def inner_schedule(env_id: str, params_json: str, signal: str) -> tuple[np.ndarray, np.ndarray]:
    """(loads, measured ``signal``) of the undisturbed steady states at SCHEDULE_LOADS."""
    temps = []
    for load in SCHEDULE_LOADS:
        sc = Scenario(name="schedule", duration_s=60.0, load=float(load))
        env = _env(env_id, params_json, sc)
        obs, _ = env.reset(seed=0)
        temps.append(float(env.unwrapped.signals.decode(obs)[signal]))
    return SCHEDULE_LOADS.copy(), np.array(temps)


#: The commissioning ramp the feed-forward is fitted on (not an evaluation scenario).
FF_RAMP = Scenario(
    name="feedforward_commissioning",
    duration_s=3600.0,
    load=((0.0, 1.0), (300.0, 1.0), (1100.0, 0.6), (1900.0, 0.6), (2700.0, 1.0)),
)


def _ramp_run(env: Any, pol: CascadePI) -> tuple[np.ndarray, ...]:
    """Load, inner setpoints, firing minus load and |e| of one commissioning-ramp episode."""
    obs, info = env.reset(seed=0)
    L, V, F, E = [], [], [], []
    while True:
        a, _ = pol.predict(obs)
        obs, _, term, trunc, info = env.step(a)
        L.append(info["load"])
        V.append(pol.inner_setpoint[0].copy())
        F.append(pol.firing(obs)[0] - info["load"] if pol.i_fire is not None else 0.0)
        E.append(abs(info["outlet_temp_C"] - info["setpoint_C"]))
        if term or trunc:
            return np.array(L), np.array(V), np.array(F), np.array(E)


@commissioned(maxsize=64)
def commissioned_tuning(env_id: str, params_json: str) -> np.ndarray:
    """(loops, 4) fixed (Kc_o, Ti_o, Kc_i, Ti_i) for the whole load range: per loop the
    SIMC gain of smallest magnitude and the longest integral time of the step tests at
    :data:`GAIN_LOADS`."""
    g = np.array([_tuning(env_id, params_json, load) for load in GAIN_LOADS], dtype=float)
    out = np.empty(g.shape[1:])
    for kc, ti in ((0, 1), (2, 3)):
        k = np.abs(g[..., kc]).argmin(axis=0)
        out[:, kc] = np.take_along_axis(g[..., kc], k[None], axis=0)[0]
        out[:, ti] = g[..., ti].max(axis=0)
    out.setflags(write=False)
    return out


def gain_table(env_id: str, params_json: str) -> np.ndarray:
    """(len(GAIN_LOADS), loops, 4) table of (Kc_o, Ki_o, Kc_i, Ki_i), Ki = Kc / Ti (0 for no
    integral), from the step tests at each of :data:`GAIN_LOADS`."""
    g = np.array([_tuning(env_id, params_json, load) for load in GAIN_LOADS], dtype=float)
    g[..., 1] = np.where(np.isfinite(g[..., 1]), g[..., 0] / g[..., 1], 0.0)
    g[..., 3] = np.where(np.isfinite(g[..., 3]), g[..., 2] / g[..., 3], 0.0)
    return g


@commissioned(maxsize=16)
def _feedforward(
    env_id: str, params_json: str, scheduled: bool = False
) -> tuple[np.ndarray, float]:
    """((a, b, c) per action, zeros for non-MAIN loops; tau_f):
    r_ff = a (L - L0) + b dL_f/dt + c (F - L), fitted on the cascade without feed-forward
    (with load-scheduled gains if ``scheduled``)."""
    env = _env(env_id, params_json, FF_RAMP)
    pol = CascadePI(env, gain_schedule=scheduled)
    plant = env.unwrapped.plant
    main = [j for j, (_, o) in enumerate(plant.control_loops) if o == MAIN]
    tau_f = max([pol.gains[j][1] for j in main if np.isfinite(pol.gains[j][1])] + [plant.dt_s])
    L, V, F, _ = _ramp_run(env, pol)
    best, best_peak = None, np.inf
    for cols in ((0, 1), (0, 1, 2)) if pol.i_fire is not None else ((0, 1),):
        A = np.column_stack([L - L[0], _filtered_rate(L, plant.dt_s, tau_f), F])[:, cols]
        coef = np.zeros((len(plant.control_loops), 3))
        for j in main:
            coef[j, list(cols)], *_ = np.linalg.lstsq(A, V[:, j] - V[0, j], rcond=None)
        trial = CascadePI(env, feedforward=(coef, tau_f), gain_schedule=scheduled)
        peak = _ramp_run(env, trial)[3].max()
        if peak < best_peak:
            best, best_peak = coef, peak
    return best, tau_f


def _filtered_rate(L: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """dL_f/dt of the first-order filter L_f (time constant tau) of a sampled load."""
    a = np.exp(-dt / tau)
    lf, out = L[0], np.empty_like(L)
    for k, x in enumerate(L):
        lf = a * lf + (1.0 - a) * x
        out[k] = (x - lf) / tau
    return out


class CascadePI:
    """Conventional loops for every actuator of a plant (see module docstring).

    Args:
        env: The env (or vector env) the policy will act on; used for its signals and plant.
        tuning: Optional ((Kc_o, Ti_o, Kc_i, Ti_i), ...) per loop, overriding the step tests.
        load_feedforward: Add the identified load feed-forward to the MAIN loops.
        feedforward: Explicit (coefficients (a, b, c) per loop, tau_f) instead of identified.
        gain_schedule: Schedule every loop's gains by the load demand, interpolated between
            the SIMC tunings from step tests at :data:`GAIN_LOADS` (bumpless: each integral
            is rescaled so that Kc times it is continuous).
        outer_gain, outer_reset, inner_gain, inner_reset: Factors on every loop's SIMC gain
            Kc and integral time Ti, outer and inner (the ``KNOBS``; None or 1: SIMC).
    """

    #: Factors on the SIMC tuning, searched by agents.baseline_tuning (default 1: SIMC).
    KNOBS = (
        Knob("outer_gain", 0.25, 4.0),
        Knob("outer_reset", 0.25, 4.0),
        Knob("inner_gain", 0.25, 4.0),
        Knob("inner_reset", 0.25, 4.0),
    )

    @staticmethod
    def knob_defaults(env_id: str) -> dict[str, float]:
        """The SIMC tuning: every factor 1."""
        return {
            "outer_gain": 1.0,
            "outer_reset": 1.0,
            "inner_gain": 1.0,
            "inner_reset": 1.0,
            "feedforward_gain": 1.0,
        }

    def __init__(
        self,
        env: Any,
        tuning: Any = None,
        load_feedforward: bool = False,
        feedforward: tuple[np.ndarray, float] | None = None,
        gain_schedule: bool = False,
        outer_gain: float | None = None,
        outer_reset: float | None = None,
        inner_gain: float | None = None,
        inner_reset: float | None = None,
    ) -> None:
        u = env.unwrapped
        plant = u.plant
        names, self._scale, self._center = observation_layout(env)
        self.i_err = names.index("error_K")
        self.i_load = names.index("load_demand")
        self.i_fire = names.index("firing_rate") if "firing_rate" in names else None
        self.i_valve = [names.index(n) for n in plant.valves]
        params = json.dumps(getattr(u, "params_overrides", {}) or {}, sort_keys=True)
        self.loops = []  # (inner idx | None, outer: MAIN | SCHEDULED | idx | None)
        self.schedules: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        for j, (inner, outer) in enumerate(plant.control_loops):
            i_in = names.index(inner) if inner else None
            if outer in (MAIN, SCHEDULED):
                i_out = outer
            else:
                i_out = names.index(outer) if outer else None
            if outer == SCHEDULED:
                self.schedules[j] = inner_schedule(plant.id, params, inner)
            self.loops.append((i_in, i_out))
        self.dt = plant.dt_s
        self.a_filter = float(np.exp(-self.dt / FILTER_S))
        if tuning is None:  # scheduled: the rated-load tuning sets the feed-forward's filter
            tuning = (
                _tuning(plant.id, params)
                if gain_schedule
                else commissioned_tuning(plant.id, params)
            )
        self.gains = np.array(tuning, dtype=float)
        factors = _factors(outer_gain, outer_reset, inner_gain, inner_reset)
        self.gains = self.gains * factors
        #: (loads, table) of the load-scheduled gains (gain_table), or None
        self.gain_schedule: tuple[np.ndarray, np.ndarray] | None = None
        if gain_schedule:  # the table's (Kc, Ki) pairs: Ki = Kc / Ti takes gain / reset
            g_o, r_o, g_i, r_i = factors
            scale = np.array([g_o, g_o / r_o, g_i, g_i / r_i])
            self.gain_schedule = (np.array(GAIN_LOADS), gain_table(plant.id, params) * scale)
        if feedforward is None and load_feedforward:
            feedforward = _feedforward(plant.id, params, gain_schedule)
        self.ff, self.ff_tau = feedforward if feedforward is not None else (None, 1.0)
        self.a_ff = float(np.exp(-self.dt / self.ff_tau))  # load filter of the feed-forward
        self._st: dict[str, np.ndarray] | None = None
        self.inner_setpoint = np.zeros((1, len(self.loops)))  # last r per row and loop
        self.loop_gains = self.gains[None]  # last (rows or 1, loops, 4) gains, _row_gains's
        self._gains_at: tuple[np.ndarray, np.ndarray] | None = None  # (load, its gains)

    def reset(self) -> None:
        self._st = None

    def firing(self, observation: np.ndarray) -> np.ndarray:
        """Measured firing rate (fraction of rated) of each row."""
        obs = np.atleast_2d(observation)
        return obs[:, self.i_fire] * self._scale[self.i_fire] + self._center[self.i_fire]

    def _restart(self, st: dict[str, np.ndarray], rows: np.ndarray, y: np.ndarray) -> None:
        st["y0"][rows], st["v0"][rows] = y[rows], y[rows][:, self.i_valve]
        load = y[rows, self.i_load]
        st["yf"][rows], st["L0"][rows], st["Lf"][rows] = y[rows], load, load
        st["io"][rows], st["ii"][rows] = 0.0, 0.0
        for j, (loads, temps) in self.schedules.items():  # bumpless: no kick at the start
            r = np.interp(y[rows, self.i_load], loads, temps)
            st["ii"][rows, j] = y[rows, self.loops[j][0]] - r

    def _row_gains(self, load: np.ndarray) -> np.ndarray:
        """(rows or 1, loops, 4) gains (Kc_o, Ti_o, Kc_i, Ti_i) at each row's load demand."""
        if self.gain_schedule is None:
            return self.gains[None]
        last = self._gains_at  # the load holds between ramps: the last gains again
        if last is not None and np.array_equal(load, last[0]):
            return last[1]
        loads, table = self.gain_schedule
        x = np.clip(load, loads[0], loads[-1])
        k = np.clip(np.searchsorted(loads, x) - 1, 0, len(loads) - 2)
        w = ((x - loads[k]) / (loads[k + 1] - loads[k]))[:, None, None]
        g = table[k] * (1.0 - w) + table[k + 1] * w
        for kc, ki in ((0, 1), (2, 3)):  # Ki back to Ti (inf: no integral)
            g[..., ki] = np.divide(
                g[..., kc],
                g[..., ki],
                out=np.full_like(g[..., ki], np.inf),
                where=g[..., ki] != 0.0,
            )
        g.flags.writeable = False  # returned again while the load holds
        self._gains_at = (np.array(load, dtype=float), g)
        return g

    def _bumpless(self, st: dict[str, np.ndarray], g: np.ndarray, restart: np.ndarray) -> None:
        """Rescale the integrals where the scheduled Kc moved, so that Kc times each stays."""
        kc = g[..., [0, 2]]
        if "kc" in st and st["kc"].shape == kc.shape:
            prev = st["kc"]
            ratio = np.divide(prev, kc, out=np.ones_like(kc), where=(kc != 0.0) & (prev != 0.0))
            ratio[restart] = 1.0
            st["io"] *= ratio[..., 0]
            st["ii"] *= ratio[..., 1]
        st["kc"] = kc

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        y = obs * self._scale + self._center  # physical values
        valve = y[:, self.i_valve]
        n = obs.shape[0]
        st = self._st
        fresh = st is None or st["y0"].shape != y.shape
        if fresh:
            z = np.zeros_like(valve)
            st = self._st = {
                "y0": y.copy(),
                "v0": valve.copy(),
                "yf": y.copy(),
                "L0": np.zeros(n),
                "Lf": np.zeros(n),
                "io": z,
                "ii": z.copy(),
            }
        restart = restart_rows(fresh, n, episode_start)
        if restart.any():
            self._restart(st, restart, y)
        yf = st["yf"]
        input_filter(yf, y, self.a_filter, restart)  # measurement filter
        load = y[:, self.i_load]
        st["Lf"] += (1.0 - self.a_ff) * (load - st["Lf"])
        e_main = yf[:, self.i_err]  # setpoint - measured outlet (filtered)
        v = st["v0"].copy()
        self.inner_setpoint = np.full_like(v, np.nan)
        gains = self.loop_gains = self._row_gains(load)
        if self.gain_schedule is not None:
            self._bumpless(st, gains, restart)
        for j, (inner, outer) in enumerate(self.loops):
            kc_o, ti_o, kc_i, ti_i = gains[:, j].T
            if outer is None or outer == SCHEDULED:
                e_o = np.zeros(n)
            else:
                e_o = e_main if outer == MAIN else st["y0"][:, outer] - yf[:, outer]
            if inner is None:  # single loop on the outer signal
                v[:, j], _ = pi_position(st["v0"][:, j], kc_o, e_o, st["io"][:, j], self.dt, ti_o)
                continue
            if outer == SCHEDULED:
                r = np.interp(load, *self.schedules[j])
            else:
                r = st["y0"][:, inner] + kc_o * (e_o + st["io"][:, j])  # inner setpoint
                if self.ff is not None and outer == MAIN:
                    a, b, c = self.ff[j]
                    r = r + a * (load - st["L0"]) + b * (load - st["Lf"]) / self.ff_tau
                    if self.i_fire is not None:
                        r = r + c * (y[:, self.i_fire] - load)
            self.inner_setpoint[:, j] = r
            v[:, j], stopped = pi_position(
                st["v0"][:, j], kc_i, r - yf[:, inner], st["ii"][:, j], self.dt, ti_i
            )
            if np.all(np.isfinite(ti_o)):  # the outer loop integrates while the inner can act
                st["io"][:, j] += np.where(stopped, 0.0, self.dt / ti_o * e_o)
        action = (2.0 * np.clip(v, 0.0, 1.0) - 1.0).astype(np.float32)
        return (action[0] if np.ndim(observation) == 1 else action), None


def _factors(*values: float | None) -> np.ndarray:
    """(Kc_o, Ti_o, Kc_i, Ti_i) factors from the knobs (None: 1); ValueError unless > 0."""
    out = np.array([1.0 if v is None else v for v in values], dtype=float)
    if not np.all(np.isfinite(out) & (out > 0.0)):
        raise ValueError(
            f"the tuning factors outer_gain, outer_reset, inner_gain and "
            f"inner_reset must be finite and > 0, got {out.tolist()}"
        )
    return out


class CascadePIFF(CascadePI):
    """The cascade as a well-commissioned unit runs it: the loops of :class:`CascadePI`
    with load-scheduled gains (SIMC tunings from step tests at :data:`GAIN_LOADS`,
    interpolated bumplessly by the load demand), the load (and, where the plant measures
    it, firing) feed-forward to every main-steam cascade's inner setpoint, and the
    load-scheduled first stages of :class:`CascadePI`. The zero of the leaderboard's
    normalized score. ``feedforward_gain`` (a knob, default 1) scales the fitted
    feed-forward.
    """

    KNOBS = (*CascadePI.KNOBS, Knob("feedforward_gain", 0.0, 2.0, log=False))

    def __init__(self, env: Any, feedforward_gain: float | None = None, **kwargs: Any) -> None:
        super().__init__(env, load_feedforward=True, gain_schedule=True, **kwargs)
        if feedforward_gain is not None:
            g = float(feedforward_gain)
            if not (np.isfinite(g) and g >= 0.0):
                raise ValueError(
                    f"feedforward_gain must be finite and >= 0, got {feedforward_gain!r}"
                )
            self.ff = self.ff * g
