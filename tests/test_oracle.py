"""The oracle's receding-horizon CEM engine (agents/oracle.py, ``engine="cem"``): a lower
bound of the optimum that is already an upper bound on every controller, deterministic,
the same alone and batched; its budget is checked. The ``optimum`` engine starts from its
sequences (tests/test_optimum.py)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from tunings import missing

import agents
import baselines
import steamtemp_gym
from agents import specs
from agents.cem import Budget
from agents.evaluation import run_batch, run_episode
from agents.oracle import INCUMBENTS
from agents.oracle import Oracle as _Oracle
from steamtemp_gym import plants
from steamtemp_gym.envs.snapshot import copy_rows
from steamtemp_gym.plants import perturb
from steamtemp_gym.scenarios import Scenario


def Oracle(env, *args, **kw):  # noqa: N802 - the oracle with its CEM engine
    return _Oracle(env, *args, engine="cem", **kw)


#: A short scenario with the disturbances of the named ones: a load ramp at 5 %/min, then a
#: heat-absorption step, with sensor noise and the coloured heat-absorption disturbance.
SHORT = Scenario(
    name="oracle_check",
    duration_s=900.0,
    load=((0.0, 1.0), (120.0, 1.0), (300.0, 0.85)),
    heat_absorption_bias=((0.0, 0.0), (500.0, 0.0), (560.0, 0.04)),
    noise_std_C=0.25,
    heat_absorption_noise_std=0.02,
    heat_absorption_noise_tau_s=300.0,
)


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
    returns = {
        p: run_episode(env, specs.parse(p, references=True).make(env_id, env), 0)["metrics"][
            "return"
        ]
        for p in _contenders(env_id)
    }
    best = max(returns, key=returns.get)
    assert oracle["return"] >= returns[best], (oracle["return"], best, returns)


def test_the_oracle_is_deterministic_and_the_same_alone_and_batched():
    env_id = "steamtemp/Cascade300MW-v0"
    sc = Scenario(
        name="tiny",
        duration_s=240.0,
        load=((0.0, 1.0), (60.0, 1.0), (180.0, 0.9)),
        noise_std_C=0.25,
        heat_absorption_noise_std=0.02,
    )
    budget = Budget(horizon_s=120.0, knot_s=20.0, replan_s=10.0, samples=6, iterations=2, elites=2)
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


@pytest.mark.parametrize(
    ("field", "value", "words"),
    [
        ("samples", 0, "samples"),
        ("iterations", 1.5, "iterations"),
        ("horizon_s", -1.0, "horizon"),
        ("elites", 99, "elites"),
        ("knot_s", 1e6, "knot_s"),
        ("sigma0", float("nan"), "sigma0"),
    ],
)
def test_bad_budgets_are_refused(field, value, words):
    with pytest.raises(ValueError, match=words):
        Budget(**{field: value})


def test_the_oracle_refuses_other_envs_and_batch_sizes():
    with pytest.raises(ValueError, match="steamtemp_gym env"):
        Oracle(gym.make("CartPole-v1"))
    venv = gym.make_vec(
        "steamtemp/Cascade300MW-v0",
        num_envs=2,
        scenario="setpoint_step",
        vectorization_mode="vector_entry_point",
    )
    obs, _ = venv.reset(seed=0)
    with pytest.raises(ValueError, match="2 row"):
        Oracle(venv).predict(obs[:1])


#: A setpoint step and a load change, short: what the oracle's model must get right.
STEP = Scenario(
    name="oracle_step",
    duration_s=600.0,
    load=((0.0, 1.0), (300.0, 1.0), (420.0, 0.9)),
    setpoint_offset_C=((0.0, 0.0), (60.0, 0.0), (60.0, 10.0)),
    noise_std_C=0.25,
    heat_absorption_noise_std=0.02,
)


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_the_oracle_plans_on_each_rows_drawn_plant(env_id):
    """With ``plant_randomization`` (here drawing the plant of a model-mismatch variant's
    factors): the episode the env runs is the rollout the oracle committed to on its copy
    of the row, bit for bit (observations and rewards); and its return is the one on an env
    made with the drawn parameters. (The CEM alone: the incumbents are commissioned on
    the env's nominal plant, which differs between the two envs.)"""
    factors = next(iter(perturb.variant_factors(env_id).values()), perturb.corners(env_id)[0])
    if not factors:
        pytest.skip(f"{env_id} declares no perturbation_groups (steamtemp_gym/plants/perturb.py)")
    dt = plants.plant_class(env_id).Params().dt_s
    budget = Budget(
        horizon_s=60 * dt, tail_s=0.0, knot_s=10 * dt, replan_s=5 * dt, samples=4, iterations=2
    )
    env = gym.make(
        env_id, scenario=STEP, plant_randomization={g: (k, k) for g, k in factors.items()}
    )
    made = gym.make(env_id, scenario=STEP, params=perturb.scaled(env_id, {}, factors))
    u = env.unwrapped
    oracle = Oracle(env, budget, incumbents=())
    obs, _ = env.reset(seed=0)
    assert u.episode_plant.params == made.unwrapped.plant.params != u.plant.params
    executed, done = [], False
    while not done:
        action, _ = oracle.predict(obs)
        obs, r, term, trunc, _ = env.step(action)
        executed.append((obs, r))
        done = term or trunc
    c = oracle.committed[0]
    assert c.start == 0 and len(c.actions) == len(executed) > 100
    np.testing.assert_array_equal(np.array([o for o, _ in executed]), c.observations)
    np.testing.assert_array_equal(np.array([r for _, r in executed]), c.rewards)
    drawn = sum(r for _, r in executed)
    alone = run_episode(made, Oracle(made, budget, incumbents=()), 0)["metrics"]["return"]
    assert drawn == alone  # summed in the same order: bit for bit


#: A CEM that can hardly move the valves from where they start: the incumbents win.
WEAK = Budget(
    horizon_s=60.0, tail_s=0.0, knot_s=30.0, replan_s=60.0, samples=2, iterations=1, sigma0=0.005
)


@pytest.mark.parametrize("env_id", ["steamtemp/SupercriticalFSH-v0", "steamtemp/Cascade300MW-v0"])
def test_the_oracle_is_at_least_each_incumbent_by_construction(env_id):
    """Where its CEM loses (a budget too small to plan), the oracle's episode is the best
    incumbent's, bit for bit: its return is what ``mpc_linear`` or ``cascade_pi_ff`` returns
    on that episode alone, and at least each of theirs. With no incumbents it is the CEM's."""
    env = gym.make(env_id, scenario=SHORT)
    oracle = Oracle(env, WEAK)
    got = run_episode(env, oracle, 0)["metrics"]["return"]
    c = oracle.committed[0]
    theirs = {
        n: run_episode(env, baselines.make(n, env), 0)["metrics"]["return"] for n in INCUMBENTS
    }
    assert c.source in INCUMBENTS and c.returns["cem"] < got
    assert got == theirs[c.source] == max(theirs.values())
    cem = run_episode(env, Oracle(env, WEAK, incumbents=()), 0)["metrics"]["return"]
    assert cem == c.returns["cem"] < got


def test_the_oracle_with_incumbents_is_its_cem_where_the_cem_wins():
    """The incumbents only add candidates: where the CEM's sequence is best, the episode is
    the one the CEM alone runs, to the bit."""
    env = gym.make("steamtemp/Cascade300MW-v0", scenario=SHORT)
    budget = Budget(horizon_s=120.0, knot_s=20.0, replan_s=10.0, samples=6, iterations=2)
    oracle = Oracle(env, budget)
    got = run_episode(env, oracle, 1)
    assert oracle.committed[0].source == "cem"
    alone = run_episode(env, Oracle(env, budget, incumbents=()), 1)
    for k in got["trace"]:
        np.testing.assert_array_equal(got["trace"][k], alone["trace"][k], err_msg=k)


def test_the_oracle_commits_again_where_its_row_was_moved():
    """Restored to an earlier state of its episode, the row is not where the committed
    sequence left it: the oracle commits afresh from there, and the rest of the episode is
    the new committed rollout."""
    env = gym.make("steamtemp/Cascade300MW-v0", scenario=SHORT)
    budget = Budget(horizon_s=120.0, knot_s=20.0, replan_s=10.0, samples=4, iterations=1)
    oracle = Oracle(env, budget, incumbents=())
    obs, _ = env.reset(seed=2)
    rewards, snap = [], None
    for t in range(400):
        if t == 200:
            snap = env.unwrapped.snapshot()
        obs, r, *_ = env.step(oracle.predict(obs)[0])
        rewards.append(r)
    obs = env.unwrapped.restore(snap)
    again = []
    for _ in range(200):
        obs, r, *_ = env.step(oracle.predict(obs)[0])
        again.append(r)
    c = oracle.committed[0]
    assert c.start == 200 and c.source == "cem"
    assert again == c.rewards[:200].tolist()


def test_bad_incumbents_are_refused():
    env = gym.make("steamtemp/Cascade300MW-v0", scenario=SHORT)
    for bad in (("no_such_controller",), "mpc_linear"):
        with pytest.raises(ValueError, match="incumbents"):
            Oracle(env, incumbents=bad)


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
