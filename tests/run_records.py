"""Hand-made leaderboard records for tests/test_run_aggregation.py: one plant, three
scenarios, four seeds, the score's two ends, a baseline and a trained agent whose
episodes come from one or several training runs."""

from __future__ import annotations

ENV = "steamtemp/SupercriticalFSH-v0"
SCENARIOS = ("a", "b", "c")
SEEDS = (0, 1, 2, 3)
#: (mean return, valve travel) of every policy but the agent.
FIXED = {"cascade_pi_ff": (-100.0, 2.0), "oracle": (-20.0, 3.0), "cascade_pi": (-110.0, 1.5)}


def metrics(ret: float, travel: float) -> dict:
    """One episode's metrics."""
    return {
        "return": ret,
        "valve_travel": travel,
        "valve_reversals": 4.0,
        "iae_K_s": -30 * ret,
        "tripped": 0.0,
    }


def rows(agent: str, offsets: dict[int | None, float], spread: bool = True) -> list[dict]:
    """Every episode of the fixed policies and of ``agent``: the agent's run ``k`` (its
    policy name ``agent@run<k>``, or ``agent`` for the key None) returns -60 + offset,
    plus (with ``spread``) a spread over scenario and seed that every policy has."""
    out = []
    for i, sc in enumerate(SCENARIOS):
        for seed in SEEDS:
            wobble = (1.5 * seed - 0.7 * i + 0.3 * (seed * i % 3)) if spread else 0.0
            for p, (ret, travel) in FIXED.items():
                out.append(
                    {
                        "env": ENV,
                        "scenario": sc,
                        "policy": p,
                        "seed": seed,
                        "fingerprint": "f",
                        "metrics": metrics(ret + wobble, travel),
                    }
                )
            for run, off in offsets.items():
                name = agent if run is None else f"{agent}@run{run}"
                out.append(
                    {
                        "env": ENV,
                        "scenario": sc,
                        "policy": name,
                        "seed": seed,
                        "fingerprint": "f",
                        "metrics": metrics(-60.0 + off + 2 * wobble, 3.0 + 0.1 * seed),
                    }
                )
    return out


def run_info(policies: list[str]) -> dict:
    return {
        "envs": [ENV],
        "scenarios": list(SCENARIOS),
        "policies": {ENV: policies},
        "seeds": list(SEEDS),
        "travel_budget": 2.0,
    }
