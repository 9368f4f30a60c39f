"""Rows of a plant's env core run under corner-biased scenarios (steamtemp_gym/scenarios/stress.py)
and random-walk / bang-bang actions: the stress run of tests/test_hardening.py and
benchmarks/fuzz_corners.py."""

from __future__ import annotations

import numpy as np

from steamtemp_gym import plants
from steamtemp_gym.envs.core import Core
from steamtemp_gym.envs.kernels import TRIP_REASONS
from steamtemp_gym.rewards import RewardConfig
from steamtemp_gym.scenarios.stress import corner_scenario
from steamtemp_gym.signals import OBS_LIMIT


def run_corners(env_id: str, num_envs: int = 16, steps: int = 500, seed: int = 0) -> dict:
    """Run ``num_envs`` rows of ``env_id`` for ``steps`` control steps under corner scenarios
    and random-walk / bang-bang actions; a row whose episode ends restarts with a new one.

    Returns counts: ``steps`` (row-steps run), ``episodes``, ``rejected`` (scenarios refused
    at reset because the plant cannot hold their start: a clear ValueError, redrawn),
    ``non_finite`` (row-steps with a non-finite observation or reward: must be 0),
    ``out_of_range`` (row-steps with an observation outside the transmitter range or a valve
    outside [0, 1]: must be 0) and ``trips`` by reason.
    """
    plant = plants.make(env_id)
    core = Core(plant, num_envs, RewardConfig())
    rng = np.random.default_rng(seed)
    counts = {
        "steps": 0,
        "episodes": 0,
        "rejected": 0,
        "non_finite": 0,
        "out_of_range": 0,
        "trips": dict.fromkeys(TRIP_REASONS[1:], 0),
    }

    def start(b: int) -> None:
        while True:
            try:
                core.reset_row(b, corner_scenario(rng), int(rng.integers(0, 2**62)))
                counts["episodes"] += 1
                return
            except ValueError:
                counts["rejected"] += 1

    for b in range(num_envs):
        start(b)
    a = np.zeros((num_envs, plant.n_u))
    for k in range(steps):
        if k % 40 < 20:
            a = np.clip(a + rng.normal(0.0, 0.3, a.shape), -1.0, 1.0)
        else:
            a = np.sign(rng.uniform(-1.0, 1.0, a.shape))
        core.step(a)
        counts["steps"] += num_envs
        bad = ~(np.isfinite(core.obs).all(axis=1) & np.isfinite(core.reward))
        counts["non_finite"] += int(bad.sum())
        valves = core.Z[:, core.valve_idx]
        counts["out_of_range"] += int(
            (
                (np.abs(core.obs) > OBS_LIMIT).any(axis=1)
                | (valves < 0).any(axis=1)
                | (valves > 1).any(axis=1)
            ).sum()
        )
        for b in np.flatnonzero(core.ended()):
            code = int(core.trip[b])
            if code:
                counts["trips"][TRIP_REASONS[code]] += 1
            start(int(b))
    return counts
