"""The plant's own time scale, and the agent settings read from it.

An agent has to credit a valve move with a temperature change that comes a dead time
later and settles over a lag: its discount must look further ahead than that, its
advantage estimate must reach past the dead time, and its observation must remember
that far back. The time scale is the one a commissioning engineer measures: dead time
plus time constant (Tu + Tg) of the true main-steam temperature after a step of a valve
that acts on it (the plant's main-steam loops, ``Plant.control_loops``), at 50 % load,
the slowest operating point (baselines/identification.py ``step_test``; docs/agents/observation.md
lists them: FSH 53 + 181 s, Benson 55 + 194 s, MIMO 47 + 134 s, Drum 77 + 251 s,
Cascade300MW 113 + 231 s).

The rules (docs/agents/observation.md, "Horizons from the plant"):

- discount: the horizon ``dt / (1 - gamma)`` is :data:`HORIZON_FACTOR` times the time
  scale (a move's whole effect and as long again for the recovery);
- GAE: the window ``dt / (1 - gamma lambda)`` is :data:`GAE_FACTOR` times the dead time
  (the advantage of a move sees its effect begin), lambda at most :data:`GAE_LAMBDA_MAX`;
- history: the controller memory's samples span the time scale (the fewest control steps
  between samples that reach it);
- output filter: a time constant of :data:`FILTER_FACTOR` times the time scale;
- exploration noise of off-policy agents (``noise_type: lowpass``, agents/exploration.py):
  a time constant of :data:`EXPLORATION_FACTOR` times the time scale;
- action repeat (agents/repeat.py): the agent decides every :data:`REPEAT_FACTOR` of the
  dead time (at least every interval), the usual sampling of a dead-time process (four to
  ten samples per dead time); with an action repeat of k intervals the discount and the
  GAE window above hold per decision of k intervals (the same horizons in seconds).
"""

from __future__ import annotations

import functools
import math

from baselines.identification import step_test
from steamtemp_gym import plants
from steamtemp_gym.plants.base import MAIN

#: The operating point of the step test (fraction of rated load): the slowest.
LOAD = 0.5
HORIZON_FACTOR = 2.0
GAE_FACTOR = 2.0
GAE_LAMBDA_MAX = 0.995
#: The output filter's time constant (``action_filter_s``, agents/moves.py) as a fraction
#: of the time scale: 9-14 s, a lag the loop barely sees that cuts a step-to-step jitter's
#: valve travel to its 7-33 % (the interval over the filter's time constant).
FILTER_FACTOR = 0.04
#: The time constant of off-policy agents' low-pass exploration noise (``noise_tau_s:
#: plant``) as a multiple of the time scale: 181-344 s, so that a noise of 5 % of the
#: stroke moves the valves about twice as much as the industrial reference does (white
#: noise of the same size: 20-70 times).
EXPLORATION_FACTOR = 1.0
#: The decision interval (``action_repeat``, agents/repeat.py) as a fraction of the dead
#: time: FSH, MIMO 2 intervals, Benson 1, Drum 3, Cascade300MW 11.
REPEAT_FACTOR = 0.1


@functools.cache
def time_scale(env_id: str) -> tuple[float, float]:
    """(dead time, time constant) in s of the true main-steam temperature after a step of
    the slowest main-steam valve at :data:`LOAD` (module docstring)."""
    plant = plants.make(env_id)
    best = (0.0, 0.0)
    for j, (_, outer) in enumerate(plant.control_loops):
        if outer != MAIN:
            continue
        m = step_test(env_id, j, ["outlet_temp_C"], load=LOAD)["outlet_temp_C"]
        if m.theta_s + m.tau_s > sum(best):
            best = (float(m.theta_s), float(m.tau_s))
    if best == (0.0, 0.0):
        raise ValueError(f"{env_id}: no valve acts on the main-steam temperature")
    return best


def discount(env_id: str, repeat: int = 1) -> float:
    """gamma per decision of ``repeat`` intervals with ``repeat dt / (1 - gamma) =
    HORIZON_FACTOR * (dead time + time constant)``."""
    dt = plants.make(env_id).dt_s * repeat
    return 1.0 - dt / (HORIZON_FACTOR * sum(time_scale(env_id)))


def gae_lambda(env_id: str, repeat: int = 1) -> float:
    """lambda with ``repeat dt / (1 - gamma lambda) = GAE_FACTOR * dead time`` (at most
    :data:`GAE_LAMBDA_MAX`)."""
    dt = plants.make(env_id).dt_s * repeat
    gl = 1.0 - dt / (GAE_FACTOR * time_scale(env_id)[0])
    return min(gl / discount(env_id, repeat), GAE_LAMBDA_MAX)


