"""The critic trained on privileged signals (agents/privileged.py): what it sees, that the
actor never does, and that the shipped policy acts on the agent's observation alone."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest
import torch
from stand_ins import ppo_yaml, refused_entry

import agents
from agents import privileged, training
from agents.policy import MlpActor
from agents.vec_env import NativeVecEnv
from steamtemp_gym import scenarios
from steamtemp_gym.scenarios import Scenario

ENV = "steamtemp/DrumBoilerSH-v0"


def test_the_look_ahead_is_the_scenario_as_the_env_schedules_it():
    ramp = Scenario(
        "ramp",
        900.0,
        load=((0.0, 1.0), (100.0, 1.0), (400.0, 0.6)),
        setpoint_offset_C=((0.0, 0.0), (250.0, 0.0), (250.0, 5.0)),
    )
    venv = NativeVecEnv(ENV, 3, scenario=ramp)
    venv.seed(0)
    venv.reset()
    times = np.asarray(privileged.LOOK_AHEAD_S)
    for _ in range(60):
        state = venv.venv.core.state
        t = state.ep[0, 0]
        for ch in privileged.AHEAD_CHANNELS:
            want = [ramp.value(ch, t + h) for h in times]
            got = privileged.schedule_ahead(state, times, ch)
            np.testing.assert_allclose(got, np.tile(want, (3, 1)), atol=1e-12, err_msg=f"{ch} {t}")
        venv.step(np.zeros((3, 1), dtype=np.float32))
    assert t > 100  # past the ramp's start: the look-ahead met the breakpoints
    venv.close()


def test_each_row_looks_ahead_on_its_own_scenario():
    venv = NativeVecEnv(ENV, 4, scenario="random")
    venv.seed(7)
    venv.reset()
    for _ in range(30):
        venv.step(np.zeros((4, 1), dtype=np.float32))
    state = venv.venv.core.state
    times = np.asarray(privileged.LOOK_AHEAD_S)
    got = privileged.schedule_ahead(state, times, "load")
    for b in range(4):
        sc = venv.views[b].scenario
        np.testing.assert_allclose(got[b], [sc.value("load", state.ep[b, 0] + h) for h in times])
    venv.close()


def test_the_wrapper_appends_the_privileged_signals_after_the_agents_observation():
    base = NativeVecEnv(ENV, 2, scenario=scenarios.get("load_ramp_100_50"))
    wrapped = privileged.VecPrivileged(base, base.venv)
    names = privileged.signal_names(base.venv.core.plant)
    assert wrapped.observation_space.shape == (base.observation_space.shape[0] + len(names),)
    assert "outlet_temp_C" in names and "fouling" in names and "load@+300s" in names
    assert "outlet_temp_meas_C" not in names  # observed: the agent's already
    wrapped.seed(0)
    obs = wrapped.reset()
    n = base.observation_space.shape[0]
    core = base.venv.core
    for _ in range(5):
        np.testing.assert_array_equal(obs[:, :n], core.state.obs.astype(np.float32))
        i = names.index("outlet_temp_C")
        sig = next(s for s in core.plant.outputs if s.name == "outlet_temp_C")
        true = (core.state.Z[:, core.plant.index["outlet_temp_C"]] - sig.center) / sig.scale
        np.testing.assert_allclose(obs[:, n + i], true, rtol=1e-6)
        obs, *_ = wrapped.step(np.zeros((2, 1), dtype=np.float32))
    wrapped.close()


def _policy(n_actor=5, n_all=9):
    from gymnasium import spaces

    space = spaces.Box(-np.inf, np.inf, (n_all,), np.float32)
    act = spaces.Box(-1.0, 1.0, (1,), np.float32)
    return privileged.PrivilegedCriticPolicy(
        space, act, lambda _: 3e-4, actor_inputs=n_actor, net_arch=dict(pi=[8], vf=[8])
    )


def test_the_actor_never_reads_the_privileged_entries_and_the_critic_does():
    pol = _policy()
    x = torch.zeros((1, 9))
    y = x.clone()
    y[0, 5:] = torch.tensor([3.0, -2.0, 1.0, 7.0])
    with torch.no_grad():
        assert torch.equal(
            pol.get_distribution(x).distribution.mean, pol.get_distribution(y).distribution.mean
        )
        assert not torch.equal(pol.predict_values(x), pol.predict_values(y))
    assert pol.mlp_extractor.policy_net[0].in_features == 5
    assert pol.mlp_extractor.value_net[0].in_features == 9


@pytest.mark.parametrize("bad", [0, 9, 12, 2.5, None])
def test_bad_actor_inputs_are_refused(bad):
    with pytest.raises((ValueError, TypeError), match="actor_inputs"):
        _policy(n_actor=bad)


def test_a_privileged_critic_is_the_algos_not_the_files(tmp_path):
    refused_entry(tmp_path, ENV, "ppo_privileged", {"privileged_critic": True}, "set by the algo")


def test_a_trained_agent_acts_on_its_observation_alone(tmp_path):
    """Trained with the wrapper; the metadata names what its critic saw; the loaded policy
    takes the env's observation, its actor the agent's normalized entries; SB3's own
    predict (the privileged entries zero) gives the same action."""
    hp = ppo_yaml(
        tmp_path, ENV, 32, env_wrapper=[{"agents.wrappers.ControllerMemory": {"history": 2}}]
    )
    meta = training.train(
        training.checked_run(
            ENV, "ppo_privileged", hp, timesteps=128, seed=0, out=tmp_path, quiet=True
        )
    )
    names = meta["privileged_critic"]["signals"]
    assert names == privileged.signal_names(gym.make(ENV).unwrapped.plant)
    stored = json.loads((tmp_path / "steamtemp__DrumBoilerSH-v0__ppo_privileged.json").read_text())
    pol = agents.load(ENV, "ppo_privileged", zoo=tmp_path)
    n_actor = pol.model.policy.actor_inputs
    assert len(stored["normalization"]["mean"]) == n_actor
    assert pol.model.observation_space.shape == (n_actor + len(names),)
    assert isinstance(pol.actor, MlpActor)
    x = np.random.default_rng(0).normal(size=(4, n_actor))
    for extra in (np.zeros((4, len(names))), np.full((4, len(names)), 5.0)):
        sb3, _ = pol.model.predict(np.hstack([x, extra]).astype(np.float32), deterministic=True)
        np.testing.assert_allclose(pol.actor(x), sb3, atol=1e-5)
    env = gym.make(ENV, scenario="load_ramp_100_50")
    obs, _ = env.reset(seed=0)
    for _ in range(10):
        a, _ = pol.predict(obs)
        b, _ = pol.predict(obs, deterministic=False)  # SB3's predict, padded
        assert np.all(np.isfinite(a)) and np.all(np.isfinite(b))
        obs, *_ = env.step(a)
