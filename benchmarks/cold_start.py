"""Cold and warm start of each plant, and the size of the compile cache.

For each env id, in a fresh Python process with an empty cache folder
(``STEAMTEMP_GYM_CACHE_DIR``): the wall time of ``import steamtemp_gym`` +
``gym.make`` + ``reset`` + one ``step`` (cold: everything compiles), then the same in a
second process (warm: everything loads from the cache), and the cache's size. Then all
ids compiled into one empty folder by ``python -m steamtemp_gym.precompile`` (one process
per plant, as many at once as there are CPUs): the whole cache of a user of every plant,
and what the command costs after an install.

Machines differ and this one is shared, so each figure is also given as a ratio to a
reference measured in the same run: a fresh process compiling a fixed numba kernel
(``REFERENCE``, about the size of one plant function).

Usage: ``python benchmarks/cold_start.py [ID ...]`` (default: every id).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

START = """
import time
t0 = time.perf_counter()
import gymnasium as gym
import steamtemp_gym
env = gym.make({env_id!r})
env.reset(seed=0)
env.step(env.action_space.sample())
print(time.perf_counter() - t0)
"""

REFERENCE = """
import time
t0 = time.perf_counter()
import numpy as np
from numba import njit

@njit(cache=False)
def kernel(x, y, a):
    out = 0.0
    for i in range(x.shape[0]):
        z = a * x[i] + y[i]
        if z > 0.0:
            out += np.sqrt(z) * np.exp(-z)
        else:
            out -= np.log1p(-z) / (1.0 + z * z)
    return out

kernel(np.ones(4), np.ones(4), 0.5)
print(time.perf_counter() - t0)
"""


def _env(cache: Path) -> dict[str, str]:
    env = dict(os.environ, STEAMTEMP_GYM_CACHE_DIR=str(cache))
    env.pop("NUMBA_CACHE_DIR", None)
    return env


def _run(code: str, cache: Path) -> float:
    """Wall time reported by ``code`` run in a fresh interpreter with cache folder ``cache``."""
    out = subprocess.run(
        [sys.executable, "-c", code],
        cwd=ROOT,
        env=_env(cache),
        check=True,
        capture_output=True,
        text=True,
    )
    return float(out.stdout.strip().splitlines()[-1])


def size_mb(path: Path) -> float:
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file()) / 1e6


def main(argv: list[str] | None = None) -> None:
    sys.path.insert(0, str(ROOT))
    import steamtemp_gym

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "ids",
        nargs="*",
        metavar="ID",
        help=f"env ids (default: all of {', '.join(steamtemp_gym.ENV_IDS)})",
    )
    args = parser.parse_args(argv)
    unknown = sorted(set(args.ids) - set(steamtemp_gym.ENV_IDS))
    if unknown:
        parser.error(f"unknown env id(s) {unknown}; valid: {list(steamtemp_gym.ENV_IDS)}")
    ids = args.ids or list(steamtemp_gym.ENV_IDS)

    with tempfile.TemporaryDirectory() as tmp:
        ref = min(_run(REFERENCE, Path(tmp) / "ref") for _ in range(2))
        cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
        print(f"reference (fresh process compiling one numba kernel): {ref:.2f} s; {cpus} CPUs\n")
        print("| id | cold start, s | x reference | warm start, s | x reference | cache, MB |")
        print("|---|---|---|---|---|---|")
        for env_id in ids:
            cache = Path(tmp) / env_id.replace("/", "_")
            cold = _run(START.format(env_id=env_id), cache)
            warm = _run(START.format(env_id=env_id), cache)
            print(
                f"| {env_id.split('/')[-1]} | {cold:.1f} | {cold / ref:.1f} | {warm:.2f} | "
                f"{warm / ref:.1f} | {size_mb(cache):.1f} |"
            )
        shared = Path(tmp) / "all"
        t0 = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "steamtemp_gym.precompile", *ids],
            cwd=ROOT,
            env=_env(shared),
            check=True,
            capture_output=True,
        )
        took = time.perf_counter() - t0
        print(
            f"\nall {len(ids)} ids by python -m steamtemp_gym.precompile ({cpus} CPUs): "
            f"{took:.0f} s ({took / ref:.1f} x reference), {size_mb(shared):.1f} MB"
        )


if __name__ == "__main__":
    main()
