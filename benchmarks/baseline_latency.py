"""Predict latency of every baseline on every plant, with CartPole-v1's step time as the
reference measured in the same run.

    python benchmarks/baseline_latency.py [--envs a,b] [--policies a,b] [--batch 64] [--calls 300]

For each (plant, baseline): microseconds per ``predict`` call for one env (the goal of the
paper controllers: <= 1 ms; MPC <= 5 ms), its 99th percentile and slowest call, and per env
for a batch of ``--batch`` rows on
observations of the native vector env; the ratio column is the single-env predict time over
a CartPole-v1 ``step`` (these machines are noisy: compare ratios). Observations come from a
real episode (``load_ramp_100_50``), so the controllers run their normal code paths.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np
from step_throughput import single_rate  # benchmarks/ (the script's folder)

import baselines
import steamtemp_gym


def latency_us(env_id: str, name: str, batch: int, calls: int) -> tuple[float, float, float, float]:
    """(us per single-env predict, its 99th percentile, the slowest single-env call, us per
    env of a batched predict). The tail matters for controllers that work every n-th step or
    whose solver iterates (MPC)."""
    env = gym.make(env_id, scenario="load_ramp_100_50")
    policy = baselines.make(name, env)
    obs, _ = env.reset(seed=0)
    trace = []
    for k in range(calls + 20):
        a, _ = policy.predict(obs, episode_start=np.array([k == 0]))
        obs, *_ = env.step(a)
        trace.append(obs)
    policy.reset()
    times = np.empty(calls)
    for k, o in enumerate(trace[:calls]):
        t0 = time.perf_counter()
        policy.predict(o, episode_start=np.array([k == 0]))
        times[k] = time.perf_counter() - t0
    single, worst = times.mean() * 1e6, times[1:].max() * 1e6  # the first call builds state
    p99 = float(np.percentile(times[1:], 99)) * 1e6
    venv = gym.make_vec(
        env_id, num_envs=batch, vectorization_mode="vector_entry_point", scenario="load_ramp_100_50"
    )
    vpol = baselines.make(name, venv)
    obs, _ = venv.reset(seed=0)
    start = np.ones(batch, dtype=bool)
    n = max(calls // 10, 20)
    t0 = time.perf_counter()
    for _ in range(n):
        a, _ = vpol.predict(obs, episode_start=start)
        start[:] = False
        t1 = time.perf_counter()
        obs, *_ = venv.step(a)
        t0 += time.perf_counter() - t1  # predict time only
    return single, p99, worst, (time.perf_counter() - t0) / n / batch * 1e6


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--envs", default=",".join(steamtemp_gym.ENV_IDS))
    ap.add_argument("--policies", default=",".join(baselines.NAMES))
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--calls", type=int, default=300)
    args = ap.parse_args(argv)
    envs = [e for e in args.envs.split(",") if e]
    names = [p for p in args.policies.split(",") if p]
    for e in envs:
        if e not in steamtemp_gym.ENV_IDS:
            ap.error(f"unknown env {e!r}; valid: {list(steamtemp_gym.ENV_IDS)}")
    for p in names:
        if p not in baselines.NAMES:
            ap.error(f"unknown policy {p!r}; valid: {list(baselines.NAMES)}")
    if args.batch < 1 or args.calls < 1:
        ap.error("--batch and --calls must be positive")
    ref = 1e6 / single_rate("CartPole-v1", 1.0)  # us per step, the same run's reference
    print(f"reference: CartPole-v1 step {ref:.1f} us\n")
    print(
        f"| plant | baseline | single env, us/call | p99, us | slowest call, us | "
        f"x CartPole step | batch {args.batch}, us/env |\n"
        f"|---|---|---|---|---|---|---|"
    )
    for env_id in envs:
        for name in names:
            single, p99, worst, per_env = latency_us(env_id, name, args.batch, args.calls)
            print(
                f"| {env_id.split('/')[-1]} | {name} | {single:.0f} | {p99:.0f} | {worst:.0f} | "
                f"{single / ref:.1f} | "
                f"{per_env:.1f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
