"""agents.vec_env.NativeVecEnv against SB3's DummyVecEnv over the same seeds: the same
transitions (observations, float32 rewards, dones, info dicts with terminal_observation
and TimeLimit.truncated, reset_infos), across trips and scenario ends."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

from agents.vec_env import NativeVecEnv
from steamtemp_gym.scenarios import Scenario

ENV_ID = "steamtemp/SupercriticalFSH-v0"
N = 3
SHORT = Scenario(name="short_for_vec_env_test", duration_s=150.0)


def _actions(k: int, n_u: int) -> np.ndarray:
    """Sub-env i closes its valve from step 40 i on (a trip ~60 steps later)."""
    rng = np.random.default_rng(k)
    a = 0.1 * rng.standard_normal((N, n_u)).astype(np.float32)
    a[np.arange(N) * 40 <= k % 200] = -1.0
    return a


def _same_infos(got: list[dict], want: list[dict]) -> None:
    assert len(got) == len(want)
    for g, w in zip(got, want, strict=True):
        assert sorted(g) == sorted(w)
        for k in w:
            np.testing.assert_array_equal(g[k], w[k], err_msg=k)
            assert type(g[k]) is type(w[k]), k


@pytest.mark.parametrize("scenario", ["random", SHORT], ids=["random", "short"])
def test_transitions_match_dummy_vec_env(scenario):
    native = NativeVecEnv(ENV_ID, N, scenario=scenario)
    dummy = DummyVecEnv([lambda: gym.make(ENV_ID, scenario=scenario)] * N)
    for venv in (native, dummy):
        venv.seed(11)
    np.testing.assert_array_equal(native.reset(), dummy.reset())
    _same_infos(native.reset_infos, dummy.reset_infos)
    ends = 0
    for k in range(260):
        a = _actions(k, 1)
        o1, r1, d1, i1 = native.step(a)
        o2, r2, d2, i2 = dummy.step(a)
        np.testing.assert_array_equal(o1, o2, err_msg=f"step {k}")
        assert r1.dtype == r2.dtype
        np.testing.assert_array_equal(r1, r2)
        np.testing.assert_array_equal(d1, d2)
        _same_infos(i1, i2)
        if d2.any():
            _same_infos(native.reset_infos, dummy.reset_infos)
        ends += int(d2.sum())
    assert ends >= N


def test_seed_applies_to_the_next_reset_only():
    env = NativeVecEnv(ENV_ID, 2)
    env.seed(3)
    a = env.reset()
    env.seed(3)
    np.testing.assert_array_equal(env.reset(), a)
    assert not np.array_equal(env.reset(), a)  # unseeded: the generators move on


def test_attributes_and_methods_of_sub_envs():
    env = NativeVecEnv(ENV_ID, 2)
    env.reset()
    assert env.get_attr("render_mode") == [None, None]
    assert [s.name for s in env.get_attr("scenario")] == ["random", "random"]
    assert env.get_attr("scenario", 1)[0] is env.venv.core.scenario[1]
    assert env.get_attr("plant")[0] is env.venv.plant
    env.step(np.zeros((2, 1), np.float32))
    assert env.env_method("current_info", indices=[1])[0]["time_s"] == 2.0
    assert env.env_is_wrapped(gym.Wrapper) == [False, False]
    with pytest.raises(ValueError, match="shared"):
        env.set_attr("plant", None, indices=[0])


def test_sb3_wrappers_run_on_it():
    env = VecNormalize(NativeVecEnv(ENV_ID, 2))
    env.reset()
    for _ in range(5):
        obs, rew, done, _ = env.step(np.zeros((2, 1), np.float32))
    assert obs.shape == (2, env.observation_space.shape[0]) and np.isfinite(obs).all()


def test_unknown_env_id():
    with pytest.raises(ValueError, match="unknown env id"):
        NativeVecEnv("steamtemp/Nope-v0", 2)
