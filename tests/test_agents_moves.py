"""Incremental and filtered actions (agents/moves.py): every move within ``max_move``, the
output filter's lag, a bumpless start at the observed openings, restarted rows, the
training wrapper and the Policy giving the env the same commands, and bad values
refused."""

from __future__ import annotations

import json

import numpy as np
import pytest
from stand_ins import Model, ppo_yaml

from agents.moves import LowPassState, MoveState, VecMoves, command_state
from agents.policy import AgentPolicy
from agents.vec_env import NativeVecEnv
from baselines.loops import observation_layout
from steamtemp_gym.scenarios import Scenario

ENV = "steamtemp/Cascade300MW-v0"
MAX_MOVE = 0.03


def _openings(venv, obs) -> np.ndarray:
    names, scale, center = observation_layout(venv)
    i = [names.index(n) for n in venv.unwrapped.plant.valves]
    return obs[:, i] * scale[i] + center[i]


@pytest.fixture(scope="module")
def native():
    venv = NativeVecEnv(ENV, 2, scenario="load_ramp_100_50")
    yield venv
    venv.close()


def test_moves_are_bounded_and_start_at_the_observed_openings(native):
    native.seed(3)
    obs = native.reset()
    ms = MoveState(native.venv, MAX_MOVE)
    ms.restart(obs, np.ones(2, dtype=bool))
    first = ms(np.zeros((2, native.action_space.shape[0])))
    np.testing.assert_allclose((first + 1.0) / 2.0, _openings(native.venv, obs), atol=1e-6)
    rng = np.random.default_rng(1)
    prev = (first.astype(np.float64) + 1.0) / 2.0
    for _ in range(40):
        u = (ms(rng.uniform(-3, 3, first.shape)).astype(np.float64) + 1.0) / 2.0
        assert np.all(np.abs(u - prev) <= MAX_MOVE + 1e-6) and np.all((u >= 0) & (u <= 1))
        prev = u
    assert np.abs(u - (first + 1.0) / 2.0).max() > MAX_MOVE  # it does move over the steps


def test_a_restarted_row_starts_again_from_its_opening_and_the_other_keeps_its_command(native):
    native.seed(0)
    obs = native.reset()
    ms = MoveState(native.venv, MAX_MOVE)
    ms.restart(obs, np.ones(2, dtype=bool))
    n = native.action_space.shape[0]
    for _ in range(5):
        kept = ms(np.ones((2, n)))
    before = ms.u.copy()
    obs2 = obs.copy()
    obs2[0] = obs[1]  # row 0 restarts on another observation
    ms.restart(obs2, np.array([True, False]))
    np.testing.assert_allclose(ms.u[0], np.clip(_openings(native.venv, obs2)[0], 0, 1))
    np.testing.assert_array_equal(ms.u[1], before[1])
    assert kept.dtype == np.float32


FORMS = [{"max_move": MAX_MOVE}, {"action_filter_s": 4.0}]


@pytest.mark.parametrize("form", FORMS, ids=["incremental", "filtered"])
def test_the_training_wrapper_and_the_policy_command_the_same(form):
    """The same model actions through VecMoves (training) and AgentPolicy (evaluation) give
    the env the same commands, across an episode boundary of the wrapper's auto-reset."""
    short = Scenario(name="short", duration_s=10.0, load=0.8)
    native = NativeVecEnv(ENV, 2, scenario=short)
    steps = int(short.duration_s / native.venv.unwrapped.plant.dt_s)
    assert steps < 20  # two episodes and a half in the 25 steps below
    n = native.action_space.shape[0]
    wrapped = VecMoves(native, native.venv, form.get("max_move"), form.get("action_filter_s"))
    sent = []
    orig = native.step_async
    native.step_async = lambda a: (sent.append(np.array(a)), orig(a))[1]
    try:
        native.seed(7)
        obs = wrapped.reset()
        model = Model(n, 2)
        for _ in range(25):
            wrapped.step_async(model.predict(obs)[0])
            obs, *_ = wrapped.step_wait()
    finally:
        native.step_async = orig
    commands = np.array(sent)

    policy = AgentPolicy(Model(n, 2), native.venv, **form)
    native.seed(7)
    obs = native.reset()
    start = np.ones(2, dtype=bool)
    for k in range(25):
        a, _ = policy.predict(obs, episode_start=start)
        np.testing.assert_array_equal(a, commands[k])
        native.step_async(a)
        obs, _, start, _ = native.step_wait()
    native.close()


