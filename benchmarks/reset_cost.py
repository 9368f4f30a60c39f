"""Reset cost of ``plant_randomization`` per plant, as a ratio to a nominal reset measured
in the same run, and the step cost of both (which the option must leave unchanged).

    python benchmarks/reset_cost.py [--resets 5] [--steps 2000]

For each id: the median wall time of ``--resets`` resets of ``gym.make(id)`` and of
``gym.make(id, plant_randomization=True)``, each reset with a new seed (so each randomized
reset draws, builds and start-checks a new plant), both under ``load_ramp_100_50`` after
one warm-up reset; then the time of a single env's step for both (``--steps`` steps of
the valve held), the single env's randomized step running the plain core step on the
drawn plant's parameters. Machines differ and this one is shared: compare the ratios.
"""

from __future__ import annotations

import argparse
import statistics
import time

import gymnasium as gym
import numpy as np

import steamtemp_gym

SCENARIO = "load_ramp_100_50"


def reset_times(env: gym.Env, n: int) -> list[float]:
    """Wall times of n resets, seeds 1..n (after a warm-up reset with seed 0)."""
    env.reset(seed=0)
    out = []
    for s in range(1, n + 1):
        t0 = time.perf_counter()
        env.reset(seed=s)
        out.append(time.perf_counter() - t0)
    return out


def step_time(env: gym.Env, n: int) -> float:
    """Mean wall time of a step (valve held at its start opening; resets not counted)."""
    _, info = env.reset(seed=0)
    a = (2.0 * np.atleast_1d(info["spray_valve"]) - 1.0).astype(np.float32)
    total, done = 0.0, 0
    while done < n:
        t0 = time.perf_counter()
        _, _, term, trunc, _ = env.step(a)
        total += time.perf_counter() - t0
        done += 1
        if term or trunc:
            env.reset()
    return total / n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--resets", type=int, default=5)
    ap.add_argument("--steps", type=int, default=2000)
    args = ap.parse_args()
    if args.resets < 1 or args.steps < 1:
        ap.error("--resets and --steps must be positive")
    print("| env | nominal reset (ms) | randomized reset (ms) | ratio | nominal step (us) "
          "| randomized step (us) | ratio |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    for env_id in steamtemp_gym.ENV_IDS:
        nom = gym.make(env_id, scenario=SCENARIO)
        rnd = gym.make(env_id, scenario=SCENARIO, plant_randomization=True)
        t_nom = statistics.median(reset_times(nom, args.resets))
        t_rnd = statistics.median(reset_times(rnd, args.resets))
        s_nom, s_rnd = step_time(nom, args.steps), step_time(rnd, args.steps)
        print(f"| {env_id} | {1e3 * t_nom:.2f} | {1e3 * t_rnd:.1f} | {t_rnd / t_nom:.0f} "
              f"| {1e6 * s_nom:.1f} | {1e6 * s_rnd:.1f} | {s_rnd / s_nom:.2f} |")  # fmt: skip


if __name__ == "__main__":
    main()
