"""steamtemp-train (agents/train.py) and agents.load: a smoke training run of each algo on
one plant, the output files, the loaded Policy (raw observations in, memory state carried,
reset and episode_start honoured, deterministic), and bad input refused before training."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml

import agents
from agents import (
    behaviour_cloning,
    checkpoints,
    train,
    train_config,
    train_runs,
    training,
    validation,
    vec_env,
)
from agents.evaluation import run_episode
from agents.files import steamtemp_paths
from steamtemp_gym.rewards import RewardConfig

ENV_ID = "steamtemp/BensonSubcritical-v0"  # 5 s control interval: short validation episodes
SMALL = {
    "ppo": {"n_steps": 128, "batch_size": 64, "n_epochs": 2},
    "sac": {"learning_starts": 300, "batch_size": 64, "train_freq": 8, "gradient_steps": 1},
    "td3": {
        "learning_starts": 300,
        "batch_size": 64,
        "train_freq": 8,
        "gradient_steps": 1,
        "noise_type": "normal",
        "noise_std": 0.1,
    },
    "trpo": {"n_steps": 128, "batch_size": 64, "n_critic_updates": 2},
    "ppo_residual": {"n_steps": 128, "batch_size": 64, "n_epochs": 2, "residual_scale": 0.2},
    "ppo_residual_mpc": {"n_steps": 128, "batch_size": 64, "n_epochs": 2, "residual_scale": 0.2},
    "ppo_imitation_mpc": {"dagger_iterations": 2, "fit_epochs": 1, "move_weight": 0.01},
    "ppo_imitation_mpc_rl": {
        "dagger_iterations": 2,
        "fit_epochs": 1,
        "n_steps": 128,
        "batch_size": 64,
        "n_epochs": 2,
        "critic_warmup_steps": 512,
        "anchor_weight": 1.0,
        "anchor_fraction": 1.0,
    },
    "sac_caps": {
        "learning_starts": 300,
        "batch_size": 64,
        "train_freq": 8,
        "gradient_steps": 1,
        "caps_temporal": 0.1,
        "caps_spatial": 0.1,
    },
    "recurrentppo": {
        "n_steps": 128,
        "batch_size": 64,
        "n_epochs": 2,
        "policy": "MlpLstmPolicy",
        "policy_kwargs": "dict(lstm_hidden_size=8, net_arch=dict(pi=[16], vf=[16]))",
    },
}
STEPS = {
    "ppo": 2048,
    "sac": 1200,
    "td3": 1200,
    "trpo": 2048,
    "ppo_residual": 1024,
    "ppo_residual_mpc": 1024,
    "ppo_imitation_mpc": 1,
    "ppo_imitation_mpc_rl": 2048,
    "recurrentppo": 1024,
    "sac_caps": 1200,
}
ALGOS = list(STEPS)
MEMORY = [{"agents.wrappers.ControllerMemory": {"integral_time_s": 60.0, "history": 1}}]


def _yaml(tmp_path: Path, algo: str, **extra) -> Path:
    hp = {
        "n_envs": 4,
        "policy": "MlpPolicy",
        "normalize": "dict(norm_obs=True)",
        "env_wrapper": MEMORY,
        "policy_kwargs": "dict(net_arch=dict(pi=[16], vf=[16]))"
        if algo.startswith(("ppo", "trpo"))
        else "dict(net_arch=[16])",
        **SMALL[algo],
        **extra,
    }
    if algo == "recurrentppo":  # the LSTM is its memory
        del hp["env_wrapper"]
    path = tmp_path / f"{algo}.yml"
    path.write_text(yaml.safe_dump({ENV_ID: hp}))
    return path


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> dict[str, Path]:
    out = {}
    for algo in ALGOS:
        d = tmp_path_factory.mktemp(algo)
        training.train(
            training.checked_run(
                ENV_ID, algo, _yaml(d, algo), timesteps=STEPS[algo], seed=1, out=d, quiet=True
            )
        )
        out[algo] = d
    return out


@pytest.mark.parametrize("algo", ALGOS)
def test_smoke_training_writes_model_and_metadata(trained, algo):
    d = trained[algo]
    model, meta_path = steamtemp_paths(d, ENV_ID, algo)
    meta = json.loads(meta_path.read_text())
    assert model.exists()
    assert meta["env_id"] == ENV_ID and meta["algo"] == algo and meta["seed"] == 1
    assert meta["timesteps_trained"] >= STEPS[algo]
    assert [c["fraction"] for c in meta["validation"]["curve"]][-1] >= 1.0
    base = train_config.RESIDUAL_BASES.get(algo)
    # a zero-output residual is validated before training too: its base alone
    dagger = meta["hyperparameters"].get("dagger_iterations", 0)
    rl = 0 if algo == "ppo_imitation_mpc" else len(checkpoints.EVAL_FRACTIONS) + (base is not None)
    assert len(meta["validation"]["curve"]) == dagger + rl
    if dagger:  # DAgger's checkpoints, then PPO's from DAgger's pairs on
        phases = [c["phase"] for c in meta["validation"]["curve"]]
        assert phases == ["dagger"] * dagger + ["rl"] * rl
        assert meta["timesteps_trained"] == meta["validation"]["curve"][-1]["timesteps"]
    assert meta["residual_base"] == base
    n_obs = gym.make(ENV_ID).observation_space.shape[0]
    if algo == "recurrentppo":
        assert meta["memory"] is None and meta["sb3_class"] == "RecurrentPPO"
        assert len(meta["normalization"]["mean"]) == n_obs
    else:
        assert meta["memory"] == MEMORY[0]["agents.wrappers.ControllerMemory"]
        # integral + 1 x (e, 2 valves), and the observed base's 2 commands
        extra = 1 + 3 + (2 if base is not None else 0)
        assert len(meta["normalization"]["mean"]) == n_obs + extra
    assert meta["residual_scale"] == (0.2 if algo in train_config.RESIDUAL_BASES else None)
    chosen: dict = {}
    for c in meta["validation"]["curve"]:
        if validation.better_checkpoint(c, chosen, meta["validation"]["travel_budget"]):
            chosen = c
    assert meta["validation"]["best"]["return"] == chosen["return"]
    # every checkpoint ran the commissioning checks; the kept one passes them if any does
    assert all(
        isinstance(c["check"], str) and c["check_travel_ratio"] > 0
        for c in meta["validation"]["curve"]
    )
    if any(not c["check"] for c in meta["validation"]["curve"]):
        assert meta["validation"]["best"]["check"] == ""
    ref = meta["validation"]["reference"]
    assert ref["policy"] == "cascade_pi_ff" and ref["valve_travel"] > 0
    assert chosen["travel_ratio"] == pytest.approx(chosen["valve_travel"] / ref["valve_travel"])
    assert meta["git_revision"] and meta["wall_time_s"] > 0


@pytest.mark.parametrize(
    "algo",
    [
        "ppo",
        "sac",
        "trpo",
        "recurrentppo",
        "ppo_residual_mpc",
        "ppo_imitation_mpc",
        "ppo_imitation_mpc_rl",
    ],
)
def test_loaded_policy_reproduces_validation_and_is_deterministic(trained, algo):
    pol = agents.load(ENV_ID, algo, zoo=trained[algo])
    meta = json.loads(steamtemp_paths(trained[algo], ENV_ID, algo)[1].read_text())
    env = gym.make(ENV_ID, scenario="random")
    rets = [
        run_episode(env, pol, validation.VALIDATION_SEED + k)["metrics"]["return"]
        for k in range(validation.N_VALIDATION)
    ]
    # validation ran the episodes as one batch: torch's batched matmuls round differently
    assert np.mean(rets) == pytest.approx(meta["validation"]["best"]["return"], rel=1e-6)
    again = run_episode(env, pol, validation.VALIDATION_SEED)["metrics"]["return"]
    assert again == rets[0]


@pytest.mark.parametrize("algo", ["ppo", "recurrentppo"])  # given memory, an LSTM state
def test_loaded_policy_carries_memory_per_row(trained, algo):
    pol = agents.load(ENV_ID, algo, zoo=trained[algo])
    venv = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="vector_entry_point")
    obs, _ = venv.reset(seed=0)
    first, _ = pol.predict(obs)
    a = first
    for _ in range(30):
        obs, *_ = venv.step(a)
        a, _ = pol.predict(obs)
    moved, _ = pol.predict(obs)  # the memory moved on: same obs, another integral
    restarted, _ = pol.predict(obs, episode_start=np.array([True, False]))
    pol.reset()
    fresh, _ = pol.predict(obs)
    np.testing.assert_array_equal(restarted[0], fresh[0])  # row 0 restarted
    assert not np.array_equal(restarted[1], fresh[1])  # row 1 kept its memory
    assert not np.array_equal(moved, fresh)


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (["--env", "steamtemp/Nope-v0", "--algo", "ppo"], "unknown env"),
        (["--env", ENV_ID, "--algo", "a2c"], "unknown algo"),
        (["--env", ENV_ID, "--algo", "ppo", "--hyperparams", "BAD"], "cannot read"),
        (["--env", ENV_ID, "--algo", "ppo", "--hyperparams", "MALFORMED"], "cannot read"),
        (["--env", ENV_ID, "--algo", "ppo", "--hyperparams", "UNKNOWN_KEY"], "n_stepz"),
        (["--env", ENV_ID, "--algo", "ppo", "--hyperparams", "BAD_WRAPPER"], "integral_tme_s"),
        (["--env", ENV_ID, "--algo", "ppo", "--hyperparams", "NO_ENTRY"], "no entry for"),
        (["--env", ENV_ID, "--algo", "ppo", "--hyperparams", "RESIDUAL_KEY"], "residual_scale"),
        (["--env", ENV_ID, "--algo", "ppo", "--hyperparams", "BAD_KWARGS"], "policy_kwargs"),
        (["--env", ENV_ID, "--algo", "ppo", "--timesteps", "0"], "timesteps"),
    ],
)
def test_bad_input_fails_before_training(tmp_path, capsys, args, match):
    files = {
        "BAD": tmp_path / "missing.yml",
        "MALFORMED": tmp_path / "malformed.yml",
        "UNKNOWN_KEY": _yaml(tmp_path, "ppo", n_stepz=3),
        "BAD_WRAPPER": tmp_path / "wrapper.yml",
        "NO_ENTRY": tmp_path / "other.yml",
        "RESIDUAL_KEY": tmp_path / "residual.yml",
        "BAD_KWARGS": tmp_path / "kwargs.yml",
    }
    files["MALFORMED"].write_text(f"{ENV_ID}: [unclosed\n")
    files["BAD_WRAPPER"].write_text(
        yaml.safe_dump(
            {ENV_ID: {"env_wrapper": [{"agents.wrappers.ControllerMemory": {"integral_tme_s": 3}}]}}
        )
    )
    files["NO_ENTRY"].write_text(yaml.safe_dump({"steamtemp/Cascade300MW-v0": {}}))
    files["RESIDUAL_KEY"].write_text(yaml.safe_dump({ENV_ID: {"residual_scale": 0.2}}))
    files["BAD_KWARGS"].write_text(yaml.safe_dump({ENV_ID: {"policy_kwargs": "__import__('os')"}}))
    args = [str(files.get(a, a)) for a in args] + ["--out", str(tmp_path / "out")]
    with pytest.raises(SystemExit) as exc:
        train.main(args)
    assert exc.value.code == 2
    assert match in capsys.readouterr().err
    assert not (tmp_path / "out").exists()  # nothing started


def test_shipped_hyperparams_are_valid_for_every_entry():
    entries = train_runs.zoo_entries()
    assert {e for e, _ in entries} <= set(__import__("steamtemp_gym").ENV_IDS)
    # every shipped agent can be rebuilt: by steamtemp-train --zoo, or the clones by
    # python -m agents.behaviour_cloning --zoo
    clones = {(e, behaviour_cloning.ALGO) for e in __import__("steamtemp_gym").ENV_IDS}
    assert set(agents.shipped()) <= set(entries) | clones
    for env_id, algo in entries:
        hp = train_config.read_hyperparams(train_config.HYPERPARAMS / f"{algo}.yml", env_id, algo)
        assert hp["normalize"]
        # the LSTM learns its memory; every other agent gets the controller memory
        assert (hp["env_wrapper"] is None) == (algo == "recurrentppo")


@pytest.mark.parametrize("algo", ALGOS)
def test_numpy_actor_matches_sb3_predict(trained, algo):
    """The float64 NumPy actor (agents.policy.MlpActor) gives SB3's deterministic action to
    float32 precision; the LSTM policy has none and acts through SB3's predict."""
    pol = agents.load(ENV_ID, algo, zoo=trained[algo])
    if algo == "recurrentppo":
        assert pol.actor is None and pol.batch_tolerance == 1e-6
        return
    assert pol.actor is not None and pol.batch_tolerance == 1e-9
    rng = np.random.default_rng(0)
    x = rng.normal(size=(50, pol.model.observation_space.shape[0])).astype(np.float32)
    expected, _ = pol.model.predict(x, deterministic=True)
    np.testing.assert_allclose(pol.actor(x), expected, atol=1e-5)
    # batch size changes float64 rounding only (an ulp), not float32's (1e-7)
    np.testing.assert_allclose(pol.actor(x[3:4]), pol.actor(x)[3:4], rtol=0, atol=1e-15)


