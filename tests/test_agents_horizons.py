"""The agents' settings from the plant's own time scale (agents/horizons.py), the
observation that spans it (agents/wrappers.py: every signal's history, the load and
setpoint rates) and the travel budget as a priced constraint (agents/travel_price.py)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import yaml
from stand_ins import refused_entry

import steamtemp_gym
from agents import horizons, train_config, training, vec_env
from agents.memory import MemoryConfig
from agents.travel_price import PRICE_MAX, PRICE_MIN, TARGET, VecTravelPrice
from agents.vec_env import NativeVecEnv
from agents.wrappers import MemoryState
from steamtemp_gym import plants
from steamtemp_gym.scenarios import Scenario

#: (dead time, time constant) in s at 50 % load, as docs/agents/observation.md lists them.
DOCUMENTED = {
    "steamtemp/SupercriticalFSH-v0": (53, 181),
    "steamtemp/BensonSubcritical-v0": (55, 194),
    "steamtemp/BoilerTurbineMIMO-v0": (47, 134),
    "steamtemp/DrumBoilerSH-v0": (77, 251),
    "steamtemp/Cascade300MW-v0": (113, 231),
}
ENV_ID = "steamtemp/SupercriticalFSH-v0"


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_time_scale_is_the_documented_step_response(env_id):
    if env_id not in DOCUMENTED:
        pytest.skip(
            f"{env_id}'s time scale is not documented: add it to "
            "docs/agents/observation.md and DOCUMENTED "
            "(python -c 'from agents import horizons; "
            f'print(horizons.time_scale("{env_id}"))\')'
        )
    theta, tau = horizons.time_scale(env_id)
    assert (round(theta), round(tau)) == DOCUMENTED[env_id]


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_discount_gae_and_history_follow_the_rules(env_id):
    dt = plants.make(env_id).dt_s
    theta, tau = horizons.time_scale(env_id)
    gamma, lam = horizons.discount(env_id), horizons.gae_lambda(env_id)
    assert dt / (1 - gamma) == pytest.approx(horizons.HORIZON_FACTOR * (theta + tau))
    window = dt / (1 - gamma * lam)
    assert window == pytest.approx(horizons.GAE_FACTOR * theta) or lam == horizons.GAE_LAMBDA_MAX
    assert dt / (1 - gamma * lam) > theta  # the advantage sees a move's effect begin
    stride = horizons.history_stride(env_id, 8)
    assert 8 * (stride - 1) * dt < theta + tau <= 8 * stride * dt  # the fewest that reach it
    with pytest.raises(ValueError, match="history must be an integer >= 1"):
        horizons.history_stride(env_id, 0)


#: Shipped agents trained before every entry took the plant's time scale, and what falls
#: short (measured by horizons.shortfalls on their metadata); the plant-scale entries
#: (agents/hyperparams/candidates/plant_scale/) replace them.
SHORT_OF_THE_PLANT = {
    ("steamtemp/BensonSubcritical-v0", "ppo"): "memory of 4 samples spans 100 s < 249 s",
    ("steamtemp/BoilerTurbineMIMO-v0", "ppo"): "GAE window 34 s < dead time 47 s, memory 40 s",
    ("steamtemp/DrumBoilerSH-v0", "ppo"): "discount horizon 200 s < 328 s, GAE 34 s, memory 40 s",
    ("steamtemp/Cascade300MW-v0", "ppo_residual"): "discount horizon 333 s < 344 s, GAE 19 s",
    **{
        (e, a): f"memory of 8 samples at a stride rounded to the nearest: {span}"
        for e, span in (
            ("steamtemp/BensonSubcritical-v0", "240 s < 249 s"),
            ("steamtemp/BoilerTurbineMIMO-v0", "176 s < 181 s"),
            ("steamtemp/DrumBoilerSH-v0", "320 s < 328 s"),
        )
        for a in ("bc", "ppo_imitation_mpc", "ppo_imitation_mpc_rl")
    },
}
#: The kinds trained without a return to discount: cloning and DAgger alone.
NOT_DISCOUNTED = ("bc", "ppo_imitation_mpc")


def _shipped_cases():
    import agents

    for env_id, algo in agents.shipped():
        reason = SHORT_OF_THE_PLANT.get((env_id, algo))
        marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
        yield pytest.param(env_id, algo, marks=marks, id=f"{env_id.split('/')[1]}-{algo}")


@pytest.mark.parametrize(("env_id", "algo"), list(_shipped_cases()))
def test_every_shipped_agent_covers_the_plants_dead_time_and_lag(env_id, algo):
    """Its memory spans dead time + lag and, trained by RL, its discount's horizon reaches
    as far and its GAE window past the dead time (as its metadata records them)."""
    import json

    import agents
    from agents.files import steamtemp_files

    meta = json.loads(steamtemp_files(agents.ZOO, env_id, algo, 0).meta[0].read_text())
    hp = {
        **meta.get("hyperparameters", {}),
        "env_wrapper": meta["memory"],
        "action_repeat": meta.get("action_repeat"),
    }
    short = horizons.shortfalls(env_id, hp)
    if algo in NOT_DISCOUNTED:
        short = [s for s in short if s.startswith("memory")]
    assert short == []


def test_plant_in_an_entry_asks_for_the_rules_values():
    env_id = "steamtemp/DrumBoilerSH-v0"
    hp = {
        "gamma": "plant",
        "gae_lambda": "plant",
        "action_filter_s": "plant",
        "n_steps": 64,
        "env_wrapper": [
            {"agents.wrappers.ControllerMemory": {"history": 8, "history_stride": "plant"}}
        ],
    }
    out = horizons.from_plant(env_id, hp)
    assert out["gamma"] == round(horizons.discount(env_id), 5)
    assert out["gae_lambda"] == round(horizons.gae_lambda(env_id), 5)
    assert out["action_filter_s"] == pytest.approx(
        horizons.FILTER_FACTOR * sum(horizons.time_scale(env_id))
    )
    memory = out["env_wrapper"][0]["agents.wrappers.ControllerMemory"]
    assert memory["history_stride"] == horizons.history_stride(env_id, 8) == 21
    assert out["n_steps"] == 64 and hp["gamma"] == "plant"  # the entry itself is unchanged


def test_candidate_ppo_entries_take_the_rules_values():
    """The candidate PPO file (RL Zoo's format, so numbers) holds what the rules give."""
    doc = yaml.safe_load((train_config.HYPERPARAMS / "candidates" / "ppo_horizons.yml").read_text())
    for env_id, hp in doc.items():
        assert hp["gamma"] == pytest.approx(horizons.discount(env_id), abs=5e-6), env_id
        assert hp["gae_lambda"] == pytest.approx(horizons.gae_lambda(env_id), abs=5e-5), env_id
        memory = hp["env_wrapper"][0]["agents.wrappers.ControllerMemory"]
        # written when the stride was rounded to the nearest: at most one step short
        rule = horizons.history_stride(env_id, memory["history"])
        assert memory["history_stride"] in (rule - 1, rule), env_id
        assert memory["history_signals"] == "observation" and memory["rates"] is True


# --------------------------------------------------------------------------- observation
def test_history_of_every_signal_spans_its_stride():
    env = gym.make(ENV_ID)
    m = MemoryState(
        env,
        MemoryConfig(integral=False, history=2, history_stride=3, history_signals="observation"),
    )
    assert m.n_extra == 2 * m.n_obs
    seq = [np.full((1, m.n_obs), float(k)) for k in range(8)]
    out = [m(o) for o in seq][-1]
    np.testing.assert_array_equal(
        out[0, m.n_obs :].reshape(2, m.n_obs), [[4.0] * m.n_obs, [1.0] * m.n_obs]
    )


def test_rates_are_the_filtered_per_minute_changes_of_load_and_setpoint():
    env = gym.make(ENV_ID)
    m = MemoryState(env, MemoryConfig(integral=False, history=0, rates=True, rate_filter_s=20.0))
    assert m.n_extra == 2
    i_load, i_sp = m.i_rate
    dt = env.unwrapped.plant.dt_s
    obs = np.zeros((1, m.n_obs))
    out = m(obs.copy())
    np.testing.assert_array_equal(out[0, -2:], [0.0, 0.0])  # a start has no rate
    for _ in range(200):  # a ramp of 0.01 per step of the load's observation, setpoint held
        obs[0, i_load] += 0.01
        out = m(obs.copy())
    assert out[0, -2] == pytest.approx(0.01 * 60.0 / dt, rel=1e-6)
    assert out[0, -1] == 0.0
    out = m(obs.copy(), restart=np.array([True]))
    np.testing.assert_array_equal(out[0, -2:], [0.0, 0.0])


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"history_signals": "all"}, "history_signals must be one of"),
        ({"rates": 1}, "rates must be true or false"),
        ({"rate_filter_s": 0.0}, "rate_filter_s must be a positive number"),
    ],
)
def test_bad_memory_options_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        MemoryConfig(**kwargs)


