"""Action repeat (agents/repeat.py): the agent decides every k control intervals and its
action is held in between, the same in training (VecRepeat) and in the shipped Policy."""

from __future__ import annotations

import json

import numpy as np
import pytest
from stand_ins import Model, ppo_yaml

import steamtemp_gym
from agents import horizons
from agents.moves import VecMoves
from agents.policy import AgentPolicy
from agents.repeat import Decisions, VecRepeat, check_repeat
from agents.vec_env import NativeVecEnv
from steamtemp_gym import plants
from steamtemp_gym.scenarios import Scenario

ENV = "steamtemp/Cascade300MW-v0"
K = 5


def _recorded(native):
    """Record what ``native`` is sent and what it returns, step by step."""
    sent, rewards = [], []
    step_async, step_wait = native.step_async, native.step_wait

    def on_async(a):
        sent.append(np.array(a))
        step_async(a)

    def on_wait():
        out = step_wait()
        rewards.append(np.array(out[1], dtype=np.float64))
        return out

    native.step_async, native.step_wait = on_async, on_wait
    return sent, rewards


# a scenario of 10 intervals: two decisions of K intervals each
SHORT = Scenario(name="short", duration_s=10.0, load=0.8)
FORMS = [{}, {"max_move": 0.03}, {"action_filter_s": 4.0}]
IDS = ["positions", "incremental", "filtered"]


@pytest.mark.parametrize("form", FORMS, ids=IDS)
def test_the_training_wrapper_and_the_policy_act_the_same(form):
    """The same model through VecRepeat (training) and AgentPolicy(action_repeat) give the
    env the same commands over three episodes; the model decides every K intervals; the
    training reward of a decision is the sum of its intervals' rewards."""
    native = NativeVecEnv(ENV, 2, scenario=SHORT)
    assert SHORT.duration_s / native.venv.unwrapped.plant.dt_s == 2 * K
    n = native.action_space.shape[0]
    venv = native
    if form:
        venv = VecMoves(venv, native.venv, form.get("max_move"), form.get("action_filter_s"))
    wrapped = VecRepeat(venv, K, incremental="max_move" in form)
    sent, rewards = _recorded(native)
    native.seed(7)
    obs = wrapped.reset()
    model = Model(n, 2)
    got = []
    for _ in range(6):
        wrapped.step_async(model.predict(obs)[0])
        obs, rew, dones, infos = wrapped.step_wait()
        got.append(rew)
        assert dones.all() == (len(got) % 2 == 0)  # every second decision ends an episode
    commands = np.array(sent)
    assert len(commands) == 6 * K and model.calls == 6
    per_interval = np.array(rewards).reshape(6, K, 2).sum(axis=1)
    np.testing.assert_allclose(np.array(got), per_interval, rtol=1e-6)
    if not form:  # positions: held as decided
        assert (commands[1:K] == commands[0]).all() and (commands[K] != commands[0]).any()
    if "max_move" in form:  # incremental: one move per decision, then the command is held
        assert (commands[1:K] == commands[0]).all()

    native2 = NativeVecEnv(ENV, 2, scenario=SHORT)
    model2 = Model(n, 2)
    policy = AgentPolicy(model2, native2.venv, action_repeat=K, **form)
    native2.seed(7)
    obs = native2.reset()
    start = np.ones(2, dtype=bool)
    for k in range(6 * K):
        a, _ = policy.predict(obs, episode_start=start)
        np.testing.assert_array_equal(a, commands[k])
        native2.step_async(a)
        obs, _, start, _ = native2.step_wait()
    assert model2.calls == 6
    native.close()
    native2.close()