def test_a_filtered_agent_follows_its_positions_through_the_first_order_lag(native):
    native.seed(2)
    obs = native.reset()
    lp = LowPassState(native.venv, 9.0)
    dt = native.venv.unwrapped.plant.dt_s
    assert lp.alpha == pytest.approx(dt / (9.0 + dt))
    lp.restart(obs, np.ones(2, dtype=bool))
    u0 = _openings(native.venv, obs)
    n = native.action_space.shape[0]
    target = np.full((2, n), 0.6)  # position 0.8 of stroke
    u = (lp(target).astype(np.float64) + 1.0) / 2.0
    np.testing.assert_allclose(u, u0 + lp.alpha * (0.8 - u0), atol=1e-6)
    for _ in range(400):
        u = (lp(target).astype(np.float64) + 1.0) / 2.0
    np.testing.assert_allclose(u, 0.8, atol=1e-6)  # it settles on the position
    # white noise through it: the travel falls by about alpha
    rng = np.random.default_rng(0)
    a = rng.uniform(-1, 1, (2000, 2, n))
    lp.restart(obs, np.ones(2, dtype=bool))
    filtered = np.array([lp(x) for x in a])
    ratio = np.abs(np.diff(filtered, axis=0)).mean() / np.abs(np.diff(a, axis=0)).mean()
    assert ratio < 2 * lp.alpha


@pytest.mark.parametrize("bad", [0, -1.0, float("nan"), float("inf"), True, "5", None])
def test_bad_filter_time_constants_are_refused(native, bad):
    with pytest.raises(ValueError, match="action_filter_s"):
        LowPassState(native.venv, bad)


def test_incremental_and_filtered_together_are_refused(native, tmp_path):
    with pytest.raises(ValueError, match="not both"):
        command_state(native.venv, 0.05, 10.0)
    with pytest.raises(ValueError, match="not two of them"):
        AgentPolicy(Model(1, 2), native.venv, residual_scale=0.2, action_filter_s=10.0)
    from agents.train_config import ConfigError, read_hyperparams

    with pytest.raises(ConfigError, match="action_filter_s filters position actions"):
        read_hyperparams(_ppo_yaml(tmp_path, max_move=0.05, action_filter_s=10.0), ENV, "ppo")
    with pytest.raises(ConfigError, match="action_filter_s must be"):
        read_hyperparams(_ppo_yaml(tmp_path, action_filter_s=-2.0), ENV, "ppo")


@pytest.mark.parametrize("bad", [0, 0.0, -0.1, 1.5, float("nan"), float("inf"), True, "0.1", None])
def test_bad_max_move_is_refused(native, bad):
    with pytest.raises(ValueError, match="max_move"):
        MoveState(native.venv, bad)


def test_residual_and_incremental_together_are_refused(native):
    with pytest.raises(ValueError, match="residual_scale.*max_move.*not two of them"):
        AgentPolicy(Model(1, 2), native.venv, residual_scale=0.2, max_move=0.02)


def test_commands_before_a_start_are_refused(native):
    with pytest.raises(ValueError, match="restart"):
        MoveState(native.venv, 0.1)(np.zeros((2, native.action_space.shape[0])))


def _ppo_yaml(tmp_path, **extra):
    return ppo_yaml(tmp_path, ENV, 64, **extra)


