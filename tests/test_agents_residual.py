"""Residual agents on a base controller (agents/residual.py): the observed base's command,
a zero residual acting as the base itself (wrapper and shipped Policy alike), the applied
command told to mpc_linear's estimator, the zeroed output layer, and the entries' checks."""

from __future__ import annotations

import numpy as np
import pytest
import torch
import yaml
from stand_ins import refused_entry

import baselines
from agents import horizons, sb3_models, train_config, vec_env
from agents.policy import AgentPolicy
from agents.residual import ResidualBase
from agents.vec_env import NativeVecEnv
from agents.wrappers import VecResidual
from steamtemp_gym.scenarios import Scenario

ENV_ID = "steamtemp/BensonSubcritical-v0"  # two valves
SHORT = Scenario(
    name="short_for_residual_test",
    duration_s=300.0,
    noise_std_C=0.3,
    load=((0.0, 0.9), (100.0, 0.9), (250.0, 0.7)),
)
ROWS = 2


def _rollout(make, n: int = 40):
    """Observations and env actions of ``n`` steps of a 2-row native vector env acted on
    by ``make(native vector env)``'s Policy."""
    venv = NativeVecEnv(ENV_ID, ROWS, scenario=SHORT)
    policy = make(venv.venv)
    venv.seed(3)
    obs = venv.reset()
    seen, acts = [obs], []
    start = np.ones(ROWS, dtype=bool)
    for _ in range(n):
        a = np.asarray(policy.predict(obs, episode_start=start)[0], np.float32)
        acts.append(a)
        venv.step_async(a)
        obs, _, dones, _ = venv.step_wait()
        start = np.asarray(dones, dtype=bool)
        seen.append(obs)
    return np.array(seen), np.array(acts)


@pytest.mark.parametrize("base", ["mpc_linear", "cascade_pi_ff_tuned"])
def test_a_zero_residual_is_its_base_and_the_agent_sees_the_base_command(base):
    obs_alone, act_alone = _rollout(lambda v: baselines.make(base, v))
    venv = NativeVecEnv(ENV_ID, ROWS, scenario=SHORT)
    res = VecResidual(venv, venv.venv, 0.2, base)
    res.seed(3)
    obs = res.reset()
    n_obs = venv.observation_space.shape[-1]
    assert res.observation_space.shape == (n_obs + 2,)
    for k in range(40):
        np.testing.assert_array_equal(obs[:, :n_obs], obs_alone[k])
        np.testing.assert_array_equal(obs[:, n_obs:], act_alone[k])  # the base's command
        res.step_async(np.zeros((ROWS, 2), np.float32))
        np.testing.assert_array_equal(venv._actions, act_alone[k])
        obs, _, _, _ = res.step_wait()


def test_the_residual_is_scaled_clipped_and_told_to_mpc_linear():
    venv = NativeVecEnv(ENV_ID, ROWS, scenario=SHORT)
    rb = ResidualBase(venv.venv, 0.5, "mpc_linear")
    venv.seed(0)
    obs = venv.reset()
    base = rb.step(obs, np.ones(ROWS, dtype=bool))
    r = np.array([[0.4, -0.2], [3.0, -3.0]])  # the second row beyond [-1, 1]: clipped
    u = rb.combine(r)
    np.testing.assert_allclose(u, np.clip(base + 0.5 * np.clip(r, -1, 1), -1, 1), atol=1e-7)
    for st, ub in zip(rb.policy._rows, u, strict=True):
        np.testing.assert_allclose(st["applied"], np.clip(0.5 * (ub + 1), 0, 1), atol=1e-7)
    rb.step(obs, np.ones(ROWS, dtype=bool))
    rb.combine(np.zeros((ROWS, 2)))  # its own action: nothing to tell
    assert all("applied" not in st for st in rb.policy._rows)


def test_mpc_linear_told_its_own_command_acts_the_same_and_another_one_moves_its_estimate():
    def run(tell):
        venv = NativeVecEnv(ENV_ID, ROWS, scenario=SHORT)
        p = baselines.make("mpc_linear", venv.venv)
        venv.seed(1)
        obs = venv.reset()
        start, out = np.ones(ROWS, dtype=bool), []
        for k in range(12):
            a, _ = p.predict(obs, episode_start=start)
            start[:] = False
            told = tell(k, np.asarray(a, np.float64))
            if told is not None:
                p.applied(told)
            out.append([st["z"].copy() for st in p._rows])
            venv.step_async(np.asarray(a, np.float32))
            obs, _, _, _ = venv.step_wait()
        return np.array(out)

    plain = run(lambda k, a: None)
    np.testing.assert_array_equal(run(lambda k, a: a), plain)  # its own action
    shifted = run(lambda k, a: a + 0.1 if k == 5 else None)
    np.testing.assert_array_equal(shifted[:6], plain[:6])  # the estimate moves at step 6
    assert np.abs(shifted[6] - plain[6]).max() > 1e-6


