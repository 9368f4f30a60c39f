"""Step throughput of every env id, as ratios to CartPole-v1 measured in the same run.

    python benchmarks/step_throughput.py [--seconds 2] [--batches 1,64,1024,4096]

Prints steps/s of each id through ``gym.make`` (default wrappers, random
actions, resets when episodes end) next to ``CartPole-v1``, and env-steps/s of
the native vector env at several batch sizes on one thread, and at the largest batch on
every thread (plants/threads.py). These
machines are noisy: compare the ratios, not the absolute numbers. Each ratio
uses the best of ``--repeats`` interleaved runs of CartPole and the env, so a
slow spell of the host hits both. The column ``B=1/single`` is the native
vector env at one row against the same id through ``gym.make``; the first line
gives the same ratio for Gymnasium's own vector env of one CartPole-v1
(``SyncVectorEnv``), the cost of the vector API (an array and a mask per info
key) on a reference env. The speed goals: single env >= 1.0x CartPole-v1;
vector env >= 2,000,000 env-steps/s at batch 4096 on one thread; vector B=1 no
slower than the single env. docs/performance_profile.md has the floors.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import steamtemp_gym
from steamtemp_gym.plants import threads

LOADS = {"scenario": "load_following"}  # the scenario every id runs here


def single_rate(env_id: str, seconds: float, **kwargs) -> float:
    env = gym.make(env_id, **kwargs)
    env.reset(seed=0)
    actions = [env.action_space.sample() for _ in range(256)]
    for a in actions[:50]:  # warm-up (compilation)
        _, _, term, trunc, _ = env.step(a)
        if term or trunc:
            env.reset()
    n, t0 = 0, time.perf_counter()
    while True:
        for a in actions:
            _, _, term, trunc, _ = env.step(a)
            if term or trunc:
                env.reset()
        n += len(actions)
        dt = time.perf_counter() - t0
        if dt > seconds:
            return n / dt


def vector_rate(
    env_id: str, batch: int, seconds: float, mode: str = "vector_entry_point", **kwargs
) -> float:
    venv = gym.make_vec(env_id, num_envs=batch, vectorization_mode=mode, **kwargs)
    venv.reset(seed=0)
    a = np.zeros(venv.action_space.shape, dtype=venv.action_space.dtype)
    venv.step(a)
    n, t0 = 0, time.perf_counter()
    while True:
        venv.step(a)
        n += batch
        dt = time.perf_counter() - t0
        if dt > seconds:
            return n / dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--batches", default="1,64,1024,4096")
    ap.add_argument("--envs", default=",".join(steamtemp_gym.ENV_IDS))
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    batches = [int(b) for b in args.batches.split(",")]
    n_thr = threads.n_threads()
    ref1 = max(single_rate("CartPole-v1", args.seconds) for _ in range(args.repeats))
    sync1 = max(vector_rate("CartPole-v1", 1, args.seconds, "sync") for _ in range(args.repeats))
    print(
        f"Gymnasium reference: CartPole-v1 {ref1:,.0f} steps/s through gym.make, "
        f"{sync1:,.0f} /s as SyncVectorEnv of one env: B=1/single {sync1 / ref1:.2f}"
    )
    print(
        f"{'env id':36s} {'steps/s':>10s} {'CartPole':>10s} {'xCartPole':>9s} "
        + " ".join(f"{'B=' + str(b):>12s}" for b in batches)
        + f" {'B=' + str(batches[-1]):>8s},"
        f"{n_thr} thr {'B=1/single':>10s}"
    )
    for env_id in args.envs.split(","):
        ref, r = 0.0, 0.0
        for _ in range(args.repeats):
            ref = max(ref, single_rate("CartPole-v1", args.seconds))
            r = max(r, single_rate(env_id, args.seconds, **LOADS))
        threads.set_threads(1)
        vec = [vector_rate(env_id, b, args.seconds, **LOADS) for b in batches]
        threads.set_threads(n_thr)
        vec.append(vector_rate(env_id, batches[-1], args.seconds, **LOADS))
        b1 = max(vector_rate(env_id, 1, args.seconds, **LOADS) for _ in range(args.repeats))
        print(
            f"{env_id:36s} {r:10,.0f} {ref:10,.0f} {r / ref:9.2f} "
            + " ".join(f"{v:12,.0f}" for v in vec)
            + f" {b1 / r:10.2f}"
        )
    print(
        "vector columns: env-steps/s of the native vector env at batch B on one thread; "
        f"the last on {n_thr} threads (plants/threads.py, STEAMTEMP_GYM_THREADS)"
    )


if __name__ == "__main__":
    main()
