"""Controller memory (agents/wrappers.py): the integral and its anti-windup, the history,
one result from every front end (Gymnasium wrapper, SB3 VecEnv wrapper, the agents'
Policy), and the residual wrapper's action."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import baselines
from agents.policy import AgentPolicy
from agents.vec_env import NativeVecEnv
from agents.wrappers import (
    STOP_MARGIN,
    ControllerMemory,
    MemoryConfig,
    MemoryState,
    VecControllerMemory,
    VecResidual,
)
from steamtemp_gym.scenarios import Scenario

ENV_ID = "steamtemp/BensonSubcritical-v0"  # two valves
SHORT = Scenario(name="short_for_memory_test", duration_s=200.0, noise_std_C=0.3)
CFG = {"integral_time_s": 30.0, "integral_limit_K": 15.0, "history": 2, "history_stride": 3}


def _obs_like(state: MemoryState, err_K: float, opening: float, n: int = 1) -> np.ndarray:
    obs = np.zeros((n, state.n_obs))
    obs[:, state.i_err] = err_K / state.e_scale
    obs[:, state.i_valve] = (opening - state.v_center) / state.v_scale
    return obs


def test_integral_integrates_clamps_and_holds_at_a_stop():
    env = gym.make(ENV_ID)
    m = MemoryState(env, MemoryConfig(integral_time_s=20.0, integral_limit_K=3.0, history=0))
    dt = env.unwrapped.plant.dt_s
    out = m(_obs_like(m, 2.0, 0.5))
    assert out[0, -1] * m.e_scale == pytest.approx(2.0 * dt / 20.0)  # e dt / Ti, in K
    for _ in range(50):
        out = m(_obs_like(m, 2.0, 0.5))
    assert out[0, -1] * m.e_scale == pytest.approx(3.0)  # clamped at the limit
    for _ in range(3):  # pulling back works below the limit
        out = m(_obs_like(m, -2.0, 0.5))
    held = out[0, -1]
    assert held * m.e_scale == pytest.approx(3.0 - 3 * 2.0 * dt / 20.0)
    out = m(_obs_like(m, 2.0, STOP_MARGIN / 2))  # every valve at a stop: may not grow
    assert out[0, -1] == held
    out = m(_obs_like(m, -2.0, 1.0))  # but may shrink
    assert out[0, -1] < held
    out = m(_obs_like(m, 2.0, 0.5), restart=np.array([True]))
    assert out[0, -1] * m.e_scale == pytest.approx(2.0 * dt / 20.0)


def test_history_holds_past_error_and_valves_oldest_last():
    env = gym.make(ENV_ID)
    m = MemoryState(env, MemoryConfig(integral=False, history=2, history_stride=3))
    assert m.n_extra == 2 * 3
    seq = [_obs_like(m, float(k), 0.1 * k) for k in range(8)]
    outs = [m(o) for o in seq]
    past = outs[7][0, m.n_obs :].reshape(2, 3)
    np.testing.assert_allclose(past[:, 0] * m.e_scale, [4.0, 1.0])  # 3 and 6 steps back
    np.testing.assert_allclose(past[0, 1:] * m.v_scale + m.v_center, [0.4, 0.4])
    # at an episode start the history is the first sample
    first = outs[0][0, m.n_obs :].reshape(2, 3)
    np.testing.assert_allclose(first[:, 0], seq[0][0, m.i_err])


def test_front_ends_agree():
    """Gymnasium wrapper, SB3 VecEnv wrapper and AgentPolicy see the same observations."""
    single = [ControllerMemory(gym.make(ENV_ID, scenario=SHORT), **CFG) for _ in range(2)]
    base = NativeVecEnv(ENV_ID, 2, scenario=SHORT)
    vec = VecControllerMemory(base, base.venv, **CFG)
    seen = []

    class Recorder:
        def predict(self, obs, deterministic=True):
            seen.append(np.array(obs))
            return np.zeros((obs.shape[0], 2), np.float32), None

    pol = AgentPolicy(Recorder(), base.venv, memory=CFG)
    vec.seed(4)
    o_vec = vec.reset()
    o_single = np.stack([e.reset(seed=4 + i)[0] for i, e in enumerate(single)])
    np.testing.assert_array_equal(o_vec, o_single)
    raw = base.venv.core.obs.copy()
    pol.predict(raw)
    np.testing.assert_array_equal(seen[-1], o_vec)
    rng = np.random.default_rng(0)
    ends = 0
    for k in range(120):  # the episodes end at step 40 and restart
        a = rng.uniform(-1, 1, (2, 2)).astype(np.float32)
        o_vec, _, done, infos = vec.step(a)
        steps = [e.step(a[i]) for i, e in enumerate(single)]
        if done.any():
            ends += 1
            for i in np.flatnonzero(done):
                np.testing.assert_array_equal(infos[i]["terminal_observation"], steps[i][0])
                steps[i] = (single[i].reset()[0],)
        np.testing.assert_array_equal(o_vec, np.stack([s[0] for s in steps]), err_msg=str(k))
        pol.predict(base.venv.core.obs.copy(), episode_start=done)
        np.testing.assert_array_equal(seen[-1], o_vec)
    assert ends == 3


def test_secondary_integral_integrates_each_scored_temperature():
    """On BoilerTurbineMIMO (main steam and reheat scored) the secondary integral adds the
    reheat error's integral (setpoint minus measurement), observed in the reheat
    measurement's scale, next to the main-steam one; without the option the memory is the
    main-steam integral alone, bit for bit."""
    env = gym.make("steamtemp/BoilerTurbineMIMO-v0")
    plant = env.unwrapped.plant
    ((name, sp),) = plant.secondary
    both = MemoryState(env, MemoryConfig(secondary_integral=True, integral_time_s=20.0, history=0))
    main = MemoryState(env, MemoryConfig(integral_time_s=20.0, history=0))
    assert both.n_extra == 2 and main.n_extra == 1
    obs = _obs_like(both, 2.0, 0.5)
    i_rh = both.i_sec[0]
    obs[:, i_rh] = (sp - 3.0 - both.sec_center[0]) / both.sec_scale[0]  # 3 K below its setpoint
    dt = plant.dt_s
    out_both, out_main = both(obs), main(obs)
    assert out_both[0, -2] * both.e_scale == pytest.approx(2.0 * dt / 20.0)
    assert out_both[0, -1] * both.sec_scale[0] == pytest.approx(3.0 * dt / 20.0)
    np.testing.assert_array_equal(out_both[0, :-1], out_main[0])
    with pytest.raises(ValueError, match="secondary_integral needs integral"):
        MemoryConfig(integral=False, secondary_integral=True)


def test_unknown_or_bad_options():
    with pytest.raises(ValueError, match="unknown controller-memory option.*integral_time_s"):
        MemoryConfig.from_kwargs({"integral_tme_s": 3})
    with pytest.raises(ValueError, match="history_stride"):
        MemoryConfig(history_stride=0)
    with pytest.raises(ValueError, match="integral_limit_K"):
        MemoryConfig(integral_limit_K=-1.0)


def test_residual_adds_scaled_action_to_the_industrial_reference():
    base = NativeVecEnv(ENV_ID, 2, scenario=SHORT)
    res = VecResidual(base, base.venv, 0.25)
    pi = baselines.make(baselines.INDUSTRIAL_REFERENCE, base.venv)
    res.seed(1)
    obs = res.reset()
    a = np.full((2, 2), 0.4, np.float32)
    expect, _ = pi.predict(obs)
    res.step_async(a)
    np.testing.assert_array_equal(base._actions, np.clip(expect + 0.25 * a, -1, 1))
    res.step_wait()
    with pytest.raises(ValueError, match="residual_scale"):
        VecResidual(base, base.venv, 0.0)
