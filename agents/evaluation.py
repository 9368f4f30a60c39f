"""One evaluation function for every policy, env, scenario and seed (the leaderboard's
single source of truth, with steamtemp_gym.metrics for the KPIs)."""

from __future__ import annotations

from typing import Any

import numpy as np

from steamtemp_gym.metrics import trajectory_metrics

TRACE_KEYS = ("time_s", "outlet_temp_C", "measured_temp_C", "setpoint_C", "load",
              "spray_valve", "spray_flow_kg_s")  # fmt: skip


def run_episode(env: Any, policy: Any, seed: int) -> dict[str, Any]:
    """Run one full episode; return its trace (arrays), return and engineering metrics.

    The trace also holds the plant's secondary controlled temperatures (e.g. reheat).
    """
    obs, info = env.reset(seed=seed)
    policy.reset()
    keys = TRACE_KEYS + tuple(name for name, _ in env.unwrapped.plant.secondary)
    trace = {k: [info[k]] for k in keys}
    ret, start, terminated = 0.0, True, False
    while True:
        action, _ = policy.predict(obs, episode_start=np.array([start]), deterministic=True)
        start = False
        obs, r, terminated, truncated, info = env.step(action)
        ret += r
        for k in keys:
            trace[k].append(info[k])
        if terminated or truncated:
            break
    tr = {k: np.asarray(v, dtype=np.float64) for k, v in trace.items()}
    metrics = trajectory_metrics(
        tr["time_s"],
        tr["outlet_temp_C"],
        tr["setpoint_C"],
        tr["spray_valve"],
        tr["spray_flow_kg_s"],
    )
    for name, sp2 in env.unwrapped.plant.secondary:  # e.g. the reheat temperature
        m2 = trajectory_metrics(tr["time_s"], tr[name], np.full_like(tr[name], sp2),
                                tr["spray_valve"], tr["spray_flow_kg_s"])  # fmt: skip
        metrics[f"{name}_iae_K_s"] = m2["iae_K_s"]
        metrics[f"{name}_max_abs_dev_K"] = m2["max_abs_dev_K"]
    metrics["return"] = float(ret)
    metrics["tripped"] = float(terminated)
    return {"trace": tr, "metrics": metrics}
