"""Imitation by DAgger (agents/imitation.py): the pairs it records, the expert in shadow
told what was applied, the move term of the regression, and the entries' checks."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch
from stand_ins import refused_entry

import baselines
from agents import imitation, train_config
from agents.behaviour_cloning import regress
from agents.evaluation import run_batch
from baselines.loops import observation_layout
from baselines.mpc_linear import MPCLinear

ENV_ID = "steamtemp/BensonSubcritical-v0"
MEMORY = {"integral_time_s": 60.0, "history": 2, "history_stride": 3}
SEEDS = [11, 12]


def _expert_alone() -> list[dict]:
    venv = gym.make_vec(
        ENV_ID, num_envs=len(SEEDS), vectorization_mode="vector_entry_point", scenario="random"
    )
    return run_batch(venv, baselines.make("mpc_linear", venv), SEEDS)


def test_with_beta_one_the_pairs_are_the_experts_own_episodes():
    x, y, x_next, y_next = imitation.collect(
        ENV_ID, "mpc_linear", MEMORY, SEEDS, 1.0, None, np.random.default_rng(0)
    )
    runs = _expert_alone()
    steps = [len(r["trace"]["time_s"]) - 1 for r in runs]  # actions per episode
    assert len(x) == sum(steps) - len(steps)  # every step but each episode's last
    m = min(steps) - 1  # steps at which both rows are recorded, row 0 then row 1
    row0 = slice(0, 2 * m, 2)
    # the recorded valve openings are those of the expert's own episode
    env = gym.make(ENV_ID)
    names, scale, center = observation_layout(env)
    i = [names.index(v) for v in env.unwrapped.plant.valves]
    seen = x[row0][:, i] * scale[i] + center[i]
    np.testing.assert_allclose(seen, runs[0]["trace"]["spray_valve"][:m], atol=1e-9)
    # consecutive pairs chain: a pair's next step is the same row's following pair
    np.testing.assert_array_equal(x_next[row0][:-1], x[row0][1:])
    np.testing.assert_array_equal(y_next[row0][:-1], y[row0][1:])
    assert np.all(np.abs(y) <= 1.0)


def test_the_learner_acts_and_the_expert_is_told_what_was_applied(monkeypatch):
    calls, told = [], []

    def learner(z):
        calls.append(z.shape)
        return np.full((z.shape[0], 2), 0.25)

    original = MPCLinear.applied

    def applied(self, action):
        told.append(np.array(action))
        original(self, action)

    monkeypatch.setattr(MPCLinear, "applied", applied)

    x, y, _, _ = imitation.collect(
        ENV_ID, "mpc_linear", MEMORY, SEEDS, 0.5, learner, np.random.default_rng(0)
    )
    assert calls and all(c == (len(SEEDS), x.shape[1]) for c in calls)
    assert len(told) == len(calls)  # every mixed step is told to the expert
    learners = np.concatenate([t for t in told]).reshape(-1, 2)
    assert 0.3 < np.mean(np.all(learners == 0.25, axis=1)) < 0.7  # beta 0.5: half the rows
    ref_x, _, _, _ = imitation.collect(
        ENV_ID, "mpc_linear", MEMORY, SEEDS, 1.0, None, np.random.default_rng(0)
    )
    assert len(x) == len(ref_x)
    assert np.abs(x - ref_x).max() > 1e-3  # the learner's steps moved the plant


def test_the_move_term_pulls_the_learners_moves_to_the_experts():
    rng = np.random.default_rng(0)
    x = torch.as_tensor(rng.normal(size=(512, 3)), dtype=torch.float32)
    x_next = x + torch.as_tensor(0.5 * rng.normal(size=(512, 3)), dtype=torch.float32)
    y = torch.zeros(512, 1)  # the expert holds still whatever it sees

    def fitted(weight):
        torch.manual_seed(0)
        net = torch.nn.Sequential(torch.nn.Linear(3, 8), torch.nn.Tanh(), torch.nn.Linear(8, 1))
        with torch.no_grad():
            net[2].bias.fill_(0.3)
        mse = regress(net, x, y, epochs=30, seed=0, moves=(x_next, y + 1e-3, weight))
        with torch.no_grad():
            return mse, float(torch.mean((net(x_next) - net(x)) ** 2))

    _, plain_moves = fitted(0.0)
    _, tied_moves = fitted(10.0)
    assert tied_moves < plain_moves


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        ({"dagger_iterations": 0}, "dagger_iterations"),
        ({"beta_decay": 1.0}, "beta_decay"),
        ({"fit_seconds": -1}, "fit_seconds"),
        ({"move_weight": -0.1}, "move_weight"),
        ({"fit_epochs": 2.5}, "fit_epochs"),
        ({"max_move": 0.05}, "positions"),
    ],
)
def test_bad_imitation_entries_are_config_errors(tmp_path, extra, match):
    refused_entry(tmp_path, ENV_ID, "ppo_imitation_mpc", extra, match)


def test_imitation_keys_are_refused_for_another_algo(tmp_path):
    refused_entry(tmp_path, ENV_ID, "ppo", {"dagger_iterations": 3}, "only for an imitation algo")


@pytest.mark.parametrize(
    ("algo", "extra", "match"),
    [
        ("ppo_imitation_mpc", {"anchor_weight": 1.0}, "only for an imitation fine-tuned by RL"),
        ("ppo_imitation_mpc_rl", {"anchor_weight": -1.0}, "anchor_weight"),
        ("ppo_imitation_mpc_rl", {"anchor_fraction": 0.0}, "anchor_fraction"),
        ("ppo_imitation_mpc_rl", {"anchor_fraction": 1.5}, "anchor_fraction"),
        ("ppo_imitation_mpc_rl", {"dagger_minutes": 0}, "dagger_minutes"),
        ("ppo_imitation_mpc_rl", {"dagger_minutes": "x"}, "dagger_minutes"),
    ],
)
def test_bad_fine_tuning_entries_are_config_errors(tmp_path, algo, extra, match):
    refused_entry(tmp_path, ENV_ID, algo, extra, match)


def test_fine_tuning_keeps_the_frozen_standardization_and_moves_the_reward_scale():
    from agents.vec_env import make_training_env

    hp = train_config.read_hyperparams(
        train_config.HYPERPARAMS / "ppo_imitation_mpc_rl.yml", ENV_ID, "ppo_imitation_mpc_rl"
    )
    venv, _, _ = make_training_env(ENV_ID, 2, 0, {**hp, "normalize": False})
    n = venv.observation_space.shape[0]
    stats = {
        "mean": list(np.linspace(-1, 1, n)),
        "var": list(np.linspace(0.5, 2, n)),
        "epsilon": 1e-8,
        "clip_obs": 10.0,
    }
    norm = imitation.frozen_normalization(venv, stats, 0.99)
    raw = venv.reset()
    norm.reset()
    for _ in range(20):
        obs, *_ = norm.step(np.zeros((2, venv.action_space.shape[0]), np.float32))
    raw = norm.get_original_obs()
    from agents.policy import normalize_obs

    np.testing.assert_array_equal(obs, normalize_obs(raw, stats))
    assert norm.obs_rms.mean.tolist() == stats["mean"] and norm.ret_rms.count > 1
    venv.close()


def test_the_anchor_pulls_the_actor_to_the_experts_actions():
    """After PPO updates, the anchor's steps bring the actor's actions on DAgger's pairs
    closer to the expert's, more with a larger weight; without updates it does nothing."""
    import torch
    from stable_baselines3 import PPO

    from agents.vec_env import make_training_env

    hp = train_config.read_hyperparams(
        train_config.HYPERPARAMS / "ppo_imitation_mpc_rl.yml", ENV_ID, "ppo_imitation_mpc_rl"
    )
    venv, _, _ = make_training_env(ENV_ID, 2, 0, {**hp, "normalize": False})
    n = venv.observation_space.shape[0]
    rng = np.random.default_rng(0)
    x = rng.normal(size=(512, n))
    y = np.tanh(x[:, :1] - x[:, 1:2]).repeat(venv.action_space.shape[0], axis=1)
    stats = {"mean": [0.0] * n, "var": [1.0] * n, "epsilon": 1e-8, "clip_obs": 10.0}
    errors = {}
    for weight in (0.0, 1.0, 10.0):
        model = PPO(
            "MlpPolicy",
            venv,
            n_steps=64,
            batch_size=64,
            n_epochs=2,
            seed=0,
            device="cpu",
            learning_rate=1e-3,
        )
        model.learn(128, callback=imitation.anchor([(x, y)], stats, weight, 10_000, 0))
        with torch.no_grad():
            a = imitation.actor_net(model)(torch.as_tensor(x, dtype=torch.float32)).numpy()
        errors[weight] = float(np.mean((np.clip(y, -1, 1) - a) ** 2))
    assert errors[10.0] < errors[1.0] < errors[0.0]
    venv.close()
