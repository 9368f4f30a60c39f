"""Env-only throughput of the SB3 VecEnvs: agents.vec_env.NativeVecEnv against SB3's
DummyVecEnv and SubprocVecEnv over ``gym.make`` envs, at 4, 16 and 64 envs.

    python -m benchmarks.vec_env_throughput [--env steamtemp/Cascade300MW-v0]
        [--n-envs 4,16,64] [--seconds 2] [--repeats 2]

Env-steps/s through ``VecEnv.step`` (SB3's API: float32 rewards, per-env info dicts,
same-step autoreset) with zero actions on the ``random`` training distribution, the
best of ``--repeats`` interleaved runs; printed as ratios to DummyVecEnv measured in the
same run (this machine is shared: compare the ratios). SubprocVecEnv uses the "fork"
start method; on a 2-core host it mostly pays for pickling.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

import steamtemp_gym  # noqa: F401  (registers the ids)
from agents.vec_env import NativeVecEnv


def _env_fn(env_id: str):
    return lambda: gym.make(env_id)


def make(kind: str, env_id: str, n: int):
    """A VecEnv of ``kind`` ("native", "dummy", "subproc") over n envs of env_id."""
    if kind == "native":
        return NativeVecEnv(env_id, n)
    fns = [_env_fn(env_id) for _ in range(n)]
    return DummyVecEnv(fns) if kind == "dummy" else SubprocVecEnv(fns, start_method="fork")


def rate(venv, seconds: float) -> float:
    """Env-steps per second of ``venv.step`` over about ``seconds``."""
    venv.seed(0)
    venv.reset()
    a = np.zeros((venv.num_envs, *venv.action_space.shape), dtype=np.float32)
    for _ in range(20):  # warm-up
        venv.step(a)
    n, t0 = 0, time.perf_counter()
    while True:
        for _ in range(50):
            venv.step(a)
        n += 50 * venv.num_envs
        dt = time.perf_counter() - t0
        if dt > seconds:
            return n / dt


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--env", default="steamtemp/Cascade300MW-v0")
    ap.add_argument("--n-envs", default="4,16,64")
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    kinds = ("dummy", "subproc", "native")
    print(f"{args.env}: env-steps/s (ratio to DummyVecEnv in the same run)")
    print(f"{'n_envs':>6s} " + " ".join(f"{k:>22s}" for k in kinds))
    for n in (int(x) for x in args.n_envs.split(",")):
        envs = {k: make(k, args.env, n) for k in kinds}
        best = dict.fromkeys(kinds, 0.0)
        for _ in range(args.repeats):
            for k in kinds:
                best[k] = max(best[k], rate(envs[k], args.seconds))
        for venv in envs.values():
            venv.close()
        ref = best["dummy"]
        print(f"{n:6d} " + " ".join(f"{best[k]:12,.0f} ({best[k] / ref:5.1f}x)" for k in kinds))


if __name__ == "__main__":
    main()
