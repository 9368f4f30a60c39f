"""python -m steamtemp_gym.precompile: every kernel of an episode compiled ahead of first use."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from steamtemp_gym import precompile

_USE = """
import json, sys
import gymnasium as gym, numpy as np
import steamtemp_gym
env = gym.make(sys.argv[1])
env.reset(seed=0)
env.step(env.action_space.sample())
env.step(np.zeros(env.action_space.shape))
out = {}
for kernel, _ in env.unwrapped.core.compile_calls():
    s = kernel.stats
    out[kernel.py_func.__qualname__] = [sum(s.cache_hits.values()), sum(s.cache_misses.values())]
print(json.dumps(out))
"""


def test_a_precompiled_plant_loads_every_step_kernel_from_the_cache(tmp_path):
    """On an empty cache folder the command compiles Cascade300MW; a later process then
    loads every kernel of its reset and step from the cache and compiles none."""
    env = dict(os.environ, STEAMTEMP_GYM_CACHE_DIR=str(tmp_path))
    env.pop("NUMBA_CACHE_DIR", None)
    run = subprocess.run(
        [sys.executable, "-m", "steamtemp_gym.precompile", "Cascade300MW-v0", "--jobs", "1"],
        env=env,
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert "steamtemp/Cascade300MW-v0" in run.stdout and "done in" in run.stdout
    out = subprocess.run(
        [sys.executable, "-c", _USE, "steamtemp/Cascade300MW-v0"],
        env=env,
        check=True,
        capture_output=True,
        text=True,
    )
    stats = json.loads(out.stdout.strip().splitlines()[-1])
    assert len(stats) == 9  # to_commands twice (float32, float64 actions)
    for name, (hits, misses) in stats.items():
        assert misses == 0 and hits >= 1 + (name == "to_commands"), (name, hits, misses)
    assert "compiling" not in out.stderr


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["NoSuchPlant-v0"], "unknown env id 'NoSuchPlant-v0'"),
        (["--jobs", "0"], "--jobs must be at least 1"),
    ],
)
def test_bad_arguments_are_refused_before_compiling(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        precompile.main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "compiling" not in err
