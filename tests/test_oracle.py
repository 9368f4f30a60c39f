"""The oracle (agents/oracle.py): an upper bound on every controller, deterministic, the
same alone and batched; its budget is checked."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from tunings import missing

import agents
import baselines
import steamtemp_gym
from agents.evaluation import run_batch, run_episode
from agents.leaderboard.episodes import _make_policy
from agents.oracle import Budget, Oracle
from steamtemp_gym.scenarios import Scenario

#: A short scenario with the disturbances of the named ones: a load ramp at 5 %/min, then a
#: heat-absorption step, with sensor noise and the coloured heat-absorption disturbance.
SHORT = Scenario(name="oracle_check", duration_s=900.0,
                 load=((0.0, 1.0), (120.0, 1.0), (300.0, 0.85)),
                 heat_absorption_bias=((0.0, 0.0), (500.0, 0.0), (560.0, 0.04)),
                 noise_std_C=0.25, heat_absorption_noise_std=0.02,
                 heat_absorption_noise_tau_s=300.0)  # fmt: skip


def _contenders(env_id: str) -> list[str]:
    """Every registered baseline (a ``_tuned`` row where ``env_id`` has its stored tuning)
    and every shipped agent of ``env_id``."""
    trained = [f"sb3:{a}" for e, a in agents.shipped() if e == env_id]
    return [n for n in baselines.NAMES if missing(n, env_id) is None] + trained


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_the_oracle_beats_every_baseline_and_shipped_agent(env_id):
    """On a short scenario, seed 0: the oracle's return is at least every registered
    baseline's and every shipped agent's (a ``_tuned`` row joins once the plant has its
    stored tuning). If an admissible policy ever beats it, the oracle is wrong (its
    rollouts see the true future)."""
    env = gym.make(env_id, scenario=SHORT)
    oracle = run_episode(env, Oracle(env), 0)["metrics"]
    assert not oracle["tripped"]
    returns = {p: run_episode(env, _make_policy(p, env_id, env), 0)["metrics"]["return"]
               for p in _contenders(env_id)}  # fmt: skip
    best = max(returns, key=returns.get)
    assert oracle["return"] >= returns[best], (oracle["return"], best, returns)


def test_the_oracle_is_deterministic_and_the_same_alone_and_batched():
    env_id = "steamtemp/Cascade300MW-v0"
    sc = Scenario(name="tiny", duration_s=240.0, load=((0.0, 1.0), (60.0, 1.0), (180.0, 0.9)),
                  noise_std_C=0.25, heat_absorption_noise_std=0.02)  # fmt: skip
    budget = Budget(horizon_s=120.0, knot_s=20.0, replan_s=10.0, samples=6, iterations=2,
                    elites=2)  # fmt: skip
    env = gym.make(env_id, scenario=sc)
    alone = [run_episode(env, Oracle(env, budget), s) for s in (3, 4)]
    again = run_episode(env, Oracle(env, budget), 3)
    venv = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point", scenario=sc)
    batched = run_batch(venv, Oracle(venv, budget), [3, 4])
    for k in alone[0]["trace"]:
        np.testing.assert_array_equal(alone[0]["trace"][k], again["trace"][k], err_msg=k)
        for a, b in zip(alone, batched, strict=True):
            np.testing.assert_array_equal(a["trace"][k], b["trace"][k], err_msg=k)
    assert alone[0]["metrics"]["return"] != alone[1]["metrics"]["return"]  # seeds differ


@pytest.mark.parametrize(("field", "value", "words"), [
    ("samples", 0, "samples"), ("iterations", 1.5, "iterations"), ("horizon_s", -1.0, "horizon"),
    ("elites", 99, "elites"), ("knot_s", 1e6, "knot_s"), ("sigma0", float("nan"), "sigma0"),
])  # fmt: skip
def test_bad_budgets_are_refused(field, value, words):
    with pytest.raises(ValueError, match=words):
        Budget(**{field: value})


def test_the_oracle_refuses_other_envs_and_batch_sizes():
    with pytest.raises(ValueError, match="steamtemp_gym env"):
        Oracle(gym.make("CartPole-v1"))
    venv = gym.make_vec("steamtemp/Cascade300MW-v0", num_envs=2, scenario="setpoint_step",
                        vectorization_mode="vector_entry_point")  # fmt: skip
    obs, _ = venv.reset(seed=0)
    with pytest.raises(ValueError, match="2 row"):
        Oracle(venv).predict(obs[:1])
