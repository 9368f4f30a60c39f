"""``random``: the seeded training distribution, drawn afresh at every reset."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from steamtemp_gym.scenarios.model import Scenario, as_duration
from steamtemp_gym.scenarios.registry import RANDOM

#: The documented training distribution of ``random`` (see random_scenario).
RANDOM_DISTRIBUTION = {
    "duration_s": 3600.0,
    "initial_load": (0.5, 1.0),
    "hold_s": (120.0, 900.0),
    "ramp_rate_per_min": (0.01, 0.05),
    "load_range": (0.5, 1.0),
    "setpoint_step_probability": 0.3,
    "setpoint_step_K": (-10.0, 10.0),
    "heat_bias_step_probability": 0.5,
    "heat_bias_step": (-0.08, 0.08),
    "fouling": (0.85, 1.15),
    "spray_water_temp_offset_C": (-15.0, 15.0),
    "noise_std_C": (0.2, 0.3),
    "heat_absorption_noise_std": (0.0, 0.04),
    "heat_absorption_noise_tau_s": (120.0, 900.0),
}


def random_scenario(rng: np.random.Generator, duration_s: float | None = None) -> Scenario:
    """Draw one scenario from the training distribution ``RANDOM_DISTRIBUTION``.

    Load: start uniform in 50-100 %, then alternate holds (2-15 min) and ramps at
    1-5 %/min (coal units: about 1.5 %/min typical, 4-6 %/min state of the art)
    to a new target in 50-100 %. With probability 0.3 a setpoint step of
    +-10 K at a random time; with probability 0.5 a heat-absorption bias step of
    +-8 %; a constant fouling factor 0.85-1.15; a constant spray-water
    temperature offset of +-15 K; thermocouple noise 0.2-0.3 K; a coloured
    heat-absorption disturbance of 0-4 % std with a 2-15 min correlation time.
    """
    dist = RANDOM_DISTRIBUTION
    duration = as_duration(duration_s if duration_s is not None else dist["duration_s"])
    u = rng.uniform
    load = u(*dist["initial_load"])
    t = 0.0
    load_pts = [(0.0, load)]
    while t < duration:
        t += u(*dist["hold_s"])
        target = u(*dist["load_range"])
        rate = u(*dist["ramp_rate_per_min"]) / 60.0
        t_end = t + abs(target - load) / rate
        load_pts += [(t, load), (t_end, target)]
        t, load = t_end, target
    sp = [(0.0, 0.0)]
    if u() < dist["setpoint_step_probability"]:
        ts, step = u(0.1, 0.8) * duration, u(*dist["setpoint_step_K"])
        sp = [(0.0, 0.0), (ts, 0.0), (ts, step)]
    bias = [(0.0, 0.0)]
    if u() < dist["heat_bias_step_probability"]:
        ts, step = u(0.1, 0.8) * duration, u(*dist["heat_bias_step"])
        bias = [(0.0, 0.0), (ts, 0.0), (ts + 60.0, step)]
    return Scenario(
        name=RANDOM,
        duration_s=duration,
        load=tuple(load_pts),
        setpoint_offset_C=tuple(sp),
        heat_absorption_bias=tuple(bias),
        fouling=((0.0, u(*dist["fouling"])),),
        spray_water_temp_offset_C=((0.0, u(*dist["spray_water_temp_offset_C"])),),
        noise_std_C=u(*dist["noise_std_C"]),
        heat_absorption_noise_std=u(*dist["heat_absorption_noise_std"]),
        heat_absorption_noise_tau_s=u(*dist["heat_absorption_noise_tau_s"]),
    )


ScenarioFactory = Callable[[np.random.Generator], Scenario]