def test_a_row_whose_episode_ends_inside_a_decision_ends_its_transition_there():
    """With K = 4 and 10-interval episodes the episode ends in the third decision's second
    interval: that decision's reward is its first two intervals', the row is done and its
    info carries the terminal observation."""
    native = NativeVecEnv(ENV, 2, scenario=SHORT)
    wrapped = VecRepeat(native, 4, incremental=False)
    _, rewards = _recorded(native)
    native.seed(1)
    wrapped.reset()
    n = native.action_space.shape[0]
    outs = []
    for _ in range(3):
        wrapped.step_async(np.zeros((2, n), dtype=np.float32))
        outs.append(wrapped.step_wait())
    r = np.array(rewards)
    assert not outs[1][2].any() and outs[2][2].all()
    np.testing.assert_allclose(outs[2][1], r[8:10].sum(axis=0), rtol=1e-6)
    assert all("terminal_observation" in info for info in outs[2][3])
    native.close()


def test_a_restarted_row_decides_at_once_and_the_other_keeps_its_clock():
    d = Decisions(3, incremental=True)
    due = d.due(np.ones(2, dtype=bool))
    assert due.all()
    a = d.act(due, np.array([[0.5], [-0.5]]))
    np.testing.assert_array_equal(a, [[0.5], [-0.5]])
    due = d.due(np.zeros(2, dtype=bool))
    assert not due.any()
    np.testing.assert_array_equal(d.act(due, None), [[0.0], [0.0]])  # moves held at zero
    due = d.due(np.array([True, False]))  # row 0 starts a new episode
    np.testing.assert_array_equal(due, [True, False])
    np.testing.assert_array_equal(d.act(due, np.array([[0.25]])), [[0.25], [0.0]])
    np.testing.assert_array_equal(d.due(np.zeros(2, dtype=bool)), [False, True])


@pytest.mark.parametrize("bad", [0, -1, 101, 1.5, 2.0, True, "2", None])
def test_bad_repeats_are_refused(bad):
    with pytest.raises(ValueError, match="action_repeat must be an integer"):
        check_repeat(bad)


def _recurrent_policy(k):
    """An untrained RecurrentPPO on the native env's observation, as a Policy deciding
    every ``k`` intervals."""
    from sb3_contrib import RecurrentPPO

    native = NativeVecEnv(ENV, 1, scenario=SHORT)
    model = RecurrentPPO(
        "MlpLstmPolicy",
        native,
        seed=0,
        device="cpu",
        n_steps=8,
        policy_kwargs={"lstm_hidden_size": 8},
    )
    native.close()
    import gymnasium as gym

    return AgentPolicy(model, gym.make(ENV), action_repeat=k)


def test_a_recurrent_model_decides_every_k_intervals_and_its_state_moves_on_decisions():
    """Held between decisions; a row acted on in a batch with a row that started later
    gets the actions it gets alone (the LSTM state of each row moves on its own
    decisions only)."""
    import gymnasium as gym

    env = gym.make(ENV, scenario="load_ramp_100_50")
    rows = []  # the observations of two episodes under a constant valve
    for s in (0, 1):
        o, _ = env.reset(seed=s)
        trace = []
        for _ in range(9):
            trace.append(o)
            o, *_ = env.step(np.full(env.action_space.shape, 0.3, dtype=np.float32))
        rows.append(np.array(trace))
    alone = _recurrent_policy(3)
    a0 = [alone.predict(x)[0] for x in rows[0]]
    for t in range(1, 9):
        if t % 3:
            np.testing.assert_array_equal(a0[t], a0[t - 1])
    assert np.abs(np.diff(np.array(a0), axis=0)).max() > 0  # it decides
    alone1 = _recurrent_policy(3)
    a1 = [alone1.predict(x)[0] for x in rows[1][:8]]
    batch = _recurrent_policy(3)  # row 1 restarts one interval after row 0 starts
    out = []
    for t in range(9):
        x = np.stack([rows[0][t], rows[1][max(t - 1, 0)]])
        a, _ = batch.predict(x, episode_start=np.array([t == 0, t <= 1]))
        out.append(a)
    out = np.array(out)
    np.testing.assert_allclose(out[:, 0], np.array(a0), atol=1e-6)
    np.testing.assert_allclose(out[1:, 1], np.array(a1), atol=1e-6)


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_the_repeat_rule_and_the_per_decision_horizons(env_id):
    """A tenth of the dead time per decision, and with k intervals per decision the
    discount and GAE window in seconds are those of one interval per decision."""
    dt = plants.make(env_id).dt_s
    theta = horizons.time_scale(env_id)[0]
    k = horizons.action_repeat(env_id)
    assert k == max(1, int(horizons.REPEAT_FACTOR * theta / dt))
    documented = {
        "steamtemp/SupercriticalFSH-v0": 2,
        "steamtemp/BensonSubcritical-v0": 1,
        "steamtemp/BoilerTurbineMIMO-v0": 2,
        "steamtemp/DrumBoilerSH-v0": 3,
        "steamtemp/Cascade300MW-v0": 11,
    }  # docs/agents/observation.md
    assert documented.get(env_id, k) == k  # as horizons.REPEAT_FACTOR says
    g1, gk = horizons.discount(env_id), horizons.discount(env_id, k)
    assert k * dt / (1 - gk) == pytest.approx(dt / (1 - g1))
    l1, lk = horizons.gae_lambda(env_id), horizons.gae_lambda(env_id, k)
    if l1 < horizons.GAE_LAMBDA_MAX and lk < horizons.GAE_LAMBDA_MAX:
        assert k * dt / (1 - gk * lk) == pytest.approx(dt / (1 - g1 * l1))