def test_an_incremental_agent_trains_and_acts_within_its_move_bound(tmp_path):
    """``max_move`` in the hyperparameters: trained through VecMoves, written to the
    metadata, and the loaded Policy's commands move at most that much per interval."""
    import gymnasium as gym

    import agents
    from agents import training

    training.train(
        training.checked_run(
            ENV,
            "ppo",
            _ppo_yaml(tmp_path, max_move=MAX_MOVE),
            timesteps=128,
            seed=0,
            out=tmp_path,
            quiet=True,
        )
    )
    meta = json.loads((tmp_path / "steamtemp__Cascade300MW-v0__ppo.json").read_text())
    assert meta["max_move"] == MAX_MOVE
    (files,) = agents.files.find(tmp_path)
    pol = files.load()
    assert pol.moves is not None and pol.moves.max_move == MAX_MOVE
    env = gym.make(ENV, scenario="load_ramp_100_50")
    obs, _ = env.reset(seed=0)
    prev = None
    for _ in range(30):
        a, _ = pol.predict(obs)
        u = (a.astype(np.float64) + 1.0) / 2.0
        if prev is not None:
            assert np.all(np.abs(u - prev) <= MAX_MOVE + 1e-6)
        prev = u
        obs, *_ = env.step(a)


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        ({"max_move": 0.0}, "max_move"),
        ({"max_move": "fast"}, "max_move"),
        ({"max_move": 0.1, "residual_scale": 0.2}, "exclude each other"),
    ],
)
def test_bad_max_move_in_the_hyperparameters_is_refused_before_training(
    tmp_path, capsys, extra, match
):
    from agents import train

    algo = "ppo_residual" if "residual_scale" in extra else "ppo"
    args = [
        "--env",
        ENV,
        "--algo",
        algo,
        "--hyperparams",
        str(_ppo_yaml(tmp_path, **extra)),
        "--out",
        str(tmp_path / "out"),
    ]
    with pytest.raises(SystemExit) as exc:
        train.main(args)
    assert exc.value.code == 2 and match in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


MIMO = "steamtemp/BoilerTurbineMIMO-v0"
SPRAYS = ["sp1_valve", "sp2_valve"]


def test_tie_map_gives_each_valve_its_action():
    from agents.moves import tie_map

    valves = ("sp1_valve", "sp2_valve", "rgd_damper", "fuel_bias")
    np.testing.assert_array_equal(tie_map(valves), [0, 1, 2, 3])
    np.testing.assert_array_equal(tie_map(valves, SPRAYS), [0, 0, 1, 2])
    np.testing.assert_array_equal(tie_map(valves, ["rgd_damper", "sp2_valve"]), [0, 1, 1, 2])


@pytest.mark.parametrize(
    ("bad", "match"),
    [
        (["sp1_valve"], "two or more"),
        (["sp1_valve", "sp1_valve"], "two or more"),
        ("sp1_valve", "two or more"),
        (["sp1_valve", "spray3"], "spray3"),
        (["sp1_valve", 2], "two or more"),
    ],
)
def test_bad_tied_valves_are_refused(bad, match):
    from agents.moves import tie_map

    with pytest.raises(ValueError, match=match):
        tie_map(("sp1_valve", "sp2_valve", "rgd_damper"), bad)


@pytest.fixture(scope="module")
def mimo():
    venv = NativeVecEnv(MIMO, 2, scenario="load_ramp_100_50")
    yield venv
    venv.close()


