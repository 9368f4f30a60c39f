"""The constraint cost of safe RL (envs/cost.py), its default budget and the six-tuple
wrappers (steamtemp_gym/wrappers.py)."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import steamtemp_gym  # noqa: F401  (registers the ids)
from steamtemp_gym import scenarios as sc
from steamtemp_gym.envs.cost import (
    COST_BAND_K,
    COST_KEYS,
    COST_LIMIT_SHARE,
    DEFAULT_COST_LIMIT_SHARE,
    cost_limit,
    interval_cost,
)
from steamtemp_gym.metrics import trajectory_metrics
from steamtemp_gym.scenarios import heldout
from steamtemp_gym.wrappers import SafetyStep, SafetyVectorStep

#: The two plants that compile fastest, with dt 1 s and 2 s.
IDS = ("steamtemp/Cascade300MW-v0", "steamtemp/SupercriticalFSH-v0")


def _actions(env_id: str, n: int, rows: int = 1) -> np.ndarray:
    """Random valve commands of n steps, wide enough to leave the band often."""
    n_u = gym.spec(env_id).make().unwrapped.plant.n_u
    return np.random.default_rng(7).uniform(-1, 1, (n, rows, n_u)).astype(np.float32)


@pytest.mark.parametrize(
    ("e0", "e1", "cost"),
    [
        (0.0, 0.0, 0.0),
        (4.9, -4.9, 0.0),
        (5.0, 5.0, 0.0),
        (-5.0, 5.0, 0.0),
        (6.0, 6.0, 1.0),
        (-6.0, 7.0, 1.0 - 10.0 / 13.0),
        (4.0, 6.0, 0.5),
        (-6.0, -4.0, 0.5),
        (6.0, 4.0, 0.5),
        (math.nan, 0.0, 1.0),
        (0.0, math.inf, 1.0),
    ],
)
def test_interval_cost_is_the_fraction_outside_the_band(e0, e1, cost):
    assert interval_cost(e0, e1) == pytest.approx(cost, abs=1e-15)
    assert interval_cost(-e0, -e1) == pytest.approx(cost, abs=1e-15)


def test_interval_cost_is_in_zero_one():
    e = np.random.default_rng(0).normal(0.0, 2 * COST_BAND_K, (10_000, 2))
    costs = np.array([interval_cost(a, b) for a, b in e])
    assert costs.min() >= 0.0 and costs.max() <= 1.0
    inside = np.all(np.abs(e) <= COST_BAND_K, axis=1)
    assert inside.any() and np.all(costs[inside] == 0.0)


@pytest.mark.parametrize("env_id", IDS)
def test_band_cost_sums_to_time_outside_5K_s(env_id):
    """sum(cost_band * dt) is the episode's time_outside_5K_s bit for bit; cost is zero
    while the error stays in the band and equal to cost_band (its only component)."""
    env = gym.make(env_id, scenario="setpoint_step")
    dt = env.unwrapped.plant.dt_s
    _, info = env.reset(seed=3)
    assert set(COST_KEYS) <= set(info) and info["cost"] == info["cost_band"] == 0.0
    keys = ("time_s", "outlet_temp_C", "setpoint_C", "spray_valve", "spray_flow_kg_s")
    trace = {k: [info[k]] for k in keys}
    band, cost = [], []
    for a in _actions(env_id, 600)[:, 0] * 0.5:
        _, _, terminated, truncated, info = env.step(a)
        for k in keys:
            trace[k].append(info[k])
        band.append(info["cost_band"])
        cost.append(info["cost"])
        if terminated or truncated:
            break
    band, cost = np.array(band), np.array(cost)
    assert np.array_equal(cost, band) and band.min() >= 0.0 and band.max() <= 1.0
    e = np.array(trace["outlet_temp_C"]) - np.array(trace["setpoint_C"])
    inside = (np.abs(e[:-1]) <= COST_BAND_K) & (np.abs(e[1:]) <= COST_BAND_K)
    assert inside.any() and (~inside).any()
    assert np.all(cost[inside] == 0.0) and np.all(cost[~inside] > 0.0)
    metric = trajectory_metrics(*(trace[k] for k in keys))["time_outside_5K_s"]
    assert metric > 0.0
    assert np.sum(band * dt) == metric  # bit for bit
    assert np.sum(band) * dt == pytest.approx(metric, rel=1e-12)


@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_vector_env_cost_equals_the_single_envs_per_row(mode, tmp_path):
    """Row i's cost is the cost of a single env seeded with seed + i, through the end of
    the episodes (a 60 s scenario) and the autoreset; SafetyVectorStep's costs are the
    costs of the steps whose rewards it returns."""
    env_id, n, steps = IDS[0], 3, 150
    path = tmp_path / "short.yaml"
    path.write_text(
        "name: short\nduration_s: 60\nload: [[0, 1.0]]\n"
        "setpoint_offset_C: [[0, 0], [5, 9]]\nnoise_std_C: 0.3\n"
        "heat_absorption_noise_std: 0.02\n"
    )
    actions = _actions(env_id, steps, n)
    venv = SafetyVectorStep(
        gym.make_vec(
            env_id,
            num_envs=n,
            autoreset_mode=mode,
            vectorization_mode="vector_entry_point",
            scenario=str(path),
        )
    )
    venv.reset(seed=10)
    assert np.array_equal(venv.cost_limit, np.full(n, DEFAULT_COST_LIMIT_SHARE * 60.0))
    got_cost, got_info_cost, got_reward = [], [], []
    for a in actions:
        _, r, c, _, _, info = venv.step(a)
        got_cost.append(c)
        got_info_cost.append(info["cost"])
        got_reward.append(r)
    got_cost, got_reward = np.array(got_cost), np.array(got_reward)
    for i in range(n):
        env = SafetyStep(gym.make(env_id, scenario=str(path)))
        env.reset(seed=10 + i)
        want_cost, want_reward, want_info_cost, done = [], [], [], False
        for a in actions[:, i]:
            if done and mode == "NextStep":  # the vector env's reset step
                _, info = env.reset()
                want_cost.append(0.0)
                want_reward.append(0.0)
                want_info_cost.append(info["cost"])
                done = False
                continue
            _, r, c, terminated, truncated, info = env.step(a)
            want_cost.append(c)
            want_reward.append(r)
            want_info_cost.append(info["cost"])
            done = terminated or truncated
            if done and mode == "SameStep":
                _, info = env.reset()
                want_info_cost[-1] = info["cost"]  # the new episode's reset info
                done = False
        assert np.array_equal(got_reward[:, i], want_reward)
        assert np.array_equal(got_cost[:, i], want_cost)
        assert np.array_equal(np.array(got_info_cost)[:, i], want_info_cost)
        assert got_cost[:, i].max() > 0.0


def test_safety_step_returns_the_six_tuple():
    env = SafetyStep(gym.make(IDS[1], scenario="setpoint_step"))
    obs, info = env.reset(seed=0)
    assert env.cost_limit == COST_LIMIT_SHARE["setpoint_step"] * 1800.0 / 2.0
    out = env.step(env.action_space.sample())
    assert len(out) == 6
    obs, reward, cost, terminated, truncated, info = out
    assert env.observation_space.contains(obs)
    assert isinstance(reward, float) and isinstance(cost, float)
    assert isinstance(terminated, bool) and isinstance(truncated, bool)
    assert cost == info["cost"] >= 0.0


def test_safety_wrappers_refuse_what_they_cannot_wrap():
    venv = gym.make_vec(IDS[0], num_envs=2, vectorization_mode="vector_entry_point")
    with pytest.raises(ValueError, match="use SafetyVectorStep"):
        SafetyStep(venv)
    with pytest.raises(ValueError, match="env of steamtemp_gym"):
        SafetyStep(gym.make("CartPole-v1"))
    with pytest.raises(ValueError, match="gym.make env"):
        SafetyStep("steamtemp/Cascade300MW-v0")
    with pytest.raises(ValueError, match="native vector env"):
        SafetyVectorStep(gym.make(IDS[0]))
    with pytest.raises(ValueError, match="native vector env"):
        SafetyVectorStep(gym.make_vec(IDS[0], num_envs=2, vectorization_mode="sync"))


def test_safety_step_passes_a_bad_action_error_and_changes_nothing():
    env = SafetyStep(gym.make(IDS[0], scenario="setpoint_step"))
    with pytest.raises(ValueError, match="cost_limit"):
        _ = env.cost_limit  # no episode yet
    env.reset(seed=0)
    before = env.unwrapped.snapshot()
    for bad in (np.array([np.nan], np.float32), np.zeros(3, np.float32), "open"):
        with pytest.raises(ValueError, match="action"):
            env.step(bad)
    after = env.unwrapped.snapshot()
    assert before.arrays.keys() == after.arrays.keys()
    for name, value in before.arrays.items():
        assert np.array_equal(value, after.arrays[name]), name


def test_cost_limit_of_every_named_scenario():
    """Every named scenario of every plant and every held-out one has its share (a new
    scenario needs one); the limit is that share of the episode's control intervals."""
    named = {n for env_id in steamtemp_gym.ENV_IDS for n in sc.names(env_id)}
    assert named | set(heldout.NAMES) == set(COST_LIMIT_SHARE)
    assert all(0.0 < s < 1.0 for s in COST_LIMIT_SHARE.values())
    ramp = sc.get("load_ramp_100_50")
    assert cost_limit(ramp, 2.0) == 0.05 * ramp.duration_s / 2.0
    mine = sc.Scenario(name="mine", duration_s=600.0)
    assert cost_limit(mine, 1) == DEFAULT_COST_LIMIT_SHARE * 600.0
    trip = sc.resolve("heldout:mill_trip", "steamtemp/SupercriticalFSH-v0")
    assert cost_limit(trip, 2.0) == COST_LIMIT_SHARE["mill_trip"] * trip.duration_s / 2.0


def test_a_scenario_of_ones_own_under_a_shipped_name_gets_the_default_share():
    """A YAML named ``mill_trip`` got that scenario's 0.45 share; docs/safe_rl.md promises
    any scenario of one's own the default 0.10."""
    mine = sc.Scenario(name="mill_trip", duration_s=600.0)
    assert COST_LIMIT_SHARE["mill_trip"] != DEFAULT_COST_LIMIT_SHARE
    assert cost_limit(mine, 2.0) == DEFAULT_COST_LIMIT_SHARE * 600.0 / 2.0


@pytest.mark.parametrize("dt", [0.0, -1.0, math.nan, math.inf, True, "2", None, 1e-320])
def test_cost_limit_refuses_a_bad_interval(dt):
    with pytest.raises(ValueError, match="dt_s"):
        cost_limit(sc.get("setpoint_step"), dt)


def test_cost_limit_refuses_a_scenario_name():
    with pytest.raises(ValueError, match="needs a Scenario"):
        cost_limit("setpoint_step", 2.0)
