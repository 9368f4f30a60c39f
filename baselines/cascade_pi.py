"""Conventional cascade PI: the steam temperature control plants run today.

Every actuator gets the loop its plant declares in ``Plant.control_loops``
(inner, outer):

- cascade (inner and outer): an outer PI on the outer temperature (MAIN: the
  main-steam error against the setpoint) sets the setpoint of the inner
  (attemperator-outlet) temperature, an inner PI on that temperature moves the
  spray valve: the standard two-loop arrangement of spray attemperation (e.g.
  the cascade of 004_d5464191c442fd5a.txt, whose inner loop is a P controller);
- inner only: a PI holds the inner temperature at its value at the episode start
  (a first-stage spray holding the temperature ahead of the next stage);
- outer only: a PI on the outer signal moves the actuator directly (a gas
  recirculation damper holding the reheat temperature).

Actuators without a loop stay where the episode started. Loops are tuned by the
SIMC rules (Skogestad 2003, tau_c = theta) on first-order-plus-dead-time models
read from open-loop step tests of each actuator at rated load
(baselines/identification.py): the inner loop on actuator -> inner
temperature, the outer loop of a cascade on inner -> outer temperature (gain
K_out/K_in, dead time and balance time of the outer response less those of the
inner one), a single loop on actuator -> its temperature. Where k loops share the
main-steam error (two spray stages), each outer gain is divided by k so that
their sum has the SIMC loop gain.

Discrete PI in position form at the plant's control interval, bumpless start
(integrators initialized from the measured actuator positions and
temperatures), anti-windup by conditional integration when the actuator
saturates. The policy sees exactly the observation an agent sees.
"""

from __future__ import annotations

import functools
import json
from typing import Any

import numpy as np

from baselines.identification import FOPDT, simc_pi, step_test
from steamtemp_gym.plants.base import MAIN

NO_LOOP = (0.0, np.inf, 0.0, np.inf)


@functools.lru_cache(maxsize=16)
def _tuning(env_id: str, params_json: str) -> tuple[tuple[float, float, float, float], ...]:
    """(Kc_outer, Ti_outer, Kc_inner, Ti_inner) per action from step tests at rated load."""
    import gymnasium as gym

    params = json.loads(params_json)
    plant = gym.make(env_id, params=params).unwrapped.plant
    out = []
    n_main = sum(outer == MAIN for _, outer in plant.control_loops)
    for j, (inner, outer) in enumerate(plant.control_loops):
        outer_sig = plant.outlet_measured if outer == MAIN else outer
        m = step_test(env_id, j, [s for s in (inner, outer_sig) if s], params=params)
        kc_o, ti_o, kc_i, ti_i = NO_LOOP
        if inner:
            kc_i, ti_i = simc_pi(m[inner])
        if outer_sig and inner:
            mi, mo = m[inner], m[outer_sig]
            kc_o, ti_o = simc_pi(FOPDT(
                K=mo.K / mi.K,
                tau_s=max(mo.tau_s - mi.tau_s, 0.2 * mo.tau_s),
                theta_s=max(mo.theta_s - mi.theta_s, plant.dt_s),
            ))  # fmt: skip
        elif outer_sig:
            kc_o, ti_o = simc_pi(m[outer_sig])
        if outer == MAIN:  # loops sharing the main-steam error share its loop gain
            kc_o /= n_main
        out.append((kc_o, ti_o, kc_i, ti_i))
    return tuple(out)


class CascadePI:
    """Conventional loops for every actuator of a plant (see module docstring).

    Args:
        env: The env (or vector env) the policy will act on; used for its signals and plant.
        tuning: Optional ((Kc_o, Ti_o, Kc_i, Ti_i), ...) per loop, overriding the step tests.
    """

    def __init__(self, env: Any, tuning: Any = None) -> None:
        u = env.unwrapped
        plant = u.plant
        names = [s.name for s in u.signals.observation]
        self._scale = np.array([s.scale for s in u.signals.observation])
        self._center = np.array([s.center for s in u.signals.observation])
        self.i_err = names.index("error_K")
        self.i_valve = [names.index(n) for n in plant.valves]
        self.loops = []  # (inner idx | None, outer: "main" | idx | None)
        for inner, outer in plant.control_loops:
            i_in = names.index(inner) if inner else None
            i_out = MAIN if outer == MAIN else (names.index(outer) if outer else None)
            self.loops.append((i_in, i_out))
        self.dt = plant.dt_s
        params = json.dumps(getattr(u, "_params_overrides", {}) or {}, sort_keys=True)
        self.gains = np.array(
            tuning if tuning is not None else _tuning(plant.id, params), dtype=float
        )
        self._st: dict[str, np.ndarray] | None = None

    def reset(self) -> None:
        self._st = None

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        y = obs * self._scale + self._center  # physical values
        valve = y[:, self.i_valve]
        n = obs.shape[0]
        st = self._st
        if st is None or st["y0"].shape != y.shape:
            st = self._st = {"y0": y.copy(), "v0": valve.copy(), "r0": np.zeros_like(valve),
                             "io": np.zeros_like(valve), "ii": np.zeros_like(valve)}  # fmt: skip
            restart = np.ones(n, dtype=bool)
        elif episode_start is not None:
            restart = np.broadcast_to(np.asarray(episode_start, dtype=bool), (n,))
        else:
            restart = np.zeros(n, dtype=bool)
        if restart.any():
            st["y0"][restart], st["v0"][restart] = y[restart], valve[restart]
            st["io"][restart], st["ii"][restart] = 0.0, 0.0
        e_main = obs[:, self.i_err] * self._scale[self.i_err]  # setpoint - measured outlet
        v = st["v0"].copy()
        for j, (inner, outer) in enumerate(self.loops):
            kc_o, ti_o, kc_i, ti_i = self.gains[j]
            if outer is None:
                e_o = np.zeros(n)
            else:
                e_o = e_main if outer == MAIN else st["y0"][:, outer] - y[:, outer]
            if inner is None:  # single loop on the outer signal
                push, v[:, j] = kc_o * e_o, st["v0"][:, j] + kc_o * (e_o + st["io"][:, j])
            else:
                r = st["y0"][:, inner] + kc_o * (e_o + st["io"][:, j])  # inner setpoint
                e_i = r - y[:, inner]
                push, v[:, j] = kc_i * e_i, st["v0"][:, j] + kc_i * (e_i + st["ii"][:, j])
                ok_i = ~(((v[:, j] >= 1.0) & (push > 0)) | ((v[:, j] <= 0.0) & (push < 0)))
                st["ii"][:, j] += np.where(ok_i, self.dt / ti_i * e_i, 0.0)
            ok = ~(((v[:, j] >= 1.0) & (push > 0)) | ((v[:, j] <= 0.0) & (push < 0)))
            st["io"][:, j] += np.where(ok, self.dt / ti_o * e_o, 0.0)
        action = (2.0 * np.clip(v, 0.0, 1.0) - 1.0).astype(np.float32)
        return (action[0] if np.ndim(observation) == 1 else action), None
