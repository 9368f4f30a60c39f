"""Large batches on several threads (steamtemp_gym/plants/threads.py): bit-identical to one
thread on every plant, including across episode ends; bad settings are refused."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

import steamtemp_gym
from steamtemp_gym.plants import threads

B = 4 * threads.MIN_ROWS_PER_THREAD  # large enough for up to 4 blocks


@pytest.fixture
def restore_threads():
    before = threads.n_threads()
    yield
    threads.set_threads(before)


def _trajectory(env_id: str, n: int) -> np.ndarray:
    threads.set_threads(n)
    venv = gym.make_vec(
        env_id, num_envs=B, vectorization_mode="vector_entry_point", scenario="random"
    )
    obs, _ = venv.reset(seed=3)
    rng = np.random.default_rng(0)
    out = [obs]
    for _ in range(40):
        a = rng.uniform(-1.0, 1.0, venv.action_space.shape).astype(np.float32)
        obs, r, term, trunc, _ = venv.step(a)
        out += [obs, r[:, None], term[:, None], trunc[:, None]]
    venv.close()
    return np.concatenate([np.asarray(o, dtype=np.float64).reshape(B, -1) for o in out], axis=1)


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_threaded_batch_is_bit_identical_to_one_thread(env_id, restore_threads):
    one = _trajectory(env_id, 1)
    for n in (2, 3):  # blocks of unequal size too
        np.testing.assert_array_equal(_trajectory(env_id, n), one)


def test_small_batches_stay_in_the_calling_thread(restore_threads):
    threads.set_threads(4)
    calls = []
    threads.run_rows(lambda x, s: calls.append(x.shape[0]), (np.zeros((100, 2)), 1.0), (0,))
    assert calls == [100]  # below 2 x MIN_ROWS_PER_THREAD: one call
    calls.clear()
    threads.run_rows(lambda x, s: calls.append(x.shape[0]), (np.zeros((B, 2)), 1.0), (0,))
    assert sorted(calls) == [B // 4] * 4


@pytest.mark.parametrize("bad", [0, -1, 1.5, "2", True])
def test_set_threads_refuses_bad_values(bad):
    with pytest.raises(ValueError, match="positive integer"):
        threads.set_threads(bad)


@pytest.mark.parametrize("raw", ["0", "two"])
def test_bad_environment_variable_is_a_clear_error(raw):
    env = dict(os.environ, STEAMTEMP_GYM_THREADS=raw)
    code = "from steamtemp_gym.plants import threads; threads.n_threads()"
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert done.returncode != 0
    assert "STEAMTEMP_GYM_THREADS must be a positive integer" in done.stderr


def test_a_forked_child_gets_threads_of_its_own(restore_threads):
    threads.set_threads(2)
    calls = []
    threads.run_rows(lambda x: calls.append(1), (np.zeros((B, 1)),), (0,))  # pool started
    pid = os.fork()
    if pid == 0:  # child: the inherited pool has no threads; a new one must be made
        signal.alarm(30)  # a hang kills the child (the test then fails) instead of the run
        ok = []
        threads.run_rows(lambda x: ok.append(1), (np.zeros((B, 1)),), (0,))
        os._exit(0 if len(ok) == 2 else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
