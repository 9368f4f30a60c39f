"""Registry-wide tests: every registered id, no per-plant code (as Gymnasium's test_envs.py)."""

from __future__ import annotations

import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import baselines
import steamtemp_gym
from steamtemp_gym import scenarios
from steamtemp_gym.scenarios import Scenario

IDS = steamtemp_gym.ENV_IDS
INFO_KEYS = ("outlet_temp_C", "setpoint_C", "load", "spray_valve", "spray_flow_kg_s")


def short_scenario(env_id: str, steps: int = 12) -> Scenario:
    dt = gym.make(env_id).unwrapped.plant.dt_s
    return Scenario(
        name="short",
        duration_s=steps * dt,
        load=((0.0, 0.9), (steps * dt, 0.85)),
        heat_absorption_bias=((0.0, 0.0), (3 * dt, 0.03)),
        noise_std_C=0.5,
    )


@pytest.mark.parametrize("env_id", IDS)
def test_gymnasium_check_env(env_id):
    env = gym.make(env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(env.unwrapped, skip_render_check=True)


@pytest.mark.parametrize("env_id", IDS)
def test_sb3_check_env(env_id):
    from stable_baselines3.common.env_checker import check_env as sb3_check

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sb3_check(gym.make(env_id).unwrapped, warn=False)


@pytest.mark.parametrize("env_id", IDS)
def test_reset_and_step_info(env_id):
    env = gym.make(env_id, scenario="setpoint_step")
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    for k in INFO_KEYS:
        assert k in info, k
    # starts in steady state at the setpoint, valve inside its range
    assert info["outlet_temp_C"] == pytest.approx(info["setpoint_C"], abs=0.05)
    assert 0.0 < np.min(info["spray_valve"]) and np.max(info["spray_valve"]) < 1.0
    obs2, r, term, trunc, info2 = env.step(env.action_space.sample())
    assert np.isfinite(r) and not term and not trunc
    assert set(info2) == set(info)
    # the observation describes itself
    assert len(env.unwrapped.signals.observation) == obs.shape[0]
    decoded = env.unwrapped.signals.decode(obs)
    assert decoded["setpoint_C"] == pytest.approx(info["setpoint_C"])


@pytest.mark.parametrize("env_id", IDS)
def test_same_seed_same_trajectory(env_id):
    def run(seed):
        env = gym.make(env_id, scenario="random")
        obs, _ = env.reset(seed=seed)
        env.action_space.seed(seed)
        out = [obs]
        for _ in range(60):
            obs, r, term, trunc, info = env.step(env.action_space.sample())
            out.append(np.append(obs, [r, info["outlet_temp_C"]]))
            if term or trunc:
                obs, _ = env.reset()
        return np.concatenate(out)

    a, b, c = run(3), run(3), run(4)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.parametrize("env_id", IDS)
def test_vector_env_matches_single_env(env_id):
    n, seed, steps = 3, 11, 30
    sc = short_scenario(env_id)
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", scenario=sc)
    envs = [gym.make(env_id, scenario=sc) for _ in range(n)]
    vobs, _ = venv.reset(seed=seed)
    sobs = [e.reset(seed=seed + i)[0] for i, e in enumerate(envs)]
    np.testing.assert_array_equal(vobs, np.stack(sobs))
    rng = np.random.default_rng(0)
    done = [False] * n
    endings = 0
    for _ in range(steps):
        actions = rng.uniform(-1, 1, size=venv.action_space.shape).astype(np.float32)
        vobs, vr, vterm, vtrunc, vinfo = venv.step(actions)
        for i, e in enumerate(envs):
            if done[i]:  # NEXT_STEP autoreset: the vector env resets this step
                o, _ = e.reset()
                r, term, trunc = 0.0, False, False
            else:
                o, r, term, trunc, info = e.step(actions[i])
                assert set(info) == {k for k in vinfo if not k.startswith("_")}
                for k, v in info.items():
                    np.testing.assert_array_equal(vinfo[k][i], v)
            np.testing.assert_array_equal(vobs[i], o)
            assert vr[i] == r and vterm[i] == term and vtrunc[i] == trunc
            done[i] = term or trunc
            endings += done[i]
    assert endings >= n, "every sub-env should have ended (and autoreset) at least once"


@pytest.mark.parametrize("env_id", IDS)
def test_pickle_roundtrip_continues_identically(env_id):
    env = gym.make(env_id, scenario="random")
    env.reset(seed=5)
    for _ in range(5):
        env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    clone = pickle.loads(pickle.dumps(env))
    a = np.full(env.action_space.shape, 0.3, dtype=np.float32)
    for _ in range(5):
        o1, r1, *_ = env.step(a)
        o2, r2, *_ = clone.step(a)
        np.testing.assert_array_equal(o1, o2)
        assert r1 == r2


@pytest.mark.parametrize("env_id", IDS)
def test_every_named_scenario_runs_to_its_end(env_id):
    for name in scenarios.names(env_id):
        if name == scenarios.RANDOM:
            continue
        env = gym.make(env_id, scenario=name)
        obs, info = env.reset(seed=0)
        policy = baselines.make("cascade_pi", env)
        steps = 0
        while True:
            obs, r, term, trunc, info = env.step(policy.predict(obs)[0])
            steps += 1
            assert np.all(np.isfinite(obs)) and np.isfinite(r)
            assert not term, f"{name}: tripped at t = {info['time_s']} s"
            if trunc:
                break
        assert info["time_s"] == pytest.approx(env.unwrapped.scenario.duration_s, abs=1e-6)


@pytest.mark.parametrize("env_id", IDS)
def test_render_rgb_array(env_id):
    env = gym.make(env_id, scenario="setpoint_step", render_mode="rgb_array")
    env.reset(seed=0)
    for _ in range(5):
        env.step(env.action_space.sample())
    img = env.render()
    assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3
    assert img.std() > 5  # something was drawn


# ----------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("env_id", IDS)
def test_bad_actions_raise_and_lose_nothing(env_id):
    env = gym.make(env_id, scenario="setpoint_step")
    env.reset(seed=0)
    before = env.unwrapped.core.X.copy()
    shape = env.action_space.shape
    for bad, match in (
        (np.full(shape, np.nan), "NaN"),
        (np.full(shape, np.inf), "NaN or infinite"),
        (np.zeros((shape[0] + 1,)), "shape"),
        (np.zeros((2, 2, 2)), "shape"),
    ):
        with pytest.raises(ValueError, match=match):
            env.unwrapped.step(bad)
    np.testing.assert_array_equal(env.unwrapped.core.X, before)
    env.step(np.zeros(shape, dtype=np.float32))  # still usable


def test_unknown_id_scenario_option_raise():
    env_id = IDS[0]
    with pytest.raises(gym.error.Error):
        gym.make("steamtemp/NoSuchPlant-v0")
    from steamtemp_gym import plants

    with pytest.raises(ValueError, match="valid ids"):
        plants.make("steamtemp/NoSuchPlant-v0")
    with pytest.raises(ValueError, match="valid names"):
        gym.make(env_id, scenario="no_such_scenario")
    with pytest.raises(ValueError, match="valid options"):
        gym.make(env_id, no_such_option=1)
    with pytest.raises(ValueError, match="valid options"):
        gym.make(env_id, reward={"no_such_weight": 1.0})
    with pytest.raises(ValueError, match="valid parameters"):
        gym.make(env_id, params={"no_such_param": 1.0})
    from steamtemp_gym.envs import SteamTempEnv

    with pytest.raises(ValueError, match="render_mode"):
        SteamTempEnv(env_id, render_mode="bogus")


@pytest.mark.parametrize("env_id", IDS)
def test_impossible_parameters_raise(env_id):
    import dataclasses

    plant_cls = gym.make(env_id).unwrapped.plant.__class__
    for f in dataclasses.fields(plant_cls.Params):
        v = getattr(plant_cls.Params(), f.name)
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            with pytest.raises(ValueError, match=f.name):
                gym.make(env_id, params={f.name: float("nan")})
    # a negative value of a positive quantity (the first positive float field)
    positive = [f.name for f in dataclasses.fields(plant_cls.Params)
                if isinstance(getattr(plant_cls.Params(), f.name), float)
                and getattr(plant_cls.Params(), f.name) > 0]  # fmt: skip
    with pytest.raises(ValueError):
        gym.make(env_id, params={positive[0]: -1.0})


def test_scenario_yaml(tmp_path):
    env_id = IDS[0]
    good = tmp_path / "good.yaml"
    good.write_text(
        "name: my_ramp\nduration_s: 60\nload: [[0, 1.0], [30, 0.9]]\n"
        "setpoint_offset_C: [[0, 0], [10, 5]]\nnoise_std_C: 0.2\n"
    )
    env = gym.make(env_id, scenario=str(good))
    _, info = env.reset(seed=0)
    assert env.unwrapped.scenario.name == "my_ramp"
    for _ in range(10):
        *_, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    assert info["setpoint_C"] == pytest.approx(env.unwrapped.plant.setpoint_C + 5.0)
    cases = {
        "malformed.yaml": ("name: x\nduration_s: [60\n", "malformed"),
        "unknown.yaml": ("name: x\nduration_s: 60\nload: 1.0\nwind: 3\n", "unknown scenario field"),
        "missing.yaml": ("name: x\nload: 1.0\n", "duration_s"),
        "badload.yaml": ("name: x\nduration_s: 60\nload: [[0, 5.0]]\n", "physical range"),
        "badtime.yaml": (
            "name: x\nduration_s: 60\nload: [[10, 1.0], [5, 0.9]]\n",
            "non-decreasing",
        ),
        "notmap.yaml": ("- 1\n- 2\n", "mapping"),
    }
    for fname, (text, match) in cases.items():
        p = tmp_path / fname
        p.write_text(text)
        with pytest.raises(ValueError, match=match):
            gym.make(env_id, scenario=str(p))
    with pytest.raises(ValueError, match="cannot read"):
        gym.make(env_id, scenario=str(tmp_path / "absent.yaml"))


@pytest.mark.parametrize("env_id", IDS)
def test_long_random_run_stays_physical(env_id):
    """Random actions under random scenarios, batched: never NaN, every state physical."""
    n, steps = 32, 1500
    venv = gym.make_vec(
        env_id, num_envs=n, vectorization_mode="vector_entry_point", scenario="random"
    )
    venv.reset(seed=123)
    rng = np.random.default_rng(1)
    for k in range(steps):
        # random walk actions with occasional bang-bang
        a = rng.uniform(-1, 1, size=venv.action_space.shape) if k % 50 < 25 else np.sign(
            rng.uniform(-1, 1, size=venv.action_space.shape))  # fmt: skip
        obs, r, term, trunc, info = venv.step(a.astype(np.float32))
        X = venv.unwrapped.core.X if hasattr(venv, "unwrapped") else venv.core.X
        assert np.all(np.isfinite(X)) and np.all(np.isfinite(obs)) and np.all(np.isfinite(r))
        assert np.all(np.abs(obs) <= 5.0)
        assert np.all((info["outlet_temp_C"] > 100.0) & (info["outlet_temp_C"] < 900.0))
        assert np.all(
            (np.asarray(info["spray_valve"]) >= 0) & (np.asarray(info["spray_valve"]) <= 1)
        )
        assert np.all(info["spray_flow_kg_s"] >= 0.0)


@pytest.mark.parametrize("env_id", IDS)
def test_holding_the_setpoint_with_design_spray_scores_about_zero(env_id):
    """The reward's spray term charges only spray above the plant's design spray."""
    env = gym.make(env_id, scenario=Scenario(name="rated", duration_s=200.0, load=1.0),
                   params={"omega_halfwidth_K": 0.0, "omega2_scale_kg_s": 0.0}
                   if "Cascade" in env_id else {})  # fmt: skip
    plant = env.unwrapped.plant
    assert plant.design_spray in plant.index, "every plant declares its design spray output"
    _, info = env.reset(seed=0)
    hold = (2.0 * np.atleast_1d(info["spray_valve"]) - 1.0).astype(np.float32)
    rewards = [env.step(hold)[1] for _ in range(20)]
    assert -0.05 < np.mean(rewards) <= 0.0
    more = np.clip(hold + 0.4, -1, 1)
    *_, info = env.step(more)
    r_more = np.mean([env.step(more)[1] for _ in range(5)])
    core = env.unwrapped.core
    spray = info["spray_flow_kg_s"]
    assert spray > core.Z[0, plant.index[plant.design_spray]]
    assert r_more < np.mean(rewards)  # more spray than designed costs
