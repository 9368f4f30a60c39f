"""A scenario's steady start: the plant in steady state at t = 0 of the scenario (its
coloured heat-absorption disturbance at the mean) must hold the true outlet within
:data:`START_BAND_K` of the setpoint, or an episode would start as a disturbance nobody
can correct. :func:`start_error` measures it, :func:`start_refusal` says why a start
fails and which of the scenario's initial values would make it possible.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from steamtemp_gym import scenarios as sc
from steamtemp_gym.envs.kernels import N_CH, schedules
from steamtemp_gym.plants.base import N_DIST, Plant

#: A scenario must start within this many K of its setpoint in steady state (the +-5 K band
#: plant engineers read): further away the valves are saturated at t = 0 and the episode
#: starts as a disturbance nobody can correct.
START_BAND_K = 5.0


def start_error(plant: Plant, scenario: sc.Scenario) -> tuple[float, np.ndarray, float]:
    """(setpoint - outlet, Z, setpoint) of ``scenario``'s steady start on ``plant`` with its
    coloured disturbance at the mean; the error is NaN if the steady state is not finite."""
    k = sc.max_breakpoints([scenario])
    tables = (np.zeros((1, N_CH, k)), np.zeros((1, N_CH, k)), np.ones((1, N_CH), np.int64))
    sc.pack(scenario, tables[0][0], tables[1][0], tables[2][0])
    D, sp = np.zeros((1, N_DIST)), np.zeros(1)
    schedules(0, 0, 0.0, *tables, plant.setpoint_C, np.zeros(1), D, sp)
    _, z = plant.steady_outputs(D[0], sp[0])
    i_out = plant.index[plant.outlet]
    e = sp[0] - z[i_out] if np.all(np.isfinite(z)) else float("nan")
    return e, z, float(sp[0])


def start_fits(plant: Plant, scenario: sc.Scenario) -> bool:
    """Whether ``plant`` holds ``scenario``'s start in steady state within
    :data:`START_BAND_K` of the setpoint."""
    return bool(abs(start_error(plant, scenario)[0]) <= START_BAND_K)


def start_refusal(plant: Plant, scenario: sc.Scenario, valves: list[int]) -> ValueError | None:
    """None if ``plant`` holds ``scenario``'s start (:func:`start_fits`), else the error that
    says why: the steady outlet's distance from the setpoint with the openings of the
    ``valves`` (output indices), and the initial values whose return to their default
    alone would make the start possible."""
    e, z, sp = start_error(plant, scenario)
    if abs(e) <= START_BAND_K:
        return None
    at0 = {ch: scenario.value(ch, 0.0) for ch in sc.CHANNELS}
    culprits = []
    for ch in sc.CHANNELS:
        default = sc.Scenario.__dataclass_fields__[ch].default
        if at0[ch] != default[0][1]:
            nominal = dataclasses.replace(scenario, **{ch: default})
            if start_fits(plant, nominal):
                culprits.append(f"{ch} = {at0[ch]:g}")
    openings = ", ".join(f"{v:.2f}" for v in z[valves])
    if not np.isfinite(e):
        state = "no finite steady state"
    else:
        side = "below" if e > 0 else "above"
        state = (
            f"the steady outlet is {abs(e):.1f} K {side} the setpoint {sp:.1f} C with the "
            f"valve openings at [{openings}]"
        )
    why = ""
    if culprits:
        names = " or ".join("nominal " + c.split(" =")[0] for c in culprits)
        why = f"; it could with {names} (here {', '.join(culprits)})"
    values = ", ".join(f"{ch} {v:g}" for ch, v in at0.items())
    return ValueError(
        f"scenario {scenario.name!r} cannot start in a steady state {plant.id} can "
        f"hold (within {START_BAND_K:g} K of the setpoint): at t = 0 ({values}) {state}{why}"
    )
