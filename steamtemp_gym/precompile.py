"""Compile the plants' kernels into the disk cache ahead of their first use.

    python -m steamtemp_gym.precompile [ENV_ID ...] [--jobs N]

Without it a plant's kernels compile when it is first made and stepped, once per code
version (docs/performance.md#cold-start), and load from the cache in every later process.
This command does that work up front for the given envs (default: all), each in a process
of its own, ``--jobs`` at a time (default: the CPUs this process may use): it makes the
env, resets it and steps it with float32 and float64 actions, which compiles the
calibration, the steady state and every kernel of the step path. Env ids may be given
without the ``steamtemp/`` prefix.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

import steamtemp_gym
from steamtemp_gym.envs import resolve_id
from steamtemp_gym.plants.threads import usable_cpus


def compile_plant(env_id: str) -> float:
    """Make, reset and step ``env_id`` once per action dtype in this process; the seconds it
    took (compiling on a cold cache, loading on a warm one)."""
    import gymnasium as gym
    import numpy as np

    t0 = time.perf_counter()
    env = gym.make(env_id)
    env.reset(seed=0)
    env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    env.step(np.zeros(env.action_space.shape, dtype=np.float64))
    env.close()
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(
        prog="python -m steamtemp_gym.precompile", description=__doc__.split("\n\n")[0]
    )
    ap.add_argument(
        "env_ids",
        nargs="*",
        metavar="ENV_ID",
        help=f"envs to compile (default: all of {', '.join(steamtemp_gym.ENV_IDS)})",
    )
    ap.add_argument(
        "--jobs",
        type=int,
        default=usable_cpus(),
        help="plants compiled at once, one process each (default: the CPUs)",
    )
    args = ap.parse_args(argv)
    if args.jobs < 1:
        ap.error(f"--jobs must be at least 1, got {args.jobs}")
    try:
        ids = [resolve_id(e) for e in args.env_ids] or list(steamtemp_gym.ENV_IDS)
    except ValueError as exc:
        ap.error(str(exc))
    print(f"compiling {len(ids)} plant(s) into {steamtemp_gym.CACHE_DIR}", flush=True)
    t0 = time.perf_counter()
    jobs = min(args.jobs, len(ids))
    with ProcessPoolExecutor(jobs, mp_context=get_context("spawn")) as pool:
        for env_id, seconds in zip(ids, pool.map(compile_plant, ids), strict=True):
            print(f"  {env_id:34s} {seconds:6.1f} s", flush=True)
    print(f"done in {time.perf_counter() - t0:.1f} s", flush=True)


if __name__ == "__main__":
    main()
