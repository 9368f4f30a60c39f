"""How hard each benchmark plant is: reference policies on every named scenario.

A benchmark needs headroom: if a frozen valve or a plain PI is already near
perfect, no better controller can show it. :func:`difficulty_table` runs, on
every named scenario of an env (3 seeds by default), through the one evaluation
function of the leaderboard (agents/evaluation.py):

- ``frozen``: the valves held where the episode started (the open-loop drift);
- ``random``: uniform random actions (seeded per episode);
- ``cascade_pi``: the conventional baseline (baselines/cascade_pi.py);
- ``cascade_pi_2x``: the same with doubled outer-loop gains (what tighter tuning buys);
- ``cascade_pi_ff``: the registered industrial reference (baselines/cascade_pi.py
  ``CascadePIFF``: load-scheduled gains and the identified load feed-forward; what a
  better-informed controller can gain: the load demand is in the observation).

The difficulty targets (a benchmark with headroom against field tolerances of about
+-10 K once-through and +-8 K drum during load changes) are :data:`TARGETS`;
tests/test_difficulty.py checks them and benchmarks/difficulty.py prints the table and
regenerates docs/difficulty.md's.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from agents.evaluation import run_episode
from baselines.cascade_pi import CascadePI, CascadePIFF
from baselines.identification import step_test
from steamtemp_gym import plants, scenarios
from steamtemp_gym.plants.base import MAIN

REFERENCE_POLICIES = ("frozen", "random", "cascade_pi", "cascade_pi_2x", "cascade_pi_ff")
COLUMNS = (
    "max_abs_dev_K",
    "iae_K_s",
    "time_outside_5K_s",
    "spray_used_kg",
    "valve_travel",
    "return",
    "tripped",
)
#: Peak |e| band (K) of cascade PI on the two 5 %/min ramps, per boiler circulation.
PI_RAMP_PEAK_K = {"once_through": (4.0, 10.0), "drum": (3.0, 8.0)}
TARGETS = {
    "frozen_ramp_peak_min_K": 20.0,
    "pi_ramp_peak_K": PI_RAMP_PEAK_K,
    "cascade300_pi_std_K": (1.0, 2.5),
    "ff_peak_reduction_min": 0.25,
}


def ramp_band(env_id: str) -> tuple[float, float] | None:
    """The cascade PI's ramp-peak band (K) of a plant by its circulation
    (``Plant.circulation``); None for a plant without one (no ramp band)."""
    kind = plants.plant_class(env_id).circulation
    return None if kind is None else PI_RAMP_PEAK_K[kind]


RAMPS = ("load_ramp_100_50", "load_ramp_50_100")
#: Field range of Tu/Tg of the true outlet after a last-stage spray step (field step tests:
#: about 0.3), and the largest the thermocouple reading may show.
TU_TG_TRUE = (0.2, 0.4)
TU_TG_MEASURED_MAX = 0.55


def last_spray_stage(plant: Any) -> int:
    """Index of the action whose loop holds the main steam (the last spray stage)."""
    return max(j for j, (_, outer) in enumerate(plant.control_loops) if outer == MAIN)


def spray_step_dead_time(env_id: str, load: float) -> tuple[Any, Any]:
    """FOPDT of the true and of the measured outlet for a +5 % last-stage spray step."""
    plant = gym.make(env_id).unwrapped.plant
    m = step_test(env_id, last_spray_stage(plant), [plant.outlet, plant.outlet_measured], load=load)
    return m[plant.outlet], m[plant.outlet_measured]


class FrozenValves:
    """Holds every actuator where the episode started."""

    def __init__(self, env: Any) -> None:
        names = [s.name for s in env.unwrapped.signals.observation]
        sig = env.unwrapped.signals.observation
        self.idx = [names.index(v) for v in env.unwrapped.plant.valves]
        self.scale = np.array([sig[i].scale for i in self.idx])
        self.center = np.array([sig[i].center for i in self.idx])
        self.hold: np.ndarray | None = None

    def reset(self) -> None:
        self.hold = None

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(observation)
        if self.hold is None or (episode_start is not None and np.any(episode_start)):
            v = obs[:, self.idx] * self.scale + self.center
            self.hold = (2.0 * np.clip(v, 0.0, 1.0) - 1.0).astype(np.float32)
        return (self.hold[0] if np.ndim(observation) == 1 else self.hold), None


class RandomActions:
    """Uniform random actions, a fresh seeded stream per episode."""

    def __init__(self, env: Any) -> None:
        self.n = env.unwrapped.plant.n_u
        self.episode = 0
        self.rng = np.random.default_rng(0)

    def reset(self) -> None:
        self.rng = np.random.default_rng(self.episode)
        self.episode += 1

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        n = 1 if np.ndim(observation) == 1 else np.shape(observation)[0]
        a = self.rng.uniform(-1.0, 1.0, (n, self.n)).astype(np.float32)
        return (a[0] if np.ndim(observation) == 1 else a), None


def make_reference(name: str, env: Any):
    """A reference policy of :data:`REFERENCE_POLICIES` for ``env``."""
    if name == "frozen":
        return FrozenValves(env)
    if name == "random":
        return RandomActions(env)
    if name == "cascade_pi":
        return CascadePI(env)
    if name == "cascade_pi_2x":
        pi = CascadePI(env)
        pi.gains[:, 0] *= 2.0
        return pi
    if name == "cascade_pi_ff":
        return CascadePIFF(env)
    raise ValueError(f"unknown reference policy {name!r}; valid: {list(REFERENCE_POLICIES)}")


def evaluate(env_id: str, policy: str, scenario: str, seeds: int = 3) -> dict[str, float]:
    """Means over ``seeds`` seeds of the COLUMNS metrics, plus the error std after 800 s."""
    env = gym.make(env_id, scenario=scenario)
    pol = make_reference(policy, env)
    rows = []
    for seed in range(seeds):
        ep = run_episode(env, pol, seed)
        m = ep["metrics"]
        tr = ep["trace"]
        e = tr["outlet_temp_C"] - tr["setpoint_C"]
        late = tr["time_s"] >= 800.0
        rows.append([m[c] for c in COLUMNS] + [float(np.std(e[late])) if late.any() else np.nan])
    mean = np.nanmean(np.array(rows, dtype=float), axis=0)
    return dict(zip(COLUMNS + ("late_error_std_K",), map(float, mean), strict=True))


def difficulty_table(
    env_ids: list[str],
    policies: tuple[str, ...] = REFERENCE_POLICIES,
    seeds: int = 3,
    scenario_names: list[str] | None = None,
) -> list[dict[str, Any]]:
    """One row per (env, scenario, policy) with the means of :func:`evaluate`."""
    out = []
    for env_id in env_ids:
        for sc in scenario_names or [s for s in scenarios.names(env_id) if s != "random"]:
            if sc not in scenarios.names(env_id):
                continue
            for pol in policies:
                out.append(
                    {
                        "env": env_id,
                        "scenario": sc,
                        "policy": pol,
                        **evaluate(env_id, pol, sc, seeds),
                    }
                )
    return out
