"""What a planner reads of an env core and how it copies rows (envs/core.py: Core's
accessors; envs/snapshot.py: env_core, planning_core, copy_rows); the core's state as one
EnvState (envs/state.py)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from steamtemp_gym.envs.core import Core
from steamtemp_gym.envs.kernels import TRIP_REASONS
from steamtemp_gym.envs.snapshot import copy_rows, env_core, planning_core
from steamtemp_gym.envs.state import ROW_FIELDS, EnvState
from steamtemp_gym.rewards import RewardConfig
from steamtemp_gym.scenarios import Scenario

ENV = "steamtemp/Cascade300MW-v0"
SHORT = Scenario(
    name="planning_api", duration_s=60.0, noise_std_C=0.25, heat_absorption_noise_std=0.02
)


def _venv(n: int = 3):
    venv = gym.make_vec(
        ENV,
        num_envs=n,
        vectorization_mode="vector_entry_point",
        scenario=SHORT,
        autoreset_mode="Disabled",
    )
    venv.reset(seed=0)
    return venv


def test_the_core_is_one_state_whose_fields_are_its_attributes():
    core = env_core(gym.make(ENV))  # wrapped: env_core unwraps it
    assert isinstance(core.state, EnvState)
    for name in EnvState._fields:
        assert getattr(core, name) is getattr(core.state, name), name
    for name in ROW_FIELDS:
        assert getattr(core, name).shape[0] == core.B, name
    assert core.trip.dtype == np.int64 and core.truncated.dtype == np.bool_


def test_the_accessors_follow_the_episode_and_agree_with_the_env():
    venv = _venv()
    core = env_core(venv)
    assert (core.steps() == 0).all() and not core.ended().any()
    np.testing.assert_array_equal(core.time_left(), np.full(3, SHORT.duration_s))
    dt = core.plant.dt_s
    a = np.zeros(venv.action_space.shape, dtype=np.float32)
    for k in range(1, 1000):
        _, r, term, trunc, info = venv.step(a)
        np.testing.assert_array_equal(core.reward, r)
        np.testing.assert_array_equal(core.trip != 0, term)
        np.testing.assert_array_equal(core.truncated, trunc)
        np.testing.assert_array_equal(core.ended(), term | trunc)
        assert list(info["trip_reason"]) == [TRIP_REASONS[c] for c in core.trip]
        assert (core.steps() == k).all()
        np.testing.assert_allclose(core.time_left(), SHORT.duration_s - k * dt, atol=1e-9)
        np.testing.assert_array_equal(core.held_commands(), core.U)
        if core.ended().all():
            break
    assert core.truncated.all() and k == round(SHORT.duration_s / dt)
    keys = core.noise_keys()
    keys[:] = 0  # copies: the core's own arrays are untouched
    core.steps()[:] = -1
    assert core.key.all() and (core.counter == k).all()


def test_a_trip_code_is_an_integer_of_its_own():
    core = env_core(_venv(2))
    core.X[1] = np.nan  # row 1 leaves the plant's valid region
    core.step(np.zeros((2, core.plant.n_u)))
    assert core.trip.tolist() == [0, TRIP_REASONS.index("non_finite_state")]
    assert core.ended().tolist() == [False, True] and np.isfinite(core.reward).all()


def test_copied_rows_continue_as_their_source():
    venv = _venv()
    src = env_core(venv)
    dst = planning_core(src, 4)
    copy_rows(src, np.array([2, 2, 0]), dst, [1, 3, 0])
    A = np.full((3, src.plant.n_u), 0.3)
    src.step(A)
    dst.step(np.full((4, src.plant.n_u), 0.3))
    for d, s in ((1, 2), (3, 2), (0, 0)):
        np.testing.assert_array_equal(dst.obs[d], src.obs[s])
        assert dst.reward[d] == src.reward[s]


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda s, d: copy_rows(s, [0, 5], d, [0, 1]), "source rows .*out of range"),
        (lambda s, d: copy_rows(s, [0, 1], d, [1, 1]), "destination rows has duplicates"),
        (lambda s, d: copy_rows(s, [0, 1], d, [0]), "2 source row.* 1 destination"),
        (lambda s, d: copy_rows(s, [0.5], d, [0]), "must be integers"),
        (lambda s, d: copy_rows(s, [0], object(), [0]), "destination must be a Core"),
        (lambda s, d: copy_rows(s, [0], d, [-1]), "out of range"),
        (lambda s, d: planning_core(s, 0), "positive integer"),
        (lambda s, d: planning_core(s, True), "positive integer"),
        (lambda s, d: planning_core(object(), 2), "plans from a Core"),
        (lambda s, d: env_core(gym.make("CartPole-v1")), "steamtemp_gym env"),
    ],
)
def test_bad_input_is_refused_and_changes_nothing(call, words):
    src = env_core(_venv())
    dst = planning_core(src, 2)
    before = [a.copy() for a in dst.state]
    with pytest.raises(ValueError, match=words):
        call(src, dst)
    for a, b in zip(before, dst.state, strict=True):
        np.testing.assert_array_equal(a, b)
    assert dst.scenario == [None, None]


def test_copy_rows_refuses_rows_never_reset_and_other_plants():
    src = env_core(_venv())
    fresh = Core(src.plant, 2, RewardConfig())
    with pytest.raises(ValueError, match="never reset"):
        copy_rows(fresh, [1], planning_core(src, 1), [0])
    other = env_core(gym.make("steamtemp/SupercriticalFSH-v0"))
    with pytest.raises(ValueError, match="cannot be copied"):
        copy_rows(src, [0], other, [0])