# --------------------------------------------------------------------------- travel price
def _priced(price: float) -> tuple[VecTravelPrice, NativeVecEnv]:
    base = NativeVecEnv(ENV_ID, 2, scenario=Scenario(name="short", duration_s=20.0))
    return VecTravelPrice(base, base.venv, reference_rate=1e-3, price=price), base


def test_price_charges_the_travel_and_measures_its_rate():
    priced, base = _priced(2.0)
    plain = NativeVecEnv(ENV_ID, 2, scenario=Scenario(name="short", duration_s=20.0))
    for venv in (priced, plain):
        venv.seed(0)
        venv.reset()
    opening = priced.opening(priced.reset())
    plain.reset()
    stroke = np.ones((2, 1))
    r_priced = priced.step(stroke)[1]
    obs, r_plain, _, _ = plain.step(stroke)
    move = np.abs(priced.opening(obs) - opening).sum(axis=1)
    assert np.all(move > 0)
    np.testing.assert_allclose(r_priced, r_plain - 2.0 * move, rtol=1e-6)
    dt = base.venv.unwrapped.plant.dt_s
    assert priced.ratio() == pytest.approx(move.mean() / dt / 1e-3)
    assert priced.ratio() == 0.0  # restarts


def test_price_rises_over_the_target_and_falls_under_it_within_bounds():
    priced, _ = _priced(1.0)
    priced._travel, priced._steps = 2 * TARGET * 1e-3 * priced.dt * 10, 10
    ratio, up = priced.update()
    assert ratio == pytest.approx(2 * TARGET) and up > 1.0
    priced._travel, priced._steps = 0.0, 10
    _, down = priced.update()
    assert down < up
    for _ in range(100):
        priced._travel, priced._steps = 0.0, 10
        priced.update()
    assert priced.price == PRICE_MIN


