"""The clairvoyant optimum (agents/optimum): its model of the episode is the env's own, its
gradient is right, its search never returns less than its best start, and the oracle takes
a stored optimum only where it replays (agents/optima.py)."""

from __future__ import annotations

import dataclasses
import json

import gymnasium as gym
import numpy as np
import pytest

import steamtemp_gym
from agents import optima, optimum
from agents.evaluation import run_episode
from agents.optimum import problem
from agents.oracle import Oracle, Replay
from steamtemp_gym.envs.snapshot import env_core
from steamtemp_gym.scenarios import Scenario

#: A short episode with a load ramp, a heat-absorption step and the coloured disturbance.
SHORT = Scenario(
    name="optimum_check",
    duration_s=300.0,
    load=((0.0, 1.0), (30.0, 1.0), (150.0, 0.9)),
    heat_absorption_bias=((0.0, 0.0), (200.0, 0.0), (220.0, 0.03)),
    noise_std_C=0.25,
    heat_absorption_noise_std=0.02,
    heat_absorption_noise_tau_s=300.0,
)


def _episode(env_id: str, seed: int = 0, scenario: Scenario = SHORT):
    env = gym.make(env_id, scenario=scenario)
    env.reset(seed=seed)
    return env, optimum.episode(env_core(env))


def _wiggle(ep, seed: int = 1) -> np.ndarray:
    """Commands that move: the held ones plus a smooth random excursion, within bounds."""
    rng = np.random.default_rng(seed)
    t = np.arange(ep.T)[:, None]
    phase = rng.uniform(0, 2 * np.pi, ep.plant.n_u)
    return np.clip(ep.u_init + 0.08 * np.sin(2 * np.pi * t / 60.0 + phase), 0.0, 1.0)


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_the_optimizers_model_is_the_envs_own_step_and_reward(env_id):
    """The bare simulation of the plant's kernel gives the env's outputs bit for bit, and the
    smoothed reward at zero width the env's reward of every step (to rounding of the sum)."""
    env, ep = _episode(env_id)
    U = _wiggle(ep)
    core = env_core(env)
    Z, rewards = [], []
    for u in U:
        env.step(optimum.to_actions(u))
        Z.append(core.Z[0].copy())
        rewards.append(float(core.reward[0]))
    cmds = 0.5 * (optimum.to_actions(U).astype(np.float64) + 1.0)  # as the env takes them
    _, Zs = problem.simulate(ep, cmds)
    np.testing.assert_array_equal(Zs, np.array(Z))
    Uprev = np.vstack([ep.u_init[None], cmds[:-1]])
    r = problem.smooth_reward(Zs, cmds, Uprev, ep.sp, ep.layout, (0.0, 0.0, 0.0))[0]
    np.testing.assert_allclose(r, rewards, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_the_adjoint_gradient_matches_finite_differences_of_the_return(env_id):
    """Directional derivatives of the smoothed return: the adjoint gradient (forward
    differences of the kernel, and central ones) against central differences of whole
    simulated episodes, to 1e-4 relative."""
    _, ep = _episode(env_id)
    U = _wiggle(ep)
    eps = problem.smoothing(0.1)
    rng = np.random.default_rng(2)
    for central in (False, True):
        _, g = problem.value_and_gradient(ep, U, eps, central=central)
        for _ in range(2):
            d = rng.standard_normal(U.shape) * 0.01
            h = 1e-4

            def J(V):
                return problem.returns(ep, V, problem.simulate(ep, V)[1], eps)[0]

            fd = (J(U + h * d) - J(U - h * d)) / (2 * h)
            assert abs(fd - float((g * d).sum())) <= 1e-4 * abs(fd) + 1e-9, (central, fd)


def test_the_search_never_returns_less_than_its_best_start_and_certifies_itself():
    """On a short Benson episode: from the held commands and a worse start, the optimum's
    exact return is above both, its certificate is computed from two paths, and the
    independent finite-difference refinement adds less than 1 % of the headroom to it
    (from the held commands it finds a good part of the way)."""
    env_id = "steamtemp/BensonSubcritical-v0"
    _, ep = _episode(env_id, seed=3)
    held = optimum.to_actions(np.repeat(ep.u_init[None], ep.T, axis=0))
    worse = optimum.to_actions(_wiggle(ep, 5))
    starts = {"held": held, "worse": worse}
    returns = {k: optimum.exact_return(ep, a)[0] for k, a in starts.items()}
    out = optimum.solve(ep, starts, returns, zero=min(returns.values()) - 1.0)
    assert out["return"] > max(returns.values())
    assert out["return"] == optimum.exact_return(ep, out["actions"])[0]
    cert = out["certificate"]
    assert {"step_gain", "last_refinement", "starts_agree", "kkt_residual"} <= set(cert)
    assert [p["start"] for p in out["paths"]] == ["held", "worse"]
    gain, _ = optimum.independent_check(ep, out["actions"], knots_s=(60.0, 20.0), iterations=2)
    assert gain <= 0.01 * cert["headroom"], (gain, cert)
    # the check can fail: from the held commands it finds much of the headroom
    power, _ = optimum.independent_check(ep, held, knots_s=(60.0, 20.0), iterations=2)
    assert power > 0.05 * (out["return"] - returns["held"]), power


def test_the_oracle_takes_a_stored_optimum_only_where_it_replays(tmp_path, capsys):
    """The ``optimum`` engine solves an episode it has no stored optimum for; stored, the
    same episode is replayed from the store (same return, no solve); a stored return that
    the replay does not give is refused, said on stderr, and the episode solved anew."""
    env_id = "steamtemp/Cascade300MW-v0"
    sc = dataclasses.replace(SHORT, name="optimum_store_check", duration_s=120.0)
    env = gym.make(env_id, scenario=sc)
    solved = Oracle(env, engine="optimum", store=tmp_path)
    first = run_episode(env, solved, 7)["metrics"]["return"]
    assert solved.committed[0].source == "optimum"
    assert "solving the clairvoyant optimum" in capsys.readouterr().err
    a = solved.committed[0].actions.astype(np.float32)
    record = {
        "env": env_id,
        "scenario": sc.name,
        "seed": 7,
        "noise_key": int(solved.committed[0].key),
        "scenario_digest": optima.scenario_digest(sc),
        "return": first,
        "actions_file": optima.file_name(env_id, sc.name, 7),
        "actions_sha": optima.actions_digest(a),
    }
    optima.write(tmp_path, json.dumps(record), record["actions_file"], a)
    stored = Oracle(env, engine="optimum", store=tmp_path)
    assert run_episode(env, stored, 7)["metrics"]["return"] == first
    assert stored.committed[0].source == "stored optimum"
    assert run_episode(env, Replay(a), 7)["metrics"]["return"] == first
    record["return"] = first + 1e-6 * max(1.0, abs(first))
    optima.write(tmp_path, json.dumps(record), record["actions_file"], a)
    refused = Oracle(env, engine="optimum", store=tmp_path)
    assert run_episode(env, refused, 7)["metrics"]["return"] == first
    assert refused.committed[0].source == "optimum"
    assert "replays to" in capsys.readouterr().err


def test_an_oracle_engine_that_does_not_exist_is_refused():
    env = gym.make("steamtemp/Cascade300MW-v0", scenario=SHORT)
    with pytest.raises(ValueError, match="engine must be one of"):
        Oracle(env, engine="mpc")


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_every_stored_optimum_of_a_plant_replays_to_its_return(env_id):
    """Each stored optimum's actions file is the one its record names, and its first
    seed's episodes replay in a fresh env to the stored return bit for bit."""
    records = [r for r in optima.load().values() if r["env"] == env_id]
    if not records:
        pytest.skip(f"no stored optima of {env_id}: python -m agents.leaderboard.optima")
    from steamtemp_gym import scenarios

    for r in records:
        a = optima.actions(r)
        assert a is not None, r["actions_file"]
        if r["seed"] != min(x["seed"] for x in records):
            continue
        env = gym.make(env_id, scenario=scenarios.resolve(r["scenario"], env_id))
        assert run_episode(env, Replay(a), r["seed"])["metrics"]["return"] == r["return"]


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["--envs", "NoSuchPlant-v0"], "unknown env id"),
        (["--jobs", "0"], "--jobs: must be >= 1"),
        (["--check"], "--check: only with --certify"),
        (["--certify", "--again"], "--again: only with --check"),
        (["--seeds", "-1"], "--seeds"),
    ],
)
def test_the_store_command_refuses_bad_flags_before_it_solves(argv, words, tmp_path, capsys):
    from agents.leaderboard import optima as command

    with pytest.raises(SystemExit) as exc:
        command.main([*argv, "--store", str(tmp_path / "store")])
    assert exc.value.code == 2 and words in capsys.readouterr().err
    assert not (tmp_path / "store").exists()
