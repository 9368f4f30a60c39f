"""Corner-biased scenarios: the stress distribution of the hardening tests and fuzzing.

Not a training distribution (that is ``random``): every channel is drawn at or near the
ends of its documented range (``scenarios.LIMITS``) with high probability, loads jump or
ramp fast between the ends of the load range, and steps come early. Used by
tests/test_hardening.py and benchmarks/fuzz_corners.py to check that no accepted scenario
makes a plant produce a non-finite observation or reward, whatever the actions.
"""

from __future__ import annotations

import numpy as np

from steamtemp_gym import scenarios as sc

#: Probability that a drawn value sits exactly at one end of its channel's range.
P_END = 0.6


def _corner_value(rng: np.random.Generator, lo: float, hi: float) -> float:
    """A value at an end of [lo, hi] with probability P_END, else uniform inside."""
    if rng.uniform() < P_END:
        return float(lo if rng.uniform() < 0.5 else hi)
    return float(rng.uniform(lo, hi))


def corner_scenario(rng: np.random.Generator, duration_s: float = 1800.0) -> sc.Scenario:
    """One corner-biased scenario (see module docstring); may be one a plant cannot start.

    Load: starts at a corner value, then 1-4 moves to corner values, each a jump or a ramp
    at 5-20 %/min. The setpoint offset, heat-absorption bias, fouling and spray-water
    offset each start at a corner value (setpoint, bias: 0 with probability 0.5) and step
    once to another corner value at a random time. Noise and the coloured disturbance at
    the top of their ranges with probability 0.5.
    """
    lim = sc.LIMITS
    t, load = 0.0, _corner_value(rng, *lim["load"])
    pts = [(0.0, load)]
    for _ in range(int(rng.integers(1, 5))):
        t += float(rng.uniform(0.05, 0.3)) * duration_s
        target = _corner_value(rng, *lim["load"])
        rate = float(rng.uniform(0.05, 0.2)) / 60.0
        dt = 0.0 if rng.uniform() < 0.3 else abs(target - load) / rate
        pts += [(t, load), (t + dt, target)]
        t, load = t + dt, target
    fields: dict[str, object] = {"load": tuple(pts)}
    for ch in ("setpoint_offset_C", "heat_absorption_bias", "fouling",
               "spray_water_temp_offset_C"):  # fmt: skip
        lo, hi = lim[ch]
        v0 = _corner_value(rng, lo, hi)
        if ch in ("setpoint_offset_C", "heat_absorption_bias") and rng.uniform() < 0.5:
            v0 = 0.0
        ts = float(rng.uniform(0.05, 0.7)) * duration_s
        fields[ch] = ((0.0, v0), (ts, v0), (ts + 30.0, _corner_value(rng, lo, hi)))
    noisy = rng.uniform() < 0.5
    return sc.Scenario(
        name="corner",
        duration_s=duration_s,
        noise_std_C=1.0 if noisy else 0.0,
        heat_absorption_noise_std=0.05 if noisy else 0.0,
        heat_absorption_noise_tau_s=60.0,
        **fields,
    )


def run_corners(env_id: str, num_envs: int = 16, steps: int = 500, seed: int = 0) -> dict:
    """Run ``num_envs`` rows of ``env_id`` for ``steps`` control steps under corner scenarios
    and random-walk / bang-bang actions; a row whose episode ends restarts with a new one.

    Returns counts: ``steps`` (row-steps run), ``episodes``, ``rejected`` (scenarios refused
    at reset because the plant cannot hold their start: a clear ValueError, redrawn),
    ``non_finite`` (row-steps with a non-finite observation or reward: must be 0),
    ``out_of_range`` (row-steps with an observation outside the transmitter range or a valve
    outside [0, 1]: must be 0) and ``trips`` by reason.
    """
    from steamtemp_gym import plants
    from steamtemp_gym.envs.core import Core
    from steamtemp_gym.envs.kernels import TRIP_REASONS
    from steamtemp_gym.rewards import RewardConfig
    from steamtemp_gym.signals import OBS_LIMIT

    plant = plants.make(env_id)
    core = Core(plant, num_envs, RewardConfig())
    rng = np.random.default_rng(seed)
    counts = {"steps": 0, "episodes": 0, "rejected": 0, "non_finite": 0, "out_of_range": 0,
              "trips": dict.fromkeys(TRIP_REASONS[1:], 0)}  # fmt: skip

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
        bad = ~(np.isfinite(core.obs).all(axis=1) & np.isfinite(core.out[:, 0]))
        counts["non_finite"] += int(bad.sum())
        valves = core.Z[:, core.valve_idx]
        counts["out_of_range"] += int(((np.abs(core.obs) > OBS_LIMIT).any(axis=1)
                                       | (valves < 0).any(axis=1)
                                       | (valves > 1).any(axis=1)).sum())  # fmt: skip
        for b in np.flatnonzero((core.out[:, 1] > 0) | (core.out[:, 2] > 0)):
            code = int(core.out[b, 1])
            if code:
                counts["trips"][TRIP_REASONS[code]] += 1
            start(int(b))
    return counts