@pytest.mark.parametrize("bad", [0.0, -1.0, PRICE_MAX * 2, "0.1", True, float("nan")])
def test_bad_travel_price_is_a_config_error(tmp_path, bad):
    refused_entry(tmp_path, ENV_ID, "ppo", {"travel_price": bad}, "travel_price")
    with pytest.raises(ValueError, match="travel price must be in"):
        _priced(bad if isinstance(bad, float) else -1.0)


def test_training_env_with_a_price_needs_the_reference_rate(tmp_path):
    path = tmp_path / "ppo.yml"
    path.write_text(yaml.safe_dump({ENV_ID: {"policy": "MlpPolicy", "travel_price": 0.1}}))
    hp = train_config.read_hyperparams(path, ENV_ID, "ppo")
    with pytest.raises(train_config.ConfigError, match="reference's travel rate"):
        vec_env.make_training_env(ENV_ID, 2, 0, hp)
    venv, _, price = vec_env.make_training_env(ENV_ID, 2, 0, hp, reference_rate=1e-3)
    assert price.price == 0.1 and PRICE_MIN <= price.price <= PRICE_MAX
    venv.close()


class _Policy:
    """A policy whose deterministic action is its observation's first entry."""

    def _predict(self, x, deterministic=True):
        assert deterministic
        return x[:, :1]


class _Model:
    def __init__(self, actions: np.ndarray, starts: np.ndarray) -> None:
        import types

        obs = np.concatenate([actions[..., None], np.zeros((*actions.shape, 2))], axis=-1)
        self.rollout_buffer = types.SimpleNamespace(
            observations=obs.astype(np.float32), episode_starts=starts, full=True
        )
        self.policy, self.device = _Policy(), "cpu"