def test_plant_action_repeat_in_an_entry_sets_the_per_decision_discount():
    env_id = "steamtemp/Cascade300MW-v0"
    out = horizons.from_plant(
        env_id, {"action_repeat": "plant", "gamma": "plant", "gae_lambda": "plant"}
    )
    assert out["action_repeat"] == 11
    assert out["gamma"] == round(horizons.discount(env_id, 11), 5)
    assert out["gae_lambda"] == round(horizons.gae_lambda(env_id, 11), 5)


def _ppo_yaml(tmp_path, **extra):
    return ppo_yaml(tmp_path, ENV, 32, **extra)


def test_an_agent_with_action_repeat_trains_and_acts_every_k_intervals(tmp_path):
    """``action_repeat`` in the hyperparameters: trained through VecRepeat, written to the
    metadata, and the loaded incremental Policy moves its command only when it decides."""
    import gymnasium as gym

    import agents
    from agents import training

    training.train(
        training.checked_run(
            ENV,
            "ppo",
            _ppo_yaml(tmp_path, max_move=0.05, action_repeat=3),
            timesteps=64,
            seed=0,
            out=tmp_path,
            quiet=True,
        )
    )
    meta = json.loads((tmp_path / "steamtemp__Cascade300MW-v0__ppo.json").read_text())
    assert meta["action_repeat"] == 3
    (files,) = agents.files.find(tmp_path)
    pol = files.load()
    assert pol.decisions is not None and pol.decisions.k == 3
    env = gym.make(ENV, scenario="load_ramp_100_50")
    obs, _ = env.reset(seed=0)
    commands = []
    for _ in range(12):
        a, _ = pol.predict(obs)
        commands.append(a)
        obs, *_ = env.step(a)
    c = np.array(commands)
    for t in range(1, 12):
        if t % 3:
            np.testing.assert_array_equal(c[t], c[t - 1])  # held between decisions
    assert np.abs(np.diff(c, axis=0)).max() > 0  # and it does decide


@pytest.mark.parametrize(
    ("algo", "extra", "match"),
    [
        ("ppo", {"action_repeat": 0}, "action_repeat must be an integer"),
        ("ppo", {"action_repeat": "often"}, "action_repeat must be an integer"),
        ("ppo_imitation_mpc", {"action_repeat": 2}, "every interval"),
    ],
)
def test_bad_action_repeat_in_the_hyperparameters_is_refused(tmp_path, algo, extra, match):
    from agents.train_config import ConfigError, read_hyperparams

    with pytest.raises(ConfigError, match=match):
        read_hyperparams(_ppo_yaml(tmp_path, **extra), ENV, algo)
