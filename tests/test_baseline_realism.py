"""Actuator realism of every baseline on every plant: what a plant would accept.

On a load ramp and a held-out fast deep ramp (seed 0), each baseline's valve travel stays
within :data:`TRAVEL_MAX` times the industrial reference's (``cascade_pi_ff``) on the same
episode, and its quiet stretch shows no sustained oscillation
(``steamtemp_gym.metrics.limit_cycles``: the quiet peak-to-peak at most
``LIMIT_CYCLE_RATIO`` times the reference's, or ``LIMIT_CYCLE_FLOOR_K``). Spray valves
erode with stroking; a controller that chatters or limit-cycles would be taken off a unit
whatever its IAE.
"""

from __future__ import annotations

import functools

import gymnasium as gym
import pytest

import baselines
import steamtemp_gym
from agents.evaluation import run_episode
from steamtemp_gym.metrics import limit_cycles

REFERENCE = "cascade_pi_ff"
TRAVEL_MAX = 3.0
SCENARIOS = ("load_ramp_100_50", "heldout:deep_fast_ramp")
SEED = 0


@functools.cache
def _metrics(env_id: str, scenario: str, name: str) -> dict:
    env = gym.make(env_id, scenario=scenario)
    return run_episode(env, baselines.make(name, env), SEED)["metrics"]


#: The (plant, baseline) pairs measured to break the criterion, with the first check that
#: fails (seed 0). The deep fast ramp ends at 35 % load, below the 50-100 % of the training
#: episodes and of the loops' commissioning: fixed gains tuned there for the best training
#: score (the ``_tuned`` rows, ``fuzzy_p2id``) stroke the valves at that load; see
#: docs/baselines.md.
MEASURED_FAILURES = {
    ("SupercriticalFSH-v0", "cascade_pi_tuned"): "deep ramp: travel 16.60x the reference's",
    ("DrumBoilerSH-v0", "cascade_pi_tuned"): "deep ramp: travel 14.76x the reference's",
    ("BoilerTurbineMIMO-v0", "cascade_pi_tuned"): "deep ramp: travel 5.42x the reference's",
    ("DrumBoilerSH-v0", "fuzzy_p2id"): "deep ramp: travel 3.58x the reference's",
}


def _cases() -> list:
    out = []
    for env_id in steamtemp_gym.ENV_IDS:
        for name in baselines.SHIPPED:
            if name == REFERENCE:
                continue
            reason = MEASURED_FAILURES.get((env_id.split("/")[-1], name))
            marks = [pytest.mark.xfail(strict=True, reason=f"measured: {reason}")] if reason else []
            out.append(pytest.param(env_id, name, marks=marks, id=f"{env_id}-{name}"))
    return out


@pytest.mark.parametrize(("env_id", "name"), _cases())
def test_travel_within_three_times_the_reference_and_no_limit_cycle(env_id, name):
    for scenario in SCENARIOS:
        ref, m = _metrics(env_id, scenario, REFERENCE), _metrics(env_id, scenario, name)
        assert not m["tripped"], (scenario, "tripped")
        ratio = m["valve_travel"] / ref["valve_travel"]
        assert ratio <= TRAVEL_MAX, (scenario, f"travel {m['valve_travel']:.2f} = {ratio:.2f}x "
                                               f"the reference's {ref['valve_travel']:.2f}")
        assert not limit_cycles(m["quiet_p2p_K"], ref["quiet_p2p_K"]), (
            scenario, f"quiet p2p {m['quiet_p2p_K']:.2f} K against the reference's "
                      f"{ref['quiet_p2p_K']:.2f} K")  # fmt: skip


def test_limit_cycle_criterion():
    """The criterion flags a swing above twice the reference's and the floor, nothing else."""
    assert limit_cycles(4.0, 1.0) and limit_cycles(3.1, 1.5)
    assert not limit_cycles(2.9, 1.5) and not limit_cycles(1.4, 0.2)
    assert not limit_cycles(float("nan"), 1.0)