@pytest.mark.parametrize("form", FORMS, ids=["incremental", "filtered"])
def test_tied_sprays_take_one_action_and_move_together(mimo, form):
    """BoilerTurbineMIMO's two sprays tied: the agent has two actions (sprays, damper);
    started apart, incremental sprays move by the same amount every step (their split is
    held), filtered ones approach the same position; the damper moves on its own."""
    wrapped = VecMoves(mimo, mimo.venv, form.get("max_move"), form.get("action_filter_s"), SPRAYS)
    assert wrapped.action_space.shape == (2,) and mimo.action_space.shape == (3,)
    moves = wrapped.moves
    mimo.seed(4)
    obs = mimo.reset()
    names, scale, _ = observation_layout(mimo.venv)
    obs[:, names.index("sp1_valve")] += 0.2 / scale[names.index("sp1_valve")]  # 20 % apart
    moves.restart(obs, np.ones(2, dtype=bool))
    u0 = _openings(mimo.venv, obs)
    assert np.all(u0[:, 0] - u0[:, 1] > 0.19)
    model = Model(2, 2, seed=5)
    steps = [(moves(model.predict(obs)[0]).astype(np.float64) + 1.0) / 2.0 for _ in range(60)]
    u = np.array(steps)  # (steps, rows, 3)
    if "max_move" in form:
        inside = ((u[:, :, :2] > 1e-9) & (u[:, :, :2] < 1 - 1e-9)).all(axis=-1)
        assert inside.mean() > 0.5
        split = np.broadcast_to(u0[:, 0] - u0[:, 1], inside.shape)
        np.testing.assert_allclose((u[:, :, 0] - u[:, :, 1])[inside], split[inside], atol=1e-6)
        assert np.abs(np.diff(u[:, :, 0], axis=0)).sum() > 0.1  # and they do move
    else:
        np.testing.assert_allclose(u[-1, :, 0], u[-1, :, 1], atol=1e-6)
    assert np.abs(np.diff(u[:, :, 2], axis=0)).sum() > 0.1  # the damper has its own action


def test_tied_valves_in_the_hyperparameters_train_and_load(tmp_path):
    """``tied_valves`` in the hyperparameters: the model has one action per group, the
    metadata names the valves, and the loaded Policy gives the env every valve."""
    import gymnasium as gym
    import yaml

    import agents
    from agents import training

    hp = yaml.safe_load(_ppo_yaml(tmp_path, max_move=MAX_MOVE, tied_valves=SPRAYS).read_text())
    path = tmp_path / "mimo.yml"
    path.write_text(yaml.safe_dump({MIMO: hp[ENV]}))
    training.train(
        training.checked_run(MIMO, "ppo", path, timesteps=128, seed=0, out=tmp_path, quiet=True)
    )
    meta = json.loads((tmp_path / "steamtemp__BoilerTurbineMIMO-v0__ppo.json").read_text())
    assert meta["tied_valves"] == SPRAYS
    (files,) = agents.files.find(tmp_path)
    files.check()  # the model's two actions fit the env's three valves
    pol = files.load()
    assert pol.model.action_space.shape == (2,) and pol.moves.n_actions == 2
    env = gym.make(MIMO, scenario="load_ramp_100_50")
    obs, _ = env.reset(seed=0)
    u0 = None
    for _ in range(10):
        a, _ = pol.predict(obs)
        assert a.shape == (3,)
        u = (a.astype(np.float64) + 1.0) / 2.0
        u0 = u if u0 is None else u0
        obs, *_ = env.step(a)
    assert (u[0] - u[1]) == pytest.approx(u0[0] - u0[1], abs=1e-6)


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        ({"tied_valves": SPRAYS}, "tied_valves needs incremental"),
        ({"max_move": 0.05, "tied_valves": ["sp1_valve", "sp3"]}, "sp3"),
        ({"max_move": 0.05, "tied_valves": "sp1_valve"}, "two or more"),
    ],
)
def test_bad_tied_valves_in_the_hyperparameters_are_refused(tmp_path, extra, match):
    import yaml

    from agents.train_config import ConfigError, read_hyperparams

    hp = yaml.safe_load(_ppo_yaml(tmp_path, **extra).read_text())[ENV]
    path = tmp_path / "mimo.yml"
    path.write_text(yaml.safe_dump({MIMO: hp}))
    with pytest.raises(ConfigError, match=match):
        read_hyperparams(path, MIMO, "ppo")
