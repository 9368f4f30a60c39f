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
from steamtemp_gym import plants
from steamtemp_gym.envs.snapshot import copy_rows
from steamtemp_gym.plants import perturb
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


#: A setpoint step and a load change, short: what the oracle's model must get right.
STEP = Scenario(name="oracle_step", duration_s=600.0, load=((0.0, 1.0), (300.0, 1.0), (420.0, 0.9)),
                setpoint_offset_C=((0.0, 0.0), (60.0, 0.0), (60.0, 10.0)),
                noise_std_C=0.25, heat_absorption_noise_std=0.02)  # fmt: skip


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_the_oracle_plans_on_each_rows_drawn_plant(env_id):
    """With ``plant_randomization`` (here drawing the plant of a model-mismatch variant's
    factors):
    a rollout of the oracle's plan from a copy of the row's state, on its planning core, is
    the episode the env then runs, bit for bit; and its return is the one on an env made
    with the drawn parameters."""
    factors = next(iter(perturb.VARIANT_FACTORS[env_id].values()))
    dt = plants.plant_class(env_id).Params().dt_s
    budget = Budget(horizon_s=60 * dt, tail_s=0.0, knot_s=10 * dt, replan_s=5 * dt, samples=4,
                    iterations=2)  # fmt: skip
    env = gym.make(env_id, scenario=STEP,
                   plant_randomization={g: (k, k) for g, k in factors.items()})  # fmt: skip
    made = gym.make(env_id, scenario=STEP, params=perturb.scaled(env_id, {}, factors))
    u = env.unwrapped
    oracle = Oracle(env, budget)
    obs, _ = env.reset(seed=0)
    assert u.episode_plant.params == made.unwrapped.plant.params != u.plant.params
    rollouts, executed, done = [], [], False
    while not done:
        action, _ = oracle.predict(obs)
        if oracle.start[0] == u.core.counter[0]:  # a new plan: roll it out from a copy
            core = oracle._planner()
            copy_rows(u.core, np.zeros(core.B, dtype=np.int64), core, np.arange(core.B))
            roll = []
            for cmd in oracle.plan[0][: oracle.R]:
                core.step(np.tile((2.0 * cmd - 1.0).astype(np.float32), (core.B, 1)))
                roll.append((core.obs[0].copy(), core.out[0, 0]))
            rollouts.append((len(executed), roll))
        obs, r, term, trunc, _ = env.step(action)
        executed.append((obs, r))
        done = term or trunc
    assert len(rollouts) > 10
    for t0, roll in rollouts:
        for (o, r), (eo, er) in zip(roll, executed[t0:], strict=False):
            np.testing.assert_array_equal(o, eo)
            assert r == er
    drawn = sum(r for _, r in executed)
    alone = run_episode(made, Oracle(made, budget), 0)["metrics"]["return"]
    assert drawn == alone  # summed in the same order: bit for bit


def test_copy_rows_refuses_a_plain_core_for_drawn_plants():
    """A planner of its own (a plain Core of the env's plant) cannot silently plan a
    plant_randomization row on the env's nominal plant; planning_core gives it the row's."""
    from steamtemp_gym.envs.core import Core
    from steamtemp_gym.envs.snapshot import planning_core
    from steamtemp_gym.rewards import RewardConfig

    env = gym.make("steamtemp/Cascade300MW-v0", scenario=STEP, plant_randomization=True)
    env.reset(seed=1)
    src = env.unwrapped.core
    plain = Core(src.plant, 2, RewardConfig())
    with pytest.raises(ValueError, match="planning_core"):
        copy_rows(src, np.zeros(2, dtype=np.int64), plain, np.arange(2))
    assert not plain.X.any()  # nothing copied
    planner = planning_core(src, 2)
    copy_rows(src, np.zeros(2, dtype=np.int64), planner, np.arange(2))
    assert all(planner.row_plant(b) is env.unwrapped.episode_plant for b in range(2))
