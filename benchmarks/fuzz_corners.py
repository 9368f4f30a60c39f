"""Corner-biased fuzzing of every plant (the long form of tests/test_hardening.py).

    python benchmarks/fuzz_corners.py [--envs a,b] [--rows 64] [--steps 2000] [--seed 0]

Runs ``rows`` x ``steps`` control steps per id under corner scenarios
(steamtemp_gym/scenarios/stress.py: loads at the ends of the range, biases and fouling at
their limits, jumps and fast ramps) with random-walk and bang-bang actions, and prints the
row-steps run, episodes, scenarios rejected at reset (the plant cannot hold their start: a
clear error), trips by reason and the count of non-finite observations or rewards (must be
0) and of out-of-range observations or valves (must be 0). Exits 1 if any is not 0.
"""

from __future__ import annotations

import argparse
import sys
import time

import steamtemp_gym
from steamtemp_gym.envs.corners import run_corners


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--envs", default=",".join(steamtemp_gym.ENV_IDS))
    ap.add_argument("--rows", type=int, default=64)
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    envs = [e for e in args.envs.split(",") if e]
    bad = [e for e in envs if e not in steamtemp_gym.ENV_IDS]
    if bad or args.rows < 1 or args.steps < 1:
        ap.error(
            f"unknown env {bad}; valid: {list(steamtemp_gym.ENV_IDS)}"
            if bad
            else "--rows and --steps must be positive"
        )
    failed = False
    for env_id in envs:
        t0 = time.perf_counter()
        c = run_corners(env_id, args.rows, args.steps, args.seed)
        failed |= c["non_finite"] > 0 or c["out_of_range"] > 0
        print(
            f"{env_id}: {c['steps']} row-steps, {c['episodes']} episodes, "
            f"{c['rejected']} starts rejected, trips {c['trips']}, "
            f"non-finite {c['non_finite']}, out of range {c['out_of_range']} "
            f"({time.perf_counter() - t0:.0f} s)",
            flush=True,
        )
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