def test_mpc_linear_refuses_bad_applied_commands_and_changes_nothing():
    venv = NativeVecEnv(ENV_ID, ROWS, scenario=SHORT)
    p = baselines.make("mpc_linear", venv.venv)
    with pytest.raises(ValueError, match="no predict call"):
        p.applied(np.zeros((ROWS, 2)))
    venv.seed(0)
    p.predict(venv.reset())
    before = [dict(st) for st in p._rows]
    for bad in (np.zeros((ROWS, 3)), np.zeros((1, 2)), np.full((ROWS, 2), np.nan)):
        with pytest.raises(ValueError, match="expected finite commands of shape"):
            p.applied(bad)
    assert [set(st) for st in p._rows] == [set(st) for st in before]
    assert all("applied" not in st for st in p._rows)


@pytest.mark.parametrize(
    ("scale", "base", "match"),
    [
        (0.0, "mpc_linear", "residual_scale"),
        (True, "mpc_linear", "residual_scale"),
        (float("nan"), None, "residual_scale"),
        (0.2, "no_such_controller", "residual_base"),
    ],
)
def test_bad_residual_settings_are_refused(scale, base, match):
    venv = NativeVecEnv(ENV_ID, 1, scenario=SHORT)
    with pytest.raises(ValueError, match=match):
        ResidualBase(venv.venv, scale, base)


def test_a_zero_output_ppo_residual_acts_as_its_base(tmp_path):
    """The run's model before its first update, through the shipped agents' Policy: the
    actor's output layer is zero, so the action is mpc_linear's to the last bit."""
    path = train_config.HYPERPARAMS / "ppo_residual_mpc.yml"
    hp = train_config.read_hyperparams(path, ENV_ID, "ppo_residual_mpc")
    venv, native, _ = vec_env.make_training_env(ENV_ID, 2, 0, hp)
    model = sb3_models.sb3_model(train_config.algo_class("ppo_residual_mpc"), hp, venv, 0, None)
    agent = AgentPolicy(
        model,
        native,
        memory=hp["env_wrapper"],
        obs_norm=None,
        residual_scale=hp["residual_scale"],
        residual_base="mpc_linear",
    )
    _, act_base = _rollout(lambda v: baselines.make("mpc_linear", v), n=15)
    _, act_agent = _rollout(lambda v: agent, n=15)
    np.testing.assert_array_equal(act_agent, act_base)
    venv.close()


def test_residual_entries_take_their_base_from_the_algo_and_plant_settings_from_the_rules(tmp_path):
    for algo, base in train_config.RESIDUAL_BASES.items():
        for env_id in ("steamtemp/SupercriticalFSH-v0", "steamtemp/Cascade300MW-v0"):
            f = train_config.HYPERPARAMS / f"{algo}.yml"
            if env_id not in yaml.safe_load(f.read_text()):
                continue
            hp = train_config.read_hyperparams(f, env_id, algo)
            assert hp["residual_base"] == base
            if base is not None:  # the new entries state the rules, not numbers
                assert hp["gamma"] == round(horizons.discount(env_id), 5)
                assert hp["gae_lambda"] == round(horizons.gae_lambda(env_id), 5)
                assert hp["env_wrapper"]["history_stride"] == horizons.history_stride(env_id, 8)
    entry = {"residual_scale": 0.2}
    for hp, match in (
        ({**entry, "residual_base": "mpc_linear"}, "set by the algo"),
        ({}, "residual_scale is required"),
        ({**entry, "residual_scale": 5.0}, "residual_scale must be"),
        ({**entry, "gamma": "plnt"}, "gamma"),
    ):
        refused_entry(tmp_path, ENV_ID, "ppo_residual_mpc", hp, match)


def test_the_actor_holds_still_while_the_critic_warms_up():
    path = train_config.HYPERPARAMS / "ppo_residual_pi.yml"
    hp = train_config.read_hyperparams(path, ENV_ID, "ppo_residual_pi")
    hp.update(n_steps=32, batch_size=32, n_epochs=2)
    venv, _, _ = vec_env.make_training_env(ENV_ID, 2, 0, hp)
    model = sb3_models.sb3_model(train_config.algo_class("ppo_residual_pi"), hp, venv, 0, None)
    actor0 = [p.detach().clone() for p in sb3_models.actor_parameters(model)]
    critic0 = [p.detach().clone() for p in model.policy.value_net.parameters()]
    model.learn(total_timesteps=128, callback=[sb3_models.critic_warmup(10_000)])
    assert all(
        torch.equal(a, p) for a, p in zip(actor0, sb3_models.actor_parameters(model), strict=True)
    )
    assert not all(
        torch.equal(c, p) for c, p in zip(critic0, model.policy.value_net.parameters(), strict=True)
    )
    model.learn(
        total_timesteps=128, callback=[sb3_models.critic_warmup(64)], reset_num_timesteps=False
    )  # past the warm-up: the actor learns
    assert not all(
        torch.equal(a, p) for a, p in zip(actor0, sb3_models.actor_parameters(model), strict=True)
    )
    venv.close()


@pytest.mark.parametrize(
    ("value", "algo", "match"),
    [
        (-1, "ppo", "critic_warmup_steps must be"),
        (1.5, "ppo", "critic_warmup_steps must be"),
        (100, "sac", "critic_warmup_steps is for PPO"),
    ],
)
def test_bad_critic_warmups_are_refused(tmp_path, value, algo, match):
    refused_entry(tmp_path, ENV_ID, algo, {"critic_warmup_steps": value}, match)
