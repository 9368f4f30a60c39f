"""Snapshot and restore of env rows (steamtemp_gym/envs/snapshot.py): a restored row goes
on bit for bit like the original, across the end of its episode and the autoreset; bad
snapshots and rows are refused with a ValueError and change nothing."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import steamtemp_gym
from steamtemp_gym import scenarios
from steamtemp_gym.envs.snapshot import ROW_ARRAYS

SHORT = scenarios.Scenario(name="short", duration_s=120.0, load=((0.0, 1.0), (60.0, 0.9)),
                           noise_std_C=0.5, heat_absorption_noise_std=0.03)  # fmt: skip


def _venv(env_id, n, **kw):
    return gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point",
                        scenario=kw.pop("scenario", SHORT), **kw)  # fmt: skip


def _actions(rng, n_steps, shape):
    return [rng.uniform(-1.0, 1.0, shape).astype(np.float32) for _ in range(n_steps)]


def _run(venv, actions, rows):
    out = []
    for a in actions:
        obs, r, term, trunc, info = venv.step(a)
        out.append((obs[rows].copy(), r[rows].copy(), term[rows].copy(), trunc[rows].copy(),
                    info["outlet_temp_C"][rows].copy(), info["time_s"][rows].copy()))  # fmt: skip
    return out


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_a_restored_row_continues_bit_for_bit(env_id):
    """One row's snapshot fanned out into three rows of another env: each goes on exactly
    as the original row, through the episode's end and the next episode's (autoreset)."""
    rng = np.random.default_rng(1)
    a = _venv(env_id, 3)
    a.reset(seed=5)
    n_u = a.unwrapped.plant.n_u
    for act in _actions(rng, 20, (3, n_u)):
        a.step(act)
    snap = a.unwrapped.snapshot(rows=[1])
    future = _actions(rng, 110, (3, n_u))  # past the episode end (Cascade300MW: 120 steps)
    want = _run(a, future, [1])
    b = _venv(env_id, 4)  # the same scenario option: its next episodes are drawn alike
    b.reset(seed=99)
    b.unwrapped.restore(snap, rows=[0, 2, 3])
    np.testing.assert_array_equal(b.unwrapped.observations[0], snap.arrays["obs"][0])
    got = _run(b, [np.repeat(f[1:2], 4, axis=0) for f in future], [0, 2, 3])
    for w, g in zip(want, got, strict=True):
        for x, y in zip(w, g, strict=True):
            np.testing.assert_array_equal(np.broadcast_to(x, y.shape), y)


def test_single_env_snapshot_restores_into_itself_and_into_vector_rows():
    env_id = "steamtemp/Cascade300MW-v0"
    env = gym.make(env_id, scenario=SHORT)
    env.reset(seed=3)
    for _ in range(10):
        env.step(env.action_space.sample() * 0 + 0.1)
    snap = env.unwrapped.snapshot()
    want = [env.step(np.array([0.2], dtype=np.float32)) for _ in range(15)]
    obs = env.unwrapped.restore(snap)
    np.testing.assert_array_equal(obs, snap.arrays["obs"][0])
    again = [env.step(np.array([0.2], dtype=np.float32)) for _ in range(15)]
    venv = _venv(env_id, 2)
    venv.unwrapped.restore(snap, rows=[0, 1])  # every row: no reset needed first
    for w, g in zip(want, again, strict=True):
        np.testing.assert_array_equal(w[0], g[0])
        assert (w[1], w[2], w[3]) == (g[1], g[2], g[3])
        o, r, *_ = venv.step(np.full((2, 1), 0.2, dtype=np.float32))
        np.testing.assert_array_equal(o[1], w[0])
        assert r[0] == w[1]


def _state(venv):
    core = venv.unwrapped.core
    return {k: getattr(core, k).copy() for k in ROW_ARRAYS}, list(core.scenario)


def test_bad_snapshots_and_rows_are_refused_and_change_nothing():
    fsh = _venv("steamtemp/SupercriticalFSH-v0", 3)
    fsh.reset(seed=0)
    other = _venv("steamtemp/Cascade300MW-v0", 2)
    other.reset(seed=0)
    finer = _venv("steamtemp/SupercriticalFSH-v0", 1, params={"n_segments": 12})
    finer.reset(seed=0)
    snap2 = fsh.unwrapped.snapshot(rows=[0, 2])
    before = _state(fsh)
    bad = [
        (lambda: fsh.unwrapped.restore(other.unwrapped.snapshot()), "Cascade300MW"),
        (lambda: fsh.unwrapped.restore(finer.unwrapped.snapshot()), "n_segments"),
        (lambda: fsh.unwrapped.restore(snap2, rows=[0, 1, 2]), "2 rows"),
        (lambda: fsh.unwrapped.restore(snap2, rows=[0, 3]), "out of range"),
        (lambda: fsh.unwrapped.restore(snap2, rows=[1, 1]), "duplicates"),
        (lambda: fsh.unwrapped.restore(snap2, rows="01"), "integer"),
        (lambda: fsh.unwrapped.restore({"X": 1}), "Snapshot"),
        (lambda: fsh.unwrapped.snapshot(rows=[-1]), "out of range"),
        (lambda: fsh.unwrapped.snapshot(rows=[]), "empty"),
        (lambda: fsh.unwrapped.snapshot(rows=[True]), "integers"),
    ]
    for call, words in bad:
        with pytest.raises(ValueError, match=words):
            call()
    after = _state(fsh)
    for k in ROW_ARRAYS:
        np.testing.assert_array_equal(before[0][k], after[0][k], err_msg=k)
    assert before[1] == after[1]
    fresh = _venv("steamtemp/SupercriticalFSH-v0", 3)
    with pytest.raises(ValueError, match="reset"):
        fresh.unwrapped.snapshot()
    with pytest.raises(ValueError, match="every sub-env"):
        fresh.unwrapped.restore(snap2, rows=[0, 1])
    single = gym.make("steamtemp/SupercriticalFSH-v0")
    single.reset(seed=0)
    with pytest.raises(ValueError, match="one-row"):
        single.unwrapped.restore(snap2)
