"""One evaluation function for every policy, env, scenario and seed (the leaderboard's
single source of truth, with steamtemp_gym.metrics for the KPIs).

:func:`run_episode` runs one episode of a ``gym.make`` env; :func:`run_batch` runs one
episode per seed side by side in the native vector env (one kernel call and one batched
``predict`` per step for all seeds). Sub-env i of the vector env is the single env seeded
with its seed, and the baselines act row by row, so both give identical traces and metrics
(tests/test_leaderboard.py checks it bit for bit).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from steamtemp_gym.metrics import (
    METRIC_NAMES,
    QUIET_SETTLE_S,
    quiet_peak_to_peak,
    trajectory_metrics,
)
from steamtemp_gym.plants.base import DIST

TRACE_KEYS = (
    "time_s",
    "outlet_temp_C",
    "measured_temp_C",
    "setpoint_C",
    "load",
    "spray_valve",
    "spray_flow_kg_s",
)
#: Scenario disturbances recorded in the trace (as the plant receives them: the heat-absorption
#: bias includes the coloured noise).
DISTURBANCE_KEYS = ("heat_absorption_bias", "fouling", "spray_water_temp_offset_C")
_DIST_COLUMNS = [DIST.index(k) for k in DISTURBANCE_KEYS]


def _keys(env: Any) -> tuple[str, ...]:
    return TRACE_KEYS + tuple(name for name, _ in env.unwrapped.plant.secondary)


#: The metrics of each secondary controlled temperature, named ``<temperature>_<metric>``.
SECONDARY_METRICS = ("iae_K_s", "max_abs_dev_K")


def metric_keys(secondary: tuple[tuple[str, float], ...]) -> tuple[str, ...]:
    """The keys of an episode's ``metrics`` on a plant with these ``secondary``
    temperatures (``Plant.secondary``)."""
    return (
        *METRIC_NAMES,
        "quiet_p2p_K",
        *(f"{name}_{m}" for name, _ in secondary for m in SECONDARY_METRICS),
        "return",
        "tripped",
    )


def _metrics(
    env: Any, tr: dict[str, np.ndarray], ret: float, tripped: bool, scenario: Any
) -> dict[str, float]:
    """The episode's metrics: steamtemp_gym.metrics of the main steam (and of the secondary
    temperatures), ``quiet_p2p_K`` (the error's peak-to-peak over the quiet stretch after the
    scenario's last scheduled change: the limit-cycle measure), return and trip."""
    metrics = trajectory_metrics(
        tr["time_s"],
        tr["outlet_temp_C"],
        tr["setpoint_C"],
        tr["spray_valve"],
        tr["spray_flow_kg_s"],
    )
    metrics["quiet_p2p_K"] = quiet_peak_to_peak(
        tr["time_s"],
        tr["outlet_temp_C"] - tr["setpoint_C"],
        scenario.last_change_s() + QUIET_SETTLE_S,
    )
    for name, sp2 in env.unwrapped.plant.secondary:  # e.g. the reheat temperature
        m2 = trajectory_metrics(
            tr["time_s"],
            tr[name],
            np.full_like(tr[name], sp2),
            tr["spray_valve"],
            tr["spray_flow_kg_s"],
        )
        for m in SECONDARY_METRICS:
            metrics[f"{name}_{m}"] = m2[m]
    metrics["return"] = float(ret)
    metrics["tripped"] = float(tripped)
    return metrics


def run_episode(env: Any, policy: Any, seed: int) -> dict[str, Any]:
    """Run one full episode; return its trace (arrays), return and engineering metrics.

    The trace also holds the plant's secondary controlled temperatures (e.g. reheat) and
    the disturbances :data:`DISTURBANCE_KEYS`.
    """
    obs, info = env.reset(seed=seed)
    policy.reset()
    keys = _keys(env)
    D = env.unwrapped.core.D
    trace = {k: [info[k]] for k in keys}
    dist = [D[0, _DIST_COLUMNS].copy()]
    ret, start, terminated = 0.0, True, False
    while True:
        action, _ = policy.predict(obs, episode_start=np.array([start]), deterministic=True)
        start = False
        obs, r, terminated, truncated, info = env.step(action)
        ret += r
        for k in keys:
            trace[k].append(info[k])
        dist.append(D[0, _DIST_COLUMNS].copy())
        if terminated or truncated:
            break
    tr = {k: np.asarray(v, dtype=np.float64) for k, v in trace.items()}
    tr.update(zip(DISTURBANCE_KEYS, np.asarray(dist).T, strict=True))
    return {"trace": tr, "metrics": _metrics(env, tr, ret, terminated, env.unwrapped.scenario)}


def run_batch(venv: Any, policy: Any, seeds: list[int]) -> list[dict[str, Any]]:
    """One episode per seed in a native vector env of ``len(seeds)`` sub-envs.

    Returns:
        One ``{"trace", "metrics"}`` per seed, in order, equal to :func:`run_episode`'s.
    """
    n = len(seeds)
    if venv.num_envs != n:
        raise ValueError(f"vector env has {venv.num_envs} sub-envs for {n} seeds")
    obs, info = venv.reset(seed=[int(s) for s in seeds])
    scenarios = list(venv.unwrapped.core.scenario)  # before any row starts a new episode
    policy.reset()
    keys = _keys(venv)
    D = venv.unwrapped.core.D
    cols = {k: [info[k].copy()] for k in keys}
    dist = [D[:, _DIST_COLUMNS].copy()]
    rewards, terminated = [], []
    end = np.full(n, -1)  # index of each row's last step
    start = np.ones(n, dtype=bool)
    while (end < 0).any():
        action, _ = policy.predict(obs, episode_start=start, deterministic=True)
        start = np.zeros(n, dtype=bool)
        obs, r, term, trunc, info = venv.step(action)
        for k in keys:
            cols[k].append(info[k].copy())
        dist.append(D[:, _DIST_COLUMNS].copy())
        rewards.append(r)
        terminated.append(term)
        done = (term | trunc) & (end < 0)
        end[done] = len(rewards)
    stacked = {k: np.asarray(v, dtype=np.float64) for k, v in cols.items()}
    dist_arr, rew, term_arr = np.asarray(dist), np.asarray(rewards), np.asarray(terminated)
    out = []
    for i in range(n):
        last = end[i]
        tr = {k: v[: last + 1, i] for k, v in stacked.items()}
        tr.update(zip(DISTURBANCE_KEYS, dist_arr[: last + 1, i].T, strict=True))
        ret = float(np.cumsum(rew[:last, i])[-1])  # sequential, as run_episode adds
        tripped = bool(term_arr[last - 1, i])
        out.append({"trace": tr, "metrics": _metrics(venv, tr, ret, tripped, scenarios[i])})
    return out