def action_repeat(env_id: str) -> int:
    """Control intervals per decision: :data:`REPEAT_FACTOR` of the dead time, at least 1."""
    return max(1, int(REPEAT_FACTOR * time_scale(env_id)[0] / plants.make(env_id).dt_s))


def action_filter(env_id: str) -> float:
    """The output filter's time constant in s: :data:`FILTER_FACTOR` times the time scale."""
    return FILTER_FACTOR * sum(time_scale(env_id))


def exploration_time_constant(env_id: str) -> float:
    """The low-pass exploration noise's time constant in s: :data:`EXPLORATION_FACTOR`
    times the time scale."""
    return EXPLORATION_FACTOR * sum(time_scale(env_id))


def history_stride(env_id: str, history: int) -> int:
    """Control steps between the memory's ``history`` samples so that they span the time
    scale: the fewest that reach it (at least 1)."""
    if not (isinstance(history, int) and history >= 1):
        raise ValueError(f"history must be an integer >= 1 to span the plant, got {history!r}")
    dt = plants.make(env_id).dt_s
    return max(1, math.ceil(sum(time_scale(env_id)) / (history * dt)))


#: The value that asks for a setting read from the plant (:func:`from_plant`).
PLANT = "plant"


def from_plant(env_id: str, hp: dict) -> dict:
    """``hp`` (an entry of an RL Zoo hyperparameter file) with every ``plant`` value of
    ``action_repeat``, ``gamma``, ``gae_lambda``, ``action_filter_s``, ``noise_tau_s`` and
    the controller memory's ``history_stride`` replaced by the rule's
    (:func:`action_repeat`, :func:`discount` and :func:`gae_lambda` per decision,
    :func:`action_filter`, :func:`exploration_time_constant`, :func:`history_stride`); the
    entry states the rule instead of numbers."""
    # torch (the agents extra) through agents.repeat: agents.horizons imports without it
    from agents.repeat import check_repeat

    out = dict(hp)
    if out.get("action_repeat") == PLANT:
        out["action_repeat"] = action_repeat(env_id)
    k = check_repeat(out.get("action_repeat", 1))
    rules = {
        "gamma": lambda e: discount(e, k),
        "gae_lambda": lambda e: gae_lambda(e, k),
        "action_filter_s": action_filter,
        "noise_tau_s": exploration_time_constant,
    }
    for key, rule in rules.items():
        if out.get(key) == PLANT:
            out[key] = round(rule(env_id), 5)
    wrappers = out.get("env_wrapper")
    if isinstance(wrappers, list):
        out["env_wrapper"] = [_memory_from_plant(env_id, w) for w in wrappers]
    elif isinstance(wrappers, dict):
        out["env_wrapper"] = _memory_from_plant(env_id, wrappers)
    return out


def _memory_from_plant(env_id: str, item: object) -> object:
    if not (isinstance(item, dict) and len(item) == 1):
        return item
    ((name, kwargs),) = item.items()
    if not (isinstance(kwargs, dict) and kwargs.get("history_stride") == PLANT):
        return item
    return {name: {**kwargs, "history_stride": history_stride(env_id, kwargs.get("history", 4))}}


__all__ = [
    "PLANT",
    "action_filter",
    "action_repeat",
    "discount",
    "exploration_time_constant",
    "from_plant",
    "gae_lambda",
    "history_stride",
    "time_scale",
]


def shortfalls(env_id: str, hp: dict) -> list[str]:
    """What of an entry ``hp`` (checked, its ``plant`` settings read: train_config's
    ``read_hyperparams``) does not cover the plant's time scale (module docstring): the
    discount's horizon shorter than dead time + lag, the GAE window shorter than the dead
    time, or a memory of samples spanning less than dead time + lag (a memory without
    samples: none needed, the error integral or a recurrent policy's state is the
    memory). Empty: it covers."""
    dt = plants.make(env_id).dt_s * (hp.get("action_repeat") or 1)
    theta, tau = time_scale(env_id)
    out = []
    gamma = hp.get("gamma", 0.99)
    if dt / (1.0 - gamma) < theta + tau:
        out.append(
            f"discount horizon {dt / (1.0 - gamma):.0f} s < dead time + lag {theta + tau:.0f} s"
        )
    if "gae_lambda" in hp or "n_steps" in hp:  # an on-policy learner: GAE
        gl = gamma * hp.get("gae_lambda", 0.95)
        if dt / (1.0 - gl) < theta:
            out.append(f"GAE window {dt / (1.0 - gl):.0f} s < dead time {theta:.0f} s")
    memory = hp.get("env_wrapper") or {}
    n = memory.get("history", 4) if memory else 0
    if n:
        span = n * memory.get("history_stride", 5) * plants.make(env_id).dt_s
        if span < theta + tau:
            out.append(
                f"memory of {n} samples spans {span:.0f} s < dead time + lag {theta + tau:.0f} s"
            )
    return out
