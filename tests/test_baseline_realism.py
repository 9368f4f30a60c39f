"""Actuator realism of every baseline on every plant: what a plant would accept.

On a load ramp and a held-out fast deep ramp (seed 0), each baseline's valve travel stays
within ``agents.stats.REALISM_TRAVEL_MAX`` times the industrial reference's
(``cascade_pi_ff``) on the same episode, and its quiet stretch shows no sustained oscillation
(``steamtemp_gym.metrics.limit_cycles``: the quiet peak-to-peak at most
``LIMIT_CYCLE_RATIO`` times the reference's, or ``LIMIT_CYCLE_FLOOR_K``):
``agents.stats.realism_breach``. Spray valves
erode with stroking; a controller that chatters or limit-cycles would be taken off a unit
whatever its IAE.
"""

from __future__ import annotations

import functools

import gymnasium as gym
import pytest
from tunings import skip_without_tuning

import baselines
import steamtemp_gym
from agents.evaluation import run_episode
from agents.stats import realism_breach
from steamtemp_gym.metrics import limit_cycles

REFERENCE = "cascade_pi_ff"
SCENARIOS = ("load_ramp_100_50", "heldout:deep_fast_ramp")
SEED = 0


@functools.cache
def _metrics(env_id: str, scenario: str, name: str) -> dict:
    env = gym.make(env_id, scenario=scenario)
    return run_episode(env, baselines.make(name, env), SEED)["metrics"]


def _cases() -> list:
    return [
        pytest.param(env_id, name, id=f"{env_id}-{name}")
        for env_id in steamtemp_gym.ENV_IDS
        for name in baselines.SHIPPED
        if name != REFERENCE
    ]


@pytest.mark.parametrize(("env_id", "name"), _cases())
def test_travel_within_three_times_the_reference_and_no_limit_cycle(env_id, name):
    skip_without_tuning(name, env_id)
    for scenario in SCENARIOS:
        ref, m = _metrics(env_id, scenario, REFERENCE), _metrics(env_id, scenario, name)
        breach = realism_breach(m, ref)
        assert breach is None, (scenario, breach)


def test_realism_breach_names_each_check():
    """Each check of the criterion fails on its own, with its numbers, and nothing else."""
    ref = {"tripped": False, "valve_travel": 2.0, "quiet_p2p_K": 1.0}
    assert realism_breach(dict(ref), ref) is None
    assert realism_breach({**ref, "tripped": True}, ref) == "tripped"
    assert "3.50x" in realism_breach({**ref, "valve_travel": 7.0}, ref)
    assert realism_breach({**ref, "valve_travel": 6.0}, ref) is None  # exactly 3x passes
    assert "quiet p2p 2.10 K" in realism_breach({**ref, "quiet_p2p_K": 2.1}, ref)


def test_limit_cycle_criterion():
    """The criterion flags a swing above twice the reference's and the floor, nothing else."""
    assert limit_cycles(4.0, 1.0) and limit_cycles(3.1, 1.5)
    assert not limit_cycles(2.9, 1.5) and not limit_cycles(1.4, 0.2)
    assert not limit_cycles(float("nan"), 1.0)
