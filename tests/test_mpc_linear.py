"""mpc_linear (baselines/mpc_linear.py): offset-free under a constant disturbance (with the
disturbance model removed as the negative control), batched == unbatched bit for bit, no
trip on the leaderboard's scenarios, a bad observation leaves the policy unchanged."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest

import steamtemp_gym
from agents.evaluation import run_batch, run_episode
from agents.leaderboard.plan import DEFAULT_SCENARIOS
from baselines.mpc_linear import MPCLinear
from steamtemp_gym.scenarios import NAMED_DISTURBANCES, Scenario, heldout

IDS = steamtemp_gym.ENV_IDS
FAST = "steamtemp/SupercriticalFSH-v0"
#: +5 % heat absorption over a minute at minute 5, no noise, rated load
HEAT_STEP = Scenario(
    name="heat_step",
    duration_s=3600.0,
    heat_absorption_bias=((0.0, 0.0), (300.0, 0.0), (360.0, 0.05)),
)

#: 100 -> 80 % at 2 %/min from the start
RAMP = Scenario(name="ramp", duration_s=900.0, load=((0.0, 1.0), (600.0, 0.8)))


def _quiet(env_id: str) -> dict:
    """No plant-internal random disturbances (Cascade300MW's omegas), as in test_baselines."""
    return {"omega_halfwidth_K": 0.0, "omega2_scale_kg_s": 0.0} if "Cascade" in env_id else {}


def _offsets(env_id: str, disturbance_model: bool) -> list[float]:
    """Mean |error| (K) over the last 200 s of HEAT_STEP, main steam then secondaries."""
    env = gym.make(env_id, scenario=HEAT_STEP, params=_quiet(env_id))
    tr = run_episode(env, MPCLinear(env, disturbance_model=disturbance_model), 0)["trace"]
    last = tr["time_s"] >= tr["time_s"][-1] - 200.0
    out = [float(np.abs(tr["setpoint_C"] - tr["outlet_temp_C"])[last].mean())]
    for name, sp in env.unwrapped.plant.secondary:
        out.append(float(np.abs(sp - tr[name])[last].mean()))
    return out


@pytest.mark.parametrize(
    "env_id", [i if i == FAST else pytest.param(i, marks=pytest.mark.slow) for i in IDS]
)
def test_no_offset_under_a_constant_heat_absorption_step(env_id):
    """With the disturbance states every scored temperature settles at its setpoint (measured:
    <= 5e-4 K); without them (the negative control) an offset of 1-5 K is left."""
    assert max(_offsets(env_id, True)) < 0.002
    assert max(_offsets(env_id, False)) > 0.5


@pytest.mark.parametrize(
    "env_id", [i if "MIMO" in i else pytest.param(i, marks=pytest.mark.slow) for i in IDS]
)
def test_batched_predict_equals_unbatched_bit_for_bit(env_id):
    """A vector env of 3 seeds under one policy acts exactly as 3 single envs with a policy
    each (noise on, along a load ramp from the start: the local models and QP matrices
    change on the way)."""
    sc = dataclasses.replace(RAMP, **NAMED_DISTURBANCES)
    venv = gym.make_vec(env_id, num_envs=3, scenario=sc, vectorization_mode="vector_entry_point")
    batched = MPCLinear(venv)
    envs = [gym.make(env_id, scenario=sc) for _ in range(3)]
    singles = [MPCLinear(e) for e in envs]
    obs_b, _ = venv.reset(seed=0)
    obs_s = [e.reset(seed=i)[0] for i, e in enumerate(envs)]
    start = np.ones(3, dtype=bool)
    for _ in range(150):
        a_b, _ = batched.predict(obs_b, episode_start=start)
        a_s = np.stack(
            [p.predict(o, episode_start=start[:1])[0] for p, o in zip(singles, obs_s, strict=True)]
        )
        np.testing.assert_array_equal(a_b, a_s)
        start[:] = False
        obs_b, *_ = venv.step(a_b)
        obs_s = [e.step(a)[0] for e, a in zip(envs, a_s, strict=True)]
    assert batched.stats["failures"] == 0


def test_the_solver_called_directly_acts_as_through_osqps_wrapper(monkeypatch):
    """The QP goes to OSQP's compiled solver directly (``QP.core``); through the public
    wrapper (an osqp without it) every action is the same to the bit, along a ramp with
    noise where the local models, the QP matrices and OSQP's adapted rho change."""
    from baselines import mpc_linear

    sc = dataclasses.replace(RAMP, **NAMED_DISTURBANCES)

    def actions() -> tuple[np.ndarray, int]:
        env = gym.make("steamtemp/BoilerTurbineMIMO-v0", scenario=sc)
        pol = MPCLinear(env)
        obs, _ = env.reset(seed=3)
        out, start = [], True
        for _ in range(120):
            a, _ = pol.predict(obs, episode_start=np.array([start]))
            start = False
            out.append(a)
            obs, *_ = env.step(a)
        return np.array(out), pol.stats["iterations"]

    direct, iters = actions()
    init = mpc_linear.QP.__init__
    made = []

    def wrapped_only(self, H, A):
        init(self, H, A)
        assert self.core is not None  # the osqp of this environment has it
        self.core = None
        made.append(self)

    monkeypatch.setattr(mpc_linear.QP, "__init__", wrapped_only)
    wrapped, iters_w = actions()
    assert made and iters_w == iters
    np.testing.assert_array_equal(direct, wrapped)


def _scenario(name: str):
    return heldout.load(name) if heldout.is_heldout(name) else name


def test_completes_the_deep_fast_ramp():
    """The cheap representative of the no-trip check: the held-out runback ramp (100 -> 35 %
    at 8 %/min, below the model grid) on the FSH, seed 0."""
    env = gym.make(FAST, scenario=_scenario("heldout:deep_fast_ramp"))
    assert run_episode(env, MPCLinear(env), 0)["metrics"]["tripped"] == 0.0


@pytest.mark.slow
@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("scenario", DEFAULT_SCENARIOS)
def test_no_trip_on_the_leaderboard_scenarios(env_id, scenario):
    """Every named and held-out scenario of the leaderboard, seeds 0-4."""
    venv = gym.make_vec(
        env_id, num_envs=5, scenario=_scenario(scenario), vectorization_mode="vector_entry_point"
    )
    res = run_batch(venv, MPCLinear(venv), [0, 1, 2, 3, 4])
    assert [r["metrics"]["tripped"] for r in res] == [0.0] * 5


def _actions(policy: MPCLinear, env, bad_at: int | None, bad_obs, steps: int = 40) -> np.ndarray:
    """Actions along a ramp; at step ``bad_at`` a call with ``bad_obs`` (which must raise
    ValueError) comes first."""
    obs, _ = env.reset(seed=0)
    out = []
    for k in range(steps):
        if k == bad_at:
            with pytest.raises(ValueError):
                policy.predict(bad_obs(obs), episode_start=np.array([False]))
        a, _ = policy.predict(obs, episode_start=np.array([k == 0]))
        out.append(a)
        obs, *_ = env.step(a)
    return np.array(out)


@pytest.mark.parametrize(
    "bad",
    [
        lambda o: np.full_like(o, np.nan),
        lambda o: np.where(np.arange(o.size) == 0, np.nan, o),  # one NaN, the load still finite
        lambda o: o[:-1],  # wrong length
        lambda o: np.full_like(o, np.inf),
    ],
    ids=["all_nan", "one_nan", "short", "inf"],
)
def test_a_bad_observation_raises_and_leaves_the_policy_unchanged(bad):
    env = gym.make(FAST, scenario="load_ramp_100_50")
    clean = _actions(MPCLinear(env), env, None, bad)
    np.testing.assert_array_equal(_actions(MPCLinear(env), env, 20, bad), clean)


def test_bad_weights_are_rejected():
    env = gym.make(FAST)
    for kw in (
        {"move_weight": 0.0},
        {"move_weight": np.nan},
        {"u_weight": -1.0},
        {"move_weight": "0.1"},
    ):
        with pytest.raises(ValueError, match="weight"):
            MPCLinear(env, **kw)
