"""Registry-wide tests: every registered id, no per-plant code (as Gymnasium's test_envs.py).

The contracts are the named checks of steamtemp_gym.testing (docs/checking.md), the same
ones users run on their own plants and variants; the tests after them are the project's
own (option errors, the scenario YAML format, the reward's spray term).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import steamtemp_gym
from steamtemp_gym.plants import plant_class
from steamtemp_gym.scenarios import Scenario
from steamtemp_gym.testing import parametrize_with_checks

IDS = steamtemp_gym.ENV_IDS


@parametrize_with_checks(ids=IDS)
def test_contract(env_id, check):
    check(env_id)


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


@pytest.mark.parametrize("env_id", [i for i in IDS if plant_class(i).design_spray is not None])
def test_holding_the_setpoint_with_design_spray_scores_about_zero(env_id):
    """The reward's spray term charges only spray above the plant's design spray."""
    env = gym.make(
        env_id,
        scenario=Scenario(name="rated", duration_s=200.0, load=1.0),
        params={"omega_halfwidth_K": 0.0, "omega2_scale_kg_s": 0.0} if "Cascade" in env_id else {},
    )
    plant = env.unwrapped.plant
    assert plant.design_spray in plant.index, "design_spray names none of the plant's outputs"
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


def test_without_a_design_spray_the_reward_charges_all_spray(monkeypatch):
    """A plant that declares no design spray (``Plant.design_spray`` None) is charged for
    every kg/s of spray, in units of the first spray flow's scale."""
    env_id = IDS[0]
    monkeypatch.setattr(plant_class(env_id), "design_spray", None)
    only_spray = {"w_abs": 0.0, "w_band": 0.0, "w_secondary": 0.0, "w_move": 0.0, "w_spray": 1.0}
    env = gym.make(
        env_id, scenario=Scenario(name="rated", duration_s=200.0, load=1.0), reward=only_spray
    )
    _, info = env.reset(seed=0)
    hold = (2.0 * np.atleast_1d(info["spray_valve"]) - 1.0).astype(np.float32)
    core, plant = env.unwrapped.core, env.unwrapped.plant
    scale = plant.outputs[core.spray_idx[0]].scale
    for _ in range(5):
        r = env.step(hold)[1]
        spray = core.Z[0, core.spray_idx].sum()
        assert spray > 0.0
        assert r == pytest.approx(-spray / scale, rel=1e-12)


@pytest.mark.parametrize("seed", ["a", -1, 1.5, True, np.bool_(True), np.float64(2.0)])
def test_a_bad_seed_is_the_same_value_error_in_the_single_and_the_vector_env(seed):
    """The single env raised Gymnasium's Error for 'a', -1 and 1.5 and took True; the
    vector env refused True. Now both raise ValueError and change nothing."""
    env = gym.make("steamtemp/Cascade300MW-v0")
    obs, _ = env.reset(seed=4)
    with pytest.raises(ValueError, match="seed"):
        env.reset(seed=seed)
    venv = gym.make_vec(
        "steamtemp/Cascade300MW-v0", num_envs=2, vectorization_mode="vector_entry_point"
    )
    with pytest.raises(ValueError, match="seed"):
        venv.reset(seed=seed)
    np.testing.assert_array_equal(env.unwrapped.core.obs[0], obs)


def test_a_numpy_integer_seed_is_its_integer_in_the_single_and_the_vector_env():
    env = gym.make("steamtemp/Cascade300MW-v0")
    a = env.reset(seed=np.int64(3))[0]
    b = env.reset(seed=3)[0]
    venv = gym.make_vec(
        "steamtemp/Cascade300MW-v0", num_envs=1, vectorization_mode="vector_entry_point"
    )
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(venv.reset(seed=np.int64(3))[0][0], b)