def test_policy_travel_is_the_deterministic_actions_travel_along_the_rollout():
    from agents.travel_price import policy_travel

    a = np.array([[0.0, 1.0], [0.5, 1.0], [-0.5, 3.0], [-0.5, 1.0]])  # (steps, rows)
    starts = np.array([[1, 1], [0, 0], [0, 1], [0, 0]], dtype=np.float32)
    # position: half the change of the (clipped) action, not across an episode start
    want = np.mean([0.25, 0.5, 0.0, 0.0, 0.0])  # row 0: 0.25, 0.5, 0; row 1: 0, (start), 0
    assert policy_travel(_Model(a, starts), None) == pytest.approx(want)
    # incremental: max_move times the clipped action
    assert policy_travel(_Model(a, starts), 0.05) == pytest.approx(
        0.05 * np.abs(np.clip(a, -1, 1)).mean()
    )
    assert policy_travel(object(), None) is None  # no rollout buffer: the rollout's travel
    # filtered: the change of the filter's output, restarted at an episode's first action
    p = 0.5 * (np.clip(a, -1, 1) + 1.0)
    u0 = [p[0, 0]]
    for k in range(1, 4):
        u0.append(u0[-1] + 0.5 * (p[k, 0] - u0[-1]))
    u1 = [p[0, 1], p[0, 1], p[2, 1], p[2, 1]]  # row 1: held at 1, restarted at step 2
    moves = list(np.abs(np.diff(u0))) + [abs(u1[1] - u1[0]), abs(u1[3] - u1[2])]
    assert policy_travel(_Model(a, starts), None, 0.5) == pytest.approx(np.mean(moves))
    # one action for two tied valves and one for a third: the tied action moves both
    expand = np.array([0, 0])
    assert policy_travel(_Model(a, starts), 0.05, None, expand) == pytest.approx(
        2 * 0.05 * np.abs(np.clip(a, -1, 1)).mean()
    )


def test_an_off_policy_travel_probe_is_the_scored_policys_closed_loop_travel():
    """Probe k: the policy's travel per second over the reference's on the probe episodes
    (new seeds each probe, apart from the validation's), as validation measures it."""
    from agents.travel_price import PROBE_EPISODES, PROBE_SEED, travel_probe
    from agents.validation import VALIDATION_SEED, validate
    from baselines.cascade_pi import CascadePI

    env_id = "steamtemp/Cascade300MW-v0"
    assert PROBE_SEED >= VALIDATION_SEED + 1000

    def make(venv):
        return CascadePI(venv)

    first = travel_probe(env_id, make, 0, 1e-3)
    want = validate(env_id, make, n=PROBE_EPISODES, seed=PROBE_SEED)["travel_per_s"]
    assert first == pytest.approx(want / 1e-3, rel=1e-12)
    assert travel_probe(env_id, make, 1, 1e-3) != first


def test_an_off_policy_buffer_holds_the_scored_reward_and_charges_the_price_it_samples_at():
    """The priced replay buffer: the wrapper hands over the scored reward (the same as an
    unpriced env's), and a sampled transition's reward is it less the price of the moment
    times the valves' travel from its observation to the next."""
    from stable_baselines3 import TD3

    from agents.travel_price import PricedReplayBuffer, price_replay

    priced, _ = _priced(2.0)
    plain = NativeVecEnv(ENV_ID, 2, scenario=Scenario(name="short", duration_s=20.0))
    model = TD3(
        "MlpPolicy",
        priced,
        buffer_size=64,
        learning_starts=0,
        device="cpu",
        policy_kwargs={"net_arch": [8]},
        seed=0,
    )
    price_replay(model, priced)
    buf = model.replay_buffer
    assert isinstance(buf, PricedReplayBuffer) and not priced.charge
    for venv in (priced, plain):
        venv.seed(0)
    obs, _ = priced.reset(), plain.reset()
    rng = np.random.default_rng(0)
    for _ in range(6):
        a = rng.uniform(-1, 1, size=(2, 1)).astype(np.float32)
        nxt, rew, done, infos = priced.step(a)
        np.testing.assert_array_equal(rew, plain.step(a)[1])  # the scored reward
        buf.add(obs, nxt, a, rew, done, infos)
        obs = nxt
    idx = np.arange(6)
    for price in (2.0, 7.5):  # the rows are drawn from numpy's global generator, as SB3's
        priced.price = price
        np.random.seed(1)  # noqa: NPY002
        got = buf._get_samples(idx)
        np.random.seed(1)  # noqa: NPY002
        rows = np.random.randint(0, high=2, size=6)  # noqa: NPY002
        travel = np.abs(
            priced.opening(buf.next_observations[idx, rows])
            - priced.opening(buf.observations[idx, rows])
        ).sum(axis=-1)
        assert np.all(travel > 0)
        want = buf.rewards[idx, rows] - price * travel
        np.testing.assert_allclose(got.rewards.numpy().ravel(), want, rtol=1e-6)
    with pytest.raises(ValueError, match="holds transitions"):
        price_replay(model, priced)


