"""Corner-biased scenarios: the stress distribution of the hardening tests and fuzzing.

Not a training distribution (that is ``random``): every channel is drawn at or near the
ends of its documented range (``scenarios.LIMITS``) with high probability, loads jump or
ramp fast between the ends of the load range, and steps come early. Used by
tests/test_hardening.py and benchmarks/fuzz_corners.py (through
steamtemp_gym/envs/corners.py) and by the contract checks (steamtemp_gym/testing) to check
that no accepted scenario makes a plant produce a non-finite observation or reward,
whatever the actions.
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
    for ch in ("setpoint_offset_C", "heat_absorption_bias", "fouling", "spray_water_temp_offset_C"):
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
