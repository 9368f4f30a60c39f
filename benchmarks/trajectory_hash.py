"""A fingerprint of every plant's trajectories, to show that a change to the code keeps them
bit for bit.

    python benchmarks/trajectory_hash.py [--steps 500] [--seeds 0,1,2] [--scenario random]
                                         [--skip-info cost,cost_band]

For each registered env, each seed: ``reset(seed=seed)`` on the given scenario, then
``--steps`` steps with actions drawn from ``numpy.random.default_rng(seed)`` over the action
space. Every observation, reward, termination flag and numeric info value is hashed
(SHA-256 of the raw float64 bytes), and one hash per env and one over all envs is printed.
``--skip-info`` leaves the named info keys out: a change that adds info keys compares its
trajectories with the code before it that way.
The same code on the same machine and library versions prints the same hashes; compare
before and after a change, not across machines (the last bits of libm differ).
"""

from __future__ import annotations

import argparse
import hashlib

import gymnasium as gym
import numpy as np

import steamtemp_gym  # noqa: F401  (registers the envs)


def env_hash(
    env_id: str, seeds: list[int], steps: int, scenario: str, skip: frozenset[str] = frozenset()
) -> str:
    """SHA-256 over ``steps`` steps of random actions for each seed of ``env_id``, without
    the info keys ``skip``."""
    h = hashlib.sha256()
    env = gym.make(env_id, scenario=scenario)
    space = env.action_space
    for seed in seeds:
        obs, info = env.reset(seed=seed)
        h.update(np.asarray(obs, np.float64).tobytes())
        rng = np.random.default_rng(seed)
        for _ in range(steps):
            a = rng.uniform(space.low, space.high).astype(space.dtype)
            obs, reward, terminated, truncated, info = env.step(a)
            h.update(np.asarray(obs, np.float64).tobytes())
            h.update(np.float64(reward).tobytes())
            h.update(bytes([terminated, truncated]))
            for key in sorted(info):
                value = info[key]
                if key not in skip and isinstance(value, (int, float, np.number, np.ndarray)):
                    h.update(key.encode())
                    h.update(np.asarray(value, np.float64).tobytes())
            if terminated or truncated:
                obs, info = env.reset()
    env.close()
    return h.hexdigest()


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--scenario", default="random")
    ap.add_argument("--skip-info", default="", help="comma-separated info keys not hashed")
    args = ap.parse_args(argv)
    if args.steps < 1:
        raise SystemExit("--steps must be at least 1")
    seeds = [int(s) for s in args.seeds.split(",")]
    ids = [k for k in gym.registry if k.startswith("steamtemp/")]
    total = hashlib.sha256()
    for env_id in ids:
        skip = frozenset(k for k in args.skip_info.split(",") if k)
        digest = env_hash(env_id, seeds, args.steps, args.scenario, skip)
        total.update(digest.encode())
        print(f"{env_id:34s} {digest[:16]}")
    print(f"{'all':34s} {total.hexdigest()[:16]}")


if __name__ == "__main__":
    main()
