"""The held-out evaluation scenarios (steamtemp_gym/scenarios/heldout/): outside the
``random`` training distribution by construction, and runnable on every plant.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import baselines
import steamtemp_gym
from agents.evaluation import run_episode
from steamtemp_gym import scenarios
from steamtemp_gym.scenarios import heldout

REQUIRED = {
    "deep_fast_ramp",
    "mill_trip",
    "sootblowing",
    "hp_heater_out",
    "setpoint_ramp_during_load_ramp",
    "high_noise",
}


def test_the_six_held_out_kinds_are_shipped_and_not_registered():
    assert REQUIRED <= set(heldout.NAMES)
    assert not set(heldout.NAMES) & set(scenarios.names())  # training sees names() only
    for name in heldout.NAMES:
        sc = heldout.load(heldout.PREFIX + name)
        assert sc.name == name and sc.description


@pytest.mark.parametrize("name", heldout.NAMES)
def test_random_cannot_draw_a_heldout_scenario(name):
    assert heldout.outside_training(heldout.load(name)), name


def test_every_random_draw_is_inside_the_training_support():
    """The support check accepts what ``random`` draws (so it is not trivially 'outside')."""
    rng = np.random.default_rng(0)
    for _ in range(2000):
        sc = scenarios.random_scenario(rng)
        assert heldout.outside_training(sc) == [], sc


def test_support_check_names_each_feature():
    sc = heldout.load("mill_trip")
    reasons = " ".join(heldout.outside_training(sc))
    assert "heat_absorption_bias" in reasons and "10 s" in reasons and "-0.12" in reasons
    assert "noise_std_C 1 outside" in " ".join(heldout.outside_training(heldout.load("high_noise")))


def test_unknown_name_lists_the_valid_ones():
    with pytest.raises(ValueError, match="heldout:mill_trip"):
        heldout.path("nope")


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_cascade_pi_runs_every_heldout_scenario_without_a_trip(env_id):
    """Every plant starts every file (no start-check refusal) and the conventional
    controller holds it on three seeds."""
    for name in heldout.NAMES:
        env = gym.make(env_id, scenario=heldout.load(name))
        pol = baselines.make("cascade_pi", env)
        for seed in range(3):
            m = run_episode(env, pol, seed)["metrics"]
            assert m["tripped"] == 0.0, (env_id, name, seed, m["max_abs_dev_K"])
