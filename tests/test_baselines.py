"""Baselines (parametrized over baselines.NAMES and every env id); the leaderboard CLI is in
tests/test_leaderboard.py."""

from __future__ import annotations

import copy
import dataclasses
import pickle

import gymnasium as gym
import numpy as np
import pytest
from tunings import skip_without_tuning

import agents
import baselines
import steamtemp_gym
from agents.difficulty import FrozenValves
from agents.evaluation import run_episode
from baselines.policy import Policy
from steamtemp_gym import scenarios
from steamtemp_gym.testing import check_bad_observations_rejected, parametrize_with_checks

IDS = steamtemp_gym.ENV_IDS


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("name", baselines.NAMES)
def test_baseline_is_a_policy_and_beats_open_loop(env_id, name):
    skip_without_tuning(name, env_id)
    env = gym.make(env_id, scenario="heat_imbalance_step")
    policy = baselines.make(name, env)
    assert isinstance(policy, Policy)
    res = run_episode(env, policy, seed=0)
    assert res["metrics"]["tripped"] == 0.0
    ref = run_episode(env, FrozenValves(env), seed=0)
    assert res["metrics"]["iae_K_s"] < 0.5 * ref["metrics"]["iae_K_s"]


def _contracts(quick: bool = False):
    """Every baseline on every plant and every shipped trained agent (sb3:<algo>,
    agents/zoo/) on its own plant: the policy contracts of steamtemp_gym.testing."""
    params = [
        *parametrize_with_checks(
            ids=IDS, policies=baselines.NAMES, env=False, quick=quick
        ).mark.args[1]
    ]
    for env_id, algo in agents.shipped():
        params += parametrize_with_checks(
            ids=[env_id], policies=[f"sb3:{algo}"], env=False, quick=quick
        ).mark.args[1]
    return pytest.mark.parametrize(("env_id", "check"), params)


#: Contracts a shipped baseline breaks today (docs/checking.md): (env id, baseline, check);
#: strict xfail, so a fix shows up here. None at present.
KNOWN_BREAKS: set[tuple[str, str, str]] = set()


def _run_contract(request, env_id, check):
    skip_without_tuning(check.policy_label, env_id)
    if (env_id, check.policy_label, check.name) in KNOWN_BREAKS:
        request.applymarker(pytest.mark.xfail(strict=True, reason="known break, see docs"))
    check(env_id)


@_contracts(quick=True)
def test_policy_contract(request, env_id, check):
    """The policy contracts of steamtemp_gym.testing, short runs (the slow check is in
    test_policy_contract_full)."""
    _run_contract(request, env_id, check)


@pytest.mark.slow
@_contracts()
def test_policy_contract_full(request, env_id, check):
    """The same contracts with full-length runs, and every named scenario, seeds 0-2."""
    _run_contract(request, env_id, check)


@pytest.mark.parametrize("env_id", IDS)
def test_cascade_pi_tracks_a_setpoint_step(env_id):
    """Without noise (settling is read in a 1 K band); ramp peaks against the field bands are
    in tests/test_difficulty.py."""
    quiet = dataclasses.replace(
        scenarios.get("setpoint_step"), noise_std_C=0.0, heat_absorption_noise_std=0.0
    )
    params = {"omega_halfwidth_K": 0.0, "omega2_scale_kg_s": 0.0} if "Cascade" in env_id else {}
    sp = gym.make(env_id, scenario=quiet, params=params)
    m = run_episode(sp, baselines.make("cascade_pi", sp), seed=0)["metrics"]
    assert m["overshoot_pct"] < 20.0 and m["settling_time_s"] < 900.0


def test_unknown_baseline_raises():
    with pytest.raises(ValueError, match="valid names"):
        baselines.make("no_such_controller", gym.make(IDS[0]))


@pytest.mark.parametrize("env_id", [i for i in IDS if gym.make(i).unwrapped.plant.secondary])
def test_secondary_temperatures_are_traced_and_scored(env_id):
    env = gym.make(env_id, scenario="heat_imbalance_step")
    res = run_episode(env, baselines.make("cascade_pi", env), seed=0)
    for name, sp in env.unwrapped.plant.secondary:
        assert res["trace"][name][0] == pytest.approx(sp, abs=0.05)
        assert np.isfinite(res["metrics"][f"{name}_max_abs_dev_K"])
        assert res["metrics"][f"{name}_iae_K_s"] > 0.0


class _Proportional:
    """A baseline as a new module would add it: no argument checks of its own."""

    def __init__(self, env):
        self.memory = 0.0

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(observation)
        self.memory = 0.5 * self.memory + obs[:, -2]  # the error entry, filtered
        a = np.clip(-0.1 * self.memory, -1.0, 1.0)[:, None]
        return (a if np.ndim(observation) == 2 else a[0]), None

    def reset(self):
        self.memory = 0.0


def test_a_baseline_added_to_the_registry_is_held_to_the_observation_checks(monkeypatch):
    """baselines.make checks every registered baseline's predict arguments, so a baseline
    added later passes check_bad_observations_rejected without code of its own."""
    monkeypatch.setitem(baselines.REGISTRY, "proportional", f"{__name__}:_Proportional")
    cascade = "steamtemp/Cascade300MW-v0"
    check_bad_observations_rejected(
        lambda env: baselines.make("proportional", env), cascade, quick=True
    )
    with pytest.raises(AssertionError, match="accepted an observation all NaN"):
        check_bad_observations_rejected(_Proportional, cascade, quick=True)


def test_a_checked_baseline_pickles_copies_and_passes_attributes_through():
    env = gym.make("steamtemp/Cascade300MW-v0", scenario="load_ramp_100_50")
    obs, _ = env.reset(seed=0)
    pol = baselines.make("lqi", env)
    pol.predict(obs)
    for twin in (copy.deepcopy(pol), pickle.loads(pickle.dumps(pol))):
        np.testing.assert_array_equal(twin.predict(obs)[0], copy.deepcopy(pol).predict(obs)[0])
        with pytest.raises(ValueError, match="NaN"):
            twin.predict(np.full_like(obs, np.nan))
    pol.max_move = pol.max_move * 0.5  # written through to the controller
    assert pol.policy.max_move is pol.max_move