def test_checkpoints_within_the_travel_budget_come_first():
    """The kept checkpoint: the best return within the budget; a checkpoint over it only
    when none is within, and then the one of least travel."""
    a = {"return": -50.0, "travel_ratio": 3.0}
    b = {"return": -80.0, "travel_ratio": 1.5}
    c = {"return": -70.0, "travel_ratio": 1.9}
    d = {"return": -40.0, "travel_ratio": 2.5}
    assert validation.better_checkpoint(a, {}, 2.0)
    assert validation.better_checkpoint(b, a, 2.0) and not validation.better_checkpoint(a, b, 2.0)
    assert validation.better_checkpoint(c, b, 2.0) and not validation.better_checkpoint(d, c, 2.0)
    assert validation.better_checkpoint(d, a, 2.0)  # both over: the lower travel


def test_checkpoints_that_fail_the_commissioning_checks_come_after_those_that_pass():
    """A checkpoint that limit-cycles (or trips, or strokes the valves) in the commissioning
    checks loses to one that passes them, whatever its return and travel; between two that
    fail, the one within the travel budget wins."""
    passes = {"return": -80.0, "travel_ratio": 1.5, "check": ""}
    cycles = {"return": -40.0, "travel_ratio": 1.2, "check": "at 35 % load, seed 1: quiet p2p"}
    over = {"return": -90.0, "travel_ratio": 2.5, "check": ""}
    over_cycles = {"return": -30.0, "travel_ratio": 2.5, "check": "tripped"}
    assert validation.better_checkpoint(passes, cycles, 2.0)
    assert not validation.better_checkpoint(cycles, passes, 2.0)
    assert validation.better_checkpoint(over, cycles, 2.0)  # passing first, then the budget
    assert validation.better_checkpoint(cycles, over_cycles, 2.0)
    assert not validation.better_checkpoint(over_cycles, cycles, 2.0)
    # no checks run (an older record): judged as passing
    assert not validation.better_checkpoint({"return": -90.0, "travel_ratio": 1.5}, passes, 2.0)