def test_an_off_policy_agents_price_moves_on_its_deterministic_travel(tmp_path):
    """TD3 with a travel price and action repeat: the price moves every OFF_POLICY_EVERY
    transitions, on the deterministic actor's travel (not the exploring rollout's)."""
    from agents.travel_price import OFF_POLICY_EVERY

    env_id = "steamtemp/Cascade300MW-v0"
    path = tmp_path / "td3.yml"
    path.write_text(
        yaml.safe_dump(
            {
                env_id: {
                    "n_envs": 8,
                    "policy": "MlpPolicy",
                    "normalize": "dict(norm_obs=True)",
                    "learning_starts": 100,
                    "buffer_size": 20000,
                    "batch_size": 32,
                    "train_freq": 1,
                    "gradient_steps": 1,
                    "noise_type": "normal",
                    "noise_std": 0.3,
                    "policy_kwargs": "dict(net_arch=[8])",
                    "max_move": 0.05,
                    "action_repeat": 2,
                    "travel_price": 0.1,
                }
            }
        )
    )
    meta = training.train(
        training.checked_run(
            env_id,
            "td3",
            path,
            timesteps=2 * OFF_POLICY_EVERY + 8,
            seed=0,
            out=tmp_path,
            quiet=True,
        )
    )
    course = meta["travel_price"]["course"]
    assert [c[0] for c in course] == [OFF_POLICY_EVERY, 2 * OFF_POLICY_EVERY]
    assert all(c[1] != c[2] for c in course)  # the policy's travel, not the rollout's
    assert course[-1][3] != 0.1 and meta["action_repeat"] == 2


def test_an_on_policy_price_can_read_the_closed_loop_travel(tmp_path):
    """PPO with ``price_probe_every``: the price moves at the first rollout's end after
    every that many transitions, on the scored policy's travel in closed loop (not on its
    rollout buffer's states); bad values are refused before training."""
    env_id = "steamtemp/Cascade300MW-v0"
    entry = {
        "n_envs": 4,
        "policy": "MlpPolicy",
        "normalize": "dict(norm_obs=True)",
        "n_steps": 64,
        "batch_size": 64,
        "n_epochs": 1,
        "policy_kwargs": "dict(net_arch=dict(pi=[8], vf=[8]))",
        "max_move": 0.05,
        "action_repeat": 2,
        "travel_price": 0.1,
        "price_probe_every": 512,
    }
    path = tmp_path / "ppo.yml"
    for bad, match in (
        (0, "positive integer"),
        (1.5, "positive integer"),
        (True, "positive integer"),
    ):
        path.write_text(yaml.safe_dump({env_id: {**entry, "price_probe_every": bad}}))
        with pytest.raises(ValueError, match=match):
            train_config.read_hyperparams(path, env_id, "ppo")
    path.write_text(
        yaml.safe_dump({env_id: {k: v for k, v in entry.items() if k != "travel_price"}})
    )
    with pytest.raises(ValueError, match="needs travel_price"):
        train_config.read_hyperparams(path, env_id, "ppo")
    path.write_text(yaml.safe_dump({env_id: entry}))
    meta = training.train(
        training.checked_run(
            env_id, "ppo", path, timesteps=4 * 256, seed=0, out=tmp_path, quiet=True
        )
    )
    course = meta["travel_price"]["course"]
    assert [c[0] for c in course] == [512, 1024]  # rollouts of 256 transitions
    assert all(c[1] != c[2] for c in course)  # the scored policy's travel, not the rollout's
