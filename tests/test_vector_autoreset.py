"""The native vector env's autoreset modes and partial resets against Gymnasium's own
``SyncVectorEnv`` over single envs with the same seeds: bit for bit, across episode ends
(trips at staggered times and scenario ends)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import steamtemp_gym
from steamtemp_gym.envs.vector_env import AUTORESET_MODES, SteamTempVectorEnv
from steamtemp_gym.scenarios import Scenario

ENV_ID = "steamtemp/SupercriticalFSH-v0"  # 2 s control interval: a closed valve trips in ~60 steps
N = 3
STEPS = 260
SHORT = Scenario(name="short_for_autoreset_test", duration_s=150.0)


def _pair(mode: AutoresetMode, scenario, env_id: str = ENV_ID):
    native = gym.make_vec(
        env_id,
        num_envs=N,
        vectorization_mode="vector_entry_point",
        autoreset_mode=mode,
        scenario=scenario,
    )
    sync = SyncVectorEnv([lambda: gym.make(env_id, scenario=scenario)] * N, autoreset_mode=mode)
    return native, sync


def _actions(k: int, n_u: int) -> np.ndarray:
    """Sub-env i closes its valves from step 40 i on (a trip ~60 steps later), else holds
    mid-stroke with a little seeded dither: episodes end at different steps."""
    rng = np.random.default_rng(k)
    a = 0.1 * rng.standard_normal((N, n_u)).astype(np.float32)
    closing = np.arange(N) * 40 <= k % 200
    a[closing] = -1.0
    return a


def _same_info(native: dict, ref: dict) -> None:
    """Every key Gymnasium reports is reported by the native env, equal where masked."""
    for key, value in ref.items():
        if key.startswith("_") or key in ("final_obs", "final_info"):
            continue
        mask = ref["_" + key]
        np.testing.assert_array_equal(native["_" + key], mask, err_msg=key)
        got, want = np.asarray(native[key])[mask], np.asarray(value)[mask]
        if want.dtype == object:
            got, want = got.astype(str), want.astype(str)
        np.testing.assert_array_equal(got, want, err_msg=key)


def _same_final(native: dict, ref: dict) -> None:
    for key in ("final_obs", "final_info"):
        assert (key in native) == (key in ref), key
    if "final_obs" not in ref:
        return
    np.testing.assert_array_equal(native["_final_obs"], ref["_final_obs"])
    for b in np.flatnonzero(ref["_final_obs"]):
        np.testing.assert_array_equal(native["final_obs"][b], ref["final_obs"][b])
    _same_info(native["final_info"], ref["final_info"])


def test_autoreset_modes_constant():
    assert set(AUTORESET_MODES) == set(AutoresetMode)
    assert all(isinstance(m, AutoresetMode) for m in AUTORESET_MODES)


@pytest.mark.parametrize("mode", AUTORESET_MODES, ids=lambda m: m.value)
@pytest.mark.parametrize("scenario", ["random", SHORT], ids=["random", "short"])
def test_matches_sync_vector_env(mode, scenario):
    native, sync = _pair(mode, scenario)
    assert native.metadata["autoreset_mode"] is mode
    assert native.unwrapped.autoreset_mode is mode
    o1, i1 = native.reset(seed=11)
    o2, i2 = sync.reset(seed=11)
    np.testing.assert_array_equal(o1, o2)
    _same_info(i1, i2)
    ends = 0
    for k in range(STEPS):
        a = _actions(k, native.single_action_space.shape[0])
        r1, r2 = native.step(a), sync.step(a)
        for x, y in zip(r1[:4], r2[:4], strict=True):
            np.testing.assert_array_equal(x, y, err_msg=f"step {k}")
        _same_info(r1[4], r2[4])
        _same_final(r1[4], r2[4])
        done = r2[2] | r2[3]
        ends += int(done.sum())
        if mode == AutoresetMode.DISABLED and done.any():
            o1, i1 = native.reset(options={"reset_mask": done})
            o2, i2 = sync.reset(options={"reset_mask": done})
            np.testing.assert_array_equal(o1[done], o2[done])
            _same_info(i1, i2)
    assert ends >= N  # the comparison crossed episode ends of every kind of sub-env


def test_reset_mask_partial_reset_matches_sync():
    native, sync = _pair(AutoresetMode.NEXT_STEP, "random")
    native.reset(seed=3)
    sync.reset(seed=3)
    for k in range(30):
        a = _actions(k, 1)
        native.step(a)
        sync.step(a)
    mask = np.array([False, True, False])
    o1, i1 = native.reset(seed=[None, 99, None], options={"reset_mask": mask})
    o2, i2 = sync.reset(seed=[None, 99, None], options={"reset_mask": mask})
    np.testing.assert_array_equal(o1, o2)
    _same_info(i1, i2)
    for k in range(30):
        a = _actions(k, 1)
        for x, y in zip(native.step(a)[:4], sync.step(a)[:4], strict=True):
            np.testing.assert_array_equal(x, y)


def test_disabled_refuses_to_step_an_ended_sub_env():
    env = SteamTempVectorEnv(ENV_ID, num_envs=2, autoreset_mode="Disabled", scenario=SHORT)
    env.reset(seed=0)
    done = np.zeros(2, dtype=bool)
    while not done.any():
        _, _, term, trunc, _ = env.step(np.zeros((2, 1), np.float32))
        done = term | trunc
    with pytest.raises(RuntimeError, match="reset_mask"):
        env.step(np.zeros((2, 1), np.float32))
    env.reset(options={"reset_mask": done})
    env.step(np.zeros((2, 1), np.float32))


@pytest.mark.parametrize("bad", ["next_step", 1, None, "SAME"])
def test_unknown_autoreset_mode_names_the_valid_ones(bad):
    with pytest.raises(ValueError, match="NextStep"):
        SteamTempVectorEnv(ENV_ID, num_envs=1, autoreset_mode=bad)


def test_registered_ids_take_the_mode():
    for env_id in steamtemp_gym.ENV_IDS[:1]:
        env = gym.make_vec(
            env_id,
            num_envs=2,
            vectorization_mode="vector_entry_point",
            autoreset_mode=AutoresetMode.SAME_STEP,
        )
        assert env.metadata["autoreset_mode"] is AutoresetMode.SAME_STEP