def test_train_reward_is_checked_and_applies_to_the_training_envs_only(tmp_path):
    path = tmp_path / "ppo.yml"
    path.write_text(yaml.safe_dump({ENV_ID: {"policy": "MlpPolicy", "train_reward": {"w_mov": 1}}}))
    with pytest.raises(train_config.ConfigError, match="train_reward: unknown reward option"):
        train_config.read_hyperparams(path, ENV_ID, "ppo")
    path.write_text(
        yaml.safe_dump({ENV_ID: {"policy": "MlpPolicy", "train_reward": {"w_move": 5.0}}})
    )
    hp = train_config.read_hyperparams(path, ENV_ID, "ppo")
    charged, _, _ = vec_env.make_training_env(ENV_ID, 2, 0, hp)
    plain, _, _ = vec_env.make_training_env(ENV_ID, 2, 0, {**hp, "train_reward": None})
    stroke = np.ones((2, charged.action_space.shape[0]))  # open every valve fully
    rewards = []
    for venv in (charged, plain):
        venv.reset()
        rewards.append(venv.step(stroke)[1])
    assert np.all(rewards[0] < rewards[1])  # the same move, charged 50x more
    assert RewardConfig().w_move == 0.1  # what validation and the leaderboard charge


def test_plant_randomization_is_checked_and_draws_the_training_plants(tmp_path):
    path = tmp_path / "ppo.yml"
    path.write_text(
        yaml.safe_dump(
            {ENV_ID: {"policy": "MlpPolicy", "plant_randomization": {"heat_transfr": [0.8, 1.2]}}}
        )
    )
    with pytest.raises(train_config.ConfigError, match="unknown group"):
        train_config.read_hyperparams(path, ENV_ID, "ppo")
    path.write_text(yaml.safe_dump({ENV_ID: {"policy": "MlpPolicy", "plant_randomization": True}}))
    hp = train_config.read_hyperparams(path, ENV_ID, "ppo")
    drawn, base, _ = vec_env.make_training_env(ENV_ID, 2, 0, hp)
    drawn.reset()
    plants = base.core.plants
    assert plants[0].params != plants[1].params  # each row its own unit
    _, nominal, _ = vec_env.make_training_env(ENV_ID, 2, 0, {**hp, "plant_randomization": None})
    assert not hasattr(nominal.core, "plants")


def test_zoo_env_takes_the_short_name_and_refuses_an_empty_selection(tmp_path, capsys):
    """``--zoo --env`` resolves the id as ``--env`` does elsewhere; a selection without any
    YAML entry is an error, not a run that trains nothing."""
    assert train_runs.zoo_env("Cascade300MW-v0") == "steamtemp/Cascade300MW-v0"
    for args, match in (
        (["--env", "Nope-v0"], "unknown env id"),
        (["--env", "BensonSubcritical-v0", "--algo", "recurrentppo"], "no entry for"),
    ):
        with pytest.raises(SystemExit) as exc:
            train.main(["--zoo", *args, "--out", str(tmp_path / "z")])
        assert exc.value.code == 2 and match in capsys.readouterr().err
    assert not (tmp_path / "z").exists()
