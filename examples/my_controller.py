"""my_controller.py: a controller of your own, scored by the leaderboard with no edit to
the package.

A single-loop PI: every valve that the plant runs in a main-steam cascade
(``plant.control_loops``) is moved directly by a PI on the main-steam temperature error,
without the inner attemperator-outlet loop; the other actuators hold their start
positions. It is tuned as the shipped cascade is: by the SIMC rules (Skogestad, J. Process
Control 13, 2003) on a first-order-plus-dead-time model read from an open-loop step test of
the valve at rated load (``baselines.identification``), with the 5 s DCS input filter on the
temperature added to the dead time; loops sharing the main-steam error share its loop gain.
Next to ``cascade_pi`` it shows what the inner loop buys: this loop sees a spray change
only through the whole superheater's lag.

The leaderboard calls ``make_controller(env)`` with a single or a vector env and uses the
SB3 ``predict`` signature (baselines/policy.py). Score it from the project's root:

    steamtemp-leaderboard --policies cascade_pi,examples/my_controller.py:make_controller \\
        --envs Cascade300MW-v0 --no-oracle --out my_leaderboard
"""

from __future__ import annotations

import functools
import json

import numpy as np

from baselines.cascade_pi import FILTER_S
from baselines.identification import FOPDT, simc_pi, step_test
from baselines.loops import input_filter, observation_layout, pi_position, restart_rows
from steamtemp_gym.plants.base import MAIN


@functools.lru_cache(maxsize=16)
def tuning(env_id: str, params_json: str) -> tuple[tuple[int, ...], np.ndarray, np.ndarray]:
    """(valves on the main-steam error, their Kc, their Ti in s) from step tests."""
    import gymnasium as gym

    params = json.loads(params_json)
    plant = gym.make(env_id, params=params).unwrapped.plant
    main = tuple(j for j, (_, outer) in enumerate(plant.control_loops) if outer == MAIN)
    kc, ti = [], []
    for j in main:
        m = step_test(env_id, j, [plant.outlet_measured], params=params)[plant.outlet_measured]
        k, t = simc_pi(FOPDT(m.K, m.tau_s, m.theta_s + FILTER_S))
        kc.append(k / len(main))
        ti.append(t)
    return main, np.array(kc), np.array(ti)


class SingleLoopPI:
    """A PI from the main-steam error to each main-steam valve (module docstring)."""

    def __init__(self, env) -> None:
        u = env.unwrapped
        names, self.scale, self.center = observation_layout(env)
        self.i_err = names.index("error_K")
        self.i_valve = [names.index(n) for n in u.plant.valves]
        params = json.dumps(getattr(u, "_params_overrides", {}) or {}, sort_keys=True)
        self.main, self.kc, self.ti = tuning(u.plant.id, params)
        self.dt = u.plant.dt_s
        self.a = float(np.exp(-self.dt / FILTER_S))
        self._st: dict[str, np.ndarray] | None = None

    def reset(self) -> None:
        self._st = None

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        y = obs * self.scale + self.center  # physical values
        n = obs.shape[0]
        fresh = self._st is None or self._st["e"].shape[0] != n
        if fresh:
            self._st = {"v0": np.zeros((n, len(self.i_valve))), "e": np.zeros(n),
                        "i": np.zeros((n, len(self.main)))}  # fmt: skip
        st = self._st
        restart = restart_rows(fresh, n, episode_start)
        st["v0"][restart] = y[restart][:, self.i_valve]  # bumpless: start where the valves are
        st["i"][restart] = 0.0
        input_filter(st["e"], y[:, self.i_err], self.a, restart)
        v = st["v0"].copy()
        cols = list(self.main)
        v[:, cols], _ = pi_position(st["v0"][:, cols], self.kc, st["e"][:, None], st["i"],
                                    self.dt, self.ti)  # fmt: skip
        action = (2.0 * np.clip(v, 0.0, 1.0) - 1.0).astype(np.float32)
        return (action[0] if np.ndim(observation) == 1 else action), None


def make_controller(env) -> SingleLoopPI:
    """The factory the leaderboard and steamtemp-check call: ``env -> Policy``."""
    return SingleLoopPI(env)
