"""The oracle's return as its budget doubles: the convergence evidence of agents/oracle.py.

Runs the oracle on one plant and scenario for several seeds side by side (as the
leaderboard does) at each budget of a doubling ladder (samples x iterations per replan;
the rest of the budget as given), next to ``cascade_pi_ff``, and prints per budget the
mean return, IAE, valve travel, trips, CPU seconds per episode and the relative change of
the return over the previous budget in percent (the ladder stops when it improves by less
than ``--stop-pct``). Example::

    python benchmarks/oracle_budget.py --env steamtemp/Cascade300MW-v0 \\
        --scenario load_ramp_100_50 --seeds 0-2 --ladder 8x2,16x2,16x4,32x4,32x8
"""

from __future__ import annotations

import argparse
import json
import time

import gymnasium as gym
import numpy as np

import steamtemp_gym  # noqa: F401  (registers the ids)
from agents.cem import Budget
from agents.evaluation import run_batch
from agents.leaderboard.plan import parse_seeds, resolve_scenario
from agents.oracle import Oracle
from baselines.cascade_pi import CascadePIFF


def _means(results: list[dict]) -> dict[str, float]:
    keys = ("return", "iae_K_s", "valve_travel", "tripped")
    return {k: float(np.mean([r["metrics"][k] for r in results])) for k in keys}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--env", default="steamtemp/Cascade300MW-v0")
    ap.add_argument("--scenario", default="load_ramp_100_50")
    ap.add_argument("--seeds", default="0-2")
    ap.add_argument(
        "--ladder", default="8x2,16x2,16x4,32x4,32x8", help="comma list of samples x iterations"
    )
    ap.add_argument("--budget", default="{}", help="other Budget fields as JSON")
    ap.add_argument("--stop-pct", type=float, default=1.0)
    args = ap.parse_args()
    seeds = parse_seeds(ap, args.seeds)
    scenario = resolve_scenario(args.scenario, args.env)
    venv = gym.make_vec(
        args.env, num_envs=len(seeds), vectorization_mode="vector_entry_point", scenario=scenario
    )
    ref = _means(run_batch(venv, CascadePIFF(venv), seeds))
    print(
        f"{args.env} {args.scenario} seeds {seeds}; cascade_pi_ff: return "
        f"{ref['return']:.2f}, IAE {ref['iae_K_s']:.0f} K s, travel {ref['valve_travel']:.2f}",
        flush=True,
    )
    print(
        "| samples x iterations | return | IAE [K s] | travel | trips | CPU s / episode | "
        "change [%] |\n|---|---|---|---|---|---|---|",
        flush=True,
    )
    extra = json.loads(args.budget)
    prev = None
    for rung in args.ladder.split(","):
        s, i = (int(x) for x in rung.split("x"))
        budget = Budget(samples=s, iterations=i, elites=max(2, s // 8), **extra)
        t0 = time.process_time()
        m = _means(run_batch(venv, Oracle(venv, budget, engine="cem"), seeds))
        cpu = (time.process_time() - t0) / len(seeds)
        change = "" if prev is None else f"{100 * (m['return'] - prev) / abs(prev):+.1f}"
        print(
            f"| {s} x {i} | {m['return']:.2f} | {m['iae_K_s']:.0f} | {m['valve_travel']:.2f} | "
            f"{m['tripped']:.2f} | {cpu:.1f} | {change} |",
            flush=True,
        )
        if prev is not None and m["return"] - prev < args.stop_pct / 100 * abs(prev):
            break
        prev = m["return"]


if __name__ == "__main__":
    main()
