"""Baselines (parametrized over baselines.NAMES and every env id); the leaderboard CLI is in
tests/test_leaderboard.py."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest

import baselines
import steamtemp_gym
from agents.difficulty import FrozenValves
from agents.evaluation import run_episode
from baselines.policy import Policy
from steamtemp_gym import scenarios

IDS = steamtemp_gym.ENV_IDS


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("name", baselines.NAMES)
def test_baseline_is_a_policy_and_beats_open_loop(env_id, name):
    env = gym.make(env_id, scenario="heat_imbalance_step")
    policy = baselines.make(name, env)
    assert isinstance(policy, Policy)
    res = run_episode(env, policy, seed=0)
    assert res["metrics"]["tripped"] == 0.0
    ref = run_episode(env, FrozenValves(env), seed=0)
    assert res["metrics"]["iae_K_s"] < 0.5 * ref["metrics"]["iae_K_s"]


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("name", baselines.NAMES)
def test_baseline_batched_equals_unbatched(env_id, name):
    """One policy on the native vector env (3 rows) acts as 3 policies on single envs."""
    n, steps = 3, 40
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point",
                        scenario="load_ramp_100_50")  # fmt: skip
    batched = baselines.make(name, venv)
    obs_b, _ = venv.reset(seed=0)
    envs = [gym.make(env_id, scenario="load_ramp_100_50") for _ in range(n)]
    singles = [baselines.make(name, e) for e in envs]
    obs_s = [e.reset(seed=i)[0] for i, e in enumerate(envs)]
    start = np.ones(n, dtype=bool)
    for _ in range(steps):
        a_b, _ = batched.predict(obs_b, episode_start=start, deterministic=True)
        a_s = [p.predict(o, episode_start=start[:1], deterministic=True)[0]
               for p, o in zip(singles, obs_s, strict=True)]  # fmt: skip
        assert a_b.shape == (n, venv.single_action_space.shape[0])
        np.testing.assert_allclose(a_b, np.stack(a_s), rtol=1e-9, atol=1e-9)
        start[:] = False
        obs_b, *_ = venv.step(a_b)
        obs_s = [e.step(a)[0] for e, a in zip(envs, a_s, strict=True)]


@pytest.mark.slow
@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("name", baselines.NAMES)
def test_baseline_runs_every_named_scenario(env_id, name):
    """Every named scenario, seeds 0-2: no exception, NaN action or trip."""
    for sc in scenarios.names(env_id):
        env = gym.make(env_id, scenario=sc)
        policy = baselines.make(name, env)
        for seed in range(3):
            m = run_episode(env, policy, seed=seed)["metrics"]
            assert m["tripped"] == 0.0, (sc, seed)
            assert np.isfinite(m["iae_K_s"]), (sc, seed)


@pytest.mark.parametrize("env_id", IDS)
def test_cascade_pi_tracks_a_setpoint_step(env_id):
    """Without noise (settling is read in a 1 K band); ramp peaks against the field bands are
    in tests/test_difficulty.py."""
    quiet = dataclasses.replace(scenarios.get("setpoint_step"), noise_std_C=0.0,
                                heat_absorption_noise_std=0.0)  # fmt: skip
    params = {"omega_halfwidth_K": 0.0, "omega2_scale_kg_s": 0.0} if "Cascade" in env_id else {}
    sp = gym.make(env_id, scenario=quiet, params=params)
    m = run_episode(sp, baselines.make("cascade_pi", sp), seed=0)["metrics"]
    assert m["overshoot_pct"] < 20.0 and m["settling_time_s"] < 900.0


def test_unknown_baseline_raises():
    with pytest.raises(ValueError, match="valid names"):
        baselines.make("no_such_controller", gym.make(IDS[0]))


@pytest.mark.parametrize("env_id", [i for i in IDS if gym.make(i).unwrapped.plant.secondary])
def test_secondary_temperatures_are_traced_and_scored(env_id):
    env = gym.make(env_id, scenario="heat_imbalance_step")
    res = run_episode(env, baselines.make("cascade_pi", env), seed=0)
    for name, sp in env.unwrapped.plant.secondary:
        assert res["trace"][name][0] == pytest.approx(sp, abs=0.05)
        assert np.isfinite(res["metrics"][f"{name}_max_abs_dev_K"])
        assert res["metrics"][f"{name}_iae_K_s"] > 0.0
