"""Reset cost of ``plant_randomization`` per plant, as a ratio to a nominal reset measured
in the same run, and the step cost of both (which the option must leave unchanged).

    python benchmarks/reset_cost.py [--resets 5] [--steps 2000]

For each id: the median wall time of ``--resets`` resets of ``gym.make(id)`` and of
``gym.make(id, plant_randomization=True)``, each reset with a new seed (so each randomized
reset draws, builds and start-checks a new plant), both under ``load_ramp_100_50`` after
one warm-up reset; then the time of a single env's step for both (the fastest block of
100 of ``--steps`` steps of the valve held, best of three interleaved runs): the single
env's randomized step is the plain core step on the drawn plant's parameters, so the two
differ by the machine's noise only; last, a native vector env step of 64 rows, per row,
for both (randomized: one compiled plant call per row). Machines differ and this one is
shared: compare the ratios.

Cascade300MW's plant packing takes 102 matrix exponentials (scipy.linalg.expm, 8x8): on
a machine whose cores are busy, OpenBLAS threads contending for them make each take
milliseconds instead of tens of microseconds; ``OPENBLAS_NUM_THREADS=1`` avoids it.
"""

from __future__ import annotations

import argparse
import statistics
import time

import gymnasium as gym
import numpy as np

import steamtemp_gym

SCENARIO = "load_ramp_100_50"
VECTOR_ROWS = 64


def reset_times(env: gym.Env, n: int) -> list[float]:
    """Wall times of n resets, seeds 1..n (after a warm-up reset with seed 0)."""
    env.reset(seed=0)
    out = []
    for s in range(1, n + 1):
        t0 = time.perf_counter()
        env.reset(seed=s)
        out.append(time.perf_counter() - t0)
    return out


def step_time(env: gym.Env, n: int, block: int = 100) -> float:
    """Wall time of a step (valve held at its start opening): the fastest block of
    ``block`` steps out of ``n`` steps, per step (a shared machine's preemptions fall in the
    slower blocks); blocks with a reset are left out."""
    _, info = env.reset(seed=0)
    a = (2.0 * np.atleast_1d(info["spray_valve"]) - 1.0).astype(np.float32)
    best = float("inf")
    for _ in range(max(n // block, 1)):
        t0 = time.perf_counter()
        ended = False
        for _ in range(block):
            _, _, term, trunc, _ = env.step(a)
            if term or trunc:
                env.reset()
                ended = True
        if not ended:
            best = min(best, (time.perf_counter() - t0) / block)
    return best


def vector_step_time(env_id: str, rows: int, n: int, **options) -> float:
    """Wall time per row of a native vector env step (the fastest of n steps, valves at
    mid stroke)."""
    venv = gym.make_vec(
        env_id, num_envs=rows, vectorization_mode="vector_entry_point", scenario=SCENARIO, **options
    )
    venv.reset(seed=0)
    a = np.zeros(venv.action_space.shape, dtype=np.float32)
    best = float("inf")
    for _ in range(n):
        t0 = time.perf_counter()
        venv.step(a)
        best = min(best, time.perf_counter() - t0)
    return best / rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--resets", type=int, default=5)
    ap.add_argument("--steps", type=int, default=2000)
    args = ap.parse_args()
    if args.resets < 1 or args.steps < 1:
        ap.error("--resets and --steps must be positive")
    print(
        "| env | nominal reset (ms) | randomized reset (ms) | ratio | nominal step (us) "
        f"| randomized step (us) | ratio | vector B={VECTOR_ROWS} nominal (us/row) "
        "| randomized (us/row) | ratio |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for env_id in steamtemp_gym.ENV_IDS:
        nom = gym.make(env_id, scenario=SCENARIO)
        rnd = gym.make(env_id, scenario=SCENARIO, plant_randomization=True)
        t_nom = statistics.median(reset_times(nom, args.resets))
        t_rnd = statistics.median(reset_times(rnd, args.resets))
        steps = [(step_time(nom, args.steps), step_time(rnd, args.steps)) for _ in range(3)]
        s_nom, s_rnd = min(s for s, _ in steps), min(s for _, s in steps)  # interleaved, best
        v_nom = vector_step_time(env_id, VECTOR_ROWS, 200)
        v_rnd = vector_step_time(env_id, VECTOR_ROWS, 200, plant_randomization=True)
        print(
            f"| {env_id} | {1e3 * t_nom:.2f} | {1e3 * t_rnd:.1f} | {t_rnd / t_nom:.0f} "
            f"| {1e6 * s_nom:.1f} | {1e6 * s_rnd:.1f} | {s_rnd / s_nom:.2f} "
            f"| {1e6 * v_nom:.2f} | {1e6 * v_rnd:.2f} | {v_rnd / v_nom:.2f} |"
        )


if __name__ == "__main__":
    main()
