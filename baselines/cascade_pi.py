"""Conventional cascade PI: the steam temperature control plants run today.

Per spray valve: an outer PI on the main-steam temperature error sets the
setpoint of the attemperator-outlet (intermediate) temperature, an inner PI on
that temperature moves the spray valve (the standard two-loop arrangement of
spray attemperation, e.g. the cascade of 004_d5464191c442fd5a.txt whose inner
loop is a P controller). Both loops are tuned by the SIMC rules (Skogestad
2003, tau_c = theta) on first-order-plus-dead-time models read from an
open-loop valve step test at rated load (baselines/identification.py): the
inner loop on valve -> intermediate temperature, the outer loop on
intermediate -> outlet temperature (gain K_out/K_in, dead time and balance
time of the outlet response less those of the intermediate one).

Discrete PI in position form at the plant's control interval, bumpless start
(integrators initialized from the measured valve position and intermediate
temperature), anti-windup by conditional integration when the valve saturates.
The policy sees exactly the observation an agent sees.
"""

from __future__ import annotations

import functools
import json
from typing import Any

import numpy as np

from baselines.identification import FOPDT, simc_pi, step_test


@functools.lru_cache(maxsize=16)
def _tuning(env_id: str, params_json: str) -> tuple[tuple[float, float, float, float], ...]:
    """((Kc_outer, Ti_outer, Kc_inner, Ti_inner) per valve) from step tests at rated load."""
    import gymnasium as gym

    params = json.loads(params_json)
    plant = gym.make(env_id, params=params).unwrapped.plant
    out = []
    for j, inner in enumerate(plant.cascade_inner):
        m = step_test(env_id, j, [inner, plant.outlet_measured], params=params)
        mi, mo = m[inner], m[plant.outlet_measured]
        outer = FOPDT(
            K=mo.K / mi.K,
            tau_s=max(mo.tau_s - mi.tau_s, 0.2 * mo.tau_s),
            theta_s=max(mo.theta_s - mi.theta_s, plant.dt_s),
        )
        kc_o, ti_o = simc_pi(outer)
        kc_i, ti_i = simc_pi(mi)
        out.append((kc_o, ti_o, kc_i, ti_i))
    return tuple(out)


class CascadePI:
    """Cascade PI for every spray valve of a plant (see module docstring).

    Args:
        env: The env (or vector env) the policy will act on; used for its signals and plant.
        tuning: Optional ((Kc_o, Ti_o, Kc_i, Ti_i), ...) per valve, overriding the step-test tuning.
    """

    def __init__(self, env: Any, tuning: Any = None) -> None:
        u = env.unwrapped
        plant = u.plant
        names = [s.name for s in u.signals.observation]
        obs_sig = u.signals.observation
        self._scale = np.array([s.scale for s in obs_sig])
        self._center = np.array([s.center for s in obs_sig])
        self.i_err = names.index("error_K")
        self.i_inner = [names.index(n) for n in plant.cascade_inner]
        self.i_valve = [names.index(n) for n in plant.valves]
        self.n_u = plant.n_u
        self.dt = plant.dt_s
        env_id = plant.id
        params = json.dumps(getattr(u, "_params_overrides", {}) or {}, sort_keys=True)
        self.gains = np.array(tuning if tuning is not None else _tuning(env_id, params))
        self._state: dict[str, np.ndarray] | None = None

    def reset(self) -> None:
        self._state = None

    def _phys(self, obs: np.ndarray, idx: list[int]) -> np.ndarray:
        return obs[:, idx] * self._scale[idx] + self._center[idx]

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        e_out = obs[:, self.i_err] * self._scale[self.i_err]  # setpoint - measured outlet, K
        t_in = self._phys(obs, self.i_inner)  # (n, k) intermediate temperatures
        valve = self._phys(obs, self.i_valve)  # (n, k) valve positions
        st = self._state
        fresh = st is None or st["v0"].shape != valve.shape
        if episode_start is not None:
            restart = np.broadcast_to(np.asarray(episode_start, dtype=bool), (obs.shape[0],))
        else:
            restart = np.zeros(obs.shape[0], dtype=bool)
        if fresh:
            st = self._state = {"r0": t_in.copy(), "v0": valve.copy(),
                                "io": np.zeros_like(valve), "ii": np.zeros_like(valve)}  # fmt: skip
        elif restart.any():
            st["r0"][restart], st["v0"][restart] = t_in[restart], valve[restart]
            st["io"][restart], st["ii"][restart] = 0.0, 0.0
        kc_o, ti_o, kc_i, ti_i = self.gains.T
        e = e_out[:, None]
        r = st["r0"] + kc_o * (e + st["io"])  # intermediate-temperature setpoint
        e_i = r - t_in
        v = st["v0"] + kc_i * (e_i + st["ii"])
        v_sat = np.clip(v, 0.0, 1.0)
        # conditional integration: integrate unless it drives a saturated valve further
        push = kc_i * e_i
        ok = ~(((v >= 1.0) & (push > 0)) | ((v <= 0.0) & (push < 0)))
        st["ii"] = np.where(ok, st["ii"] + self.dt / ti_i * e_i, st["ii"])
        st["io"] = np.where(ok, st["io"] + self.dt / ti_o * e, st["io"])
        action = (2.0 * v_sat - 1.0).astype(np.float32)
        if np.ndim(observation) == 1:
            action = action[0]
        return action, None
