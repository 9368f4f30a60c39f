"""The shipped zoo (agents/zoo/): every agent loads, runs a full named scenario without
error, deterministically, and the leaderboard lists it; every plant has a trained agent. The
RL Zoo path (slow): the shipped YAML works unchanged with ``python -m rl_zoo3.train``."""

from __future__ import annotations

import json
import subprocess
import sys

import gymnasium as gym
import pytest

import agents
import steamtemp_gym
from agents import behaviour_cloning, files, train_config, train_runs
from agents.evaluation import run_episode
from agents.leaderboard.plan import available_policies


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_every_plant_has_a_shipped_agent_with_three_training_runs(env_id):
    """A plant without a shipped agent (one just added) is skipped, saying how to train one."""
    algos = [a for e, a in agents.shipped() if e == env_id]
    if not algos:
        pytest.skip(
            f"{env_id} has no shipped agent; train one with "
            f"python -m agents.train --zoo --env {env_id} --runs 3"
        )
    assert all(agents.runs(env_id, a) == [0, 1, 2] for a in algos)


def test_every_algorithm_says_what_kind_of_agent_it_trains():
    # the training algorithms, and behaviour cloning from an offline dataset
    assert set(agents.KINDS) == {*train_config.ALGOS, behaviour_cloning.ALGO}
    assert {agents.kind(a) for _, a in agents.shipped()} <= set(agents.KINDS.values())
    assert agents.kind("ppo_residual").startswith("residual over ")
    assert agents.kind("my_algo") == "trained agent"


@pytest.mark.parametrize(("env_id", "algo"), agents.shipped())
def test_shipped_agent_runs_a_named_scenario_deterministically(env_id, algo):
    meta = json.loads(files.steamtemp_paths(agents.ZOO, env_id, algo)[1].read_text())
    assert meta["env_id"] == env_id and meta["algo"] == algo
    pol = agents.load(env_id, algo)
    env = gym.make(env_id, scenario="setpoint_step")
    first = run_episode(env, pol, seed=0)["metrics"]
    again = run_episode(env, pol, seed=0)["metrics"]
    assert first == again
    # the leaderboard scores it, once per training run where the zoo holds several
    from agents import specs

    named = [specs.split_run(n)[0] for n in available_policies(env_id)]
    assert f"sb3:{algo}" in named


def test_unknown_agent_lists_the_shipped_ones():
    with pytest.raises(ValueError, match="shipped"):
        agents.load("steamtemp/Cascade300MW-v0", "a2c")


#: RL Zoo's algo name of each shipped YAML file (the residual is our extension: not RL Zoo's).
RL_ZOO_ALGO = {"ppo": "ppo", "sac": "sac", "td3": "td3", "trpo": "trpo", "recurrentppo": "ppo_lstm"}


@pytest.mark.slow
@pytest.mark.parametrize("algo", sorted(RL_ZOO_ALGO))
def test_rl_zoo_trains_with_the_shipped_yaml(tmp_path, algo):
    pytest.importorskip("rl_zoo3")
    env_id = train_runs.zoo_entries_of(algo)[0]
    yml = train_config.HYPERPARAMS / f"{algo}.yml"
    cmd = [
        sys.executable,
        "-m",
        "rl_zoo3.train",
        "--algo",
        RL_ZOO_ALGO[algo],
        "--env",
        env_id,
        "--gym-packages",
        "steamtemp_gym",
        "--conf-file",
        str(yml),
        "-n",
        "4096",
        "--log-folder",
        str(tmp_path),
        "--eval-freq",
        "-1",
    ]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "Loading hyperparameters from" in done.stdout  # ours, not RL Zoo's defaults
    assert "agents.wrappers.ControllerMemory" in done.stdout or algo == "recurrentppo"
    assert list(tmp_path.rglob("*.zip"))
