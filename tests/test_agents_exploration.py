"""Low-pass exploration noise for off-policy agents (agents/exploration.py): its spread,
its correlation in time, its time constant from the plant, the travel it spends, and its
settings checked."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from stand_ins import refused_entry

from agents import horizons, sb3_models, train_config, training, vec_env
from agents.exploration import LowPassActionNoise

ENV_ID = "steamtemp/SupercriticalFSH-v0"


def test_the_noise_has_its_spread_and_its_correlation():
    np.random.seed(0)  # noqa: NPY002 - SB3's action noises draw from the global generator
    a = float(np.exp(-4.0 / 234.5))
    noise = LowPassActionNoise(np.array([0.1, 0.2]), a)
    x = np.array([noise() for _ in range(200_000)])
    np.testing.assert_allclose(x.std(axis=0), [0.1, 0.2], rtol=0.05)
    lag1 = [np.corrcoef(x[:-1, j], x[1:, j])[0, 1] for j in range(2)]
    np.testing.assert_allclose(lag1, a, atol=0.002)
    # its travel per decision is that of the spread's sqrt(2 (1 - a)), not the spread's
    step = np.abs(np.diff(x[:, 0])).mean()
    assert step == pytest.approx(0.1 * np.sqrt(2 * (1 - a)) * np.sqrt(2 / np.pi), rel=0.03)
    white = np.abs(np.diff(np.random.normal(0, 0.1, 200_000))).mean()  # noqa: NPY002
    assert step < white / 5


def test_reset_starts_from_the_stationary_spread():
    np.random.seed(1)  # noqa: NPY002
    noise = LowPassActionNoise(np.array([0.1]), 0.99)
    starts = []
    for _ in range(4000):
        noise.reset()
        starts.append(noise())
    assert np.std(starts) == pytest.approx(0.1, rel=0.05)


@pytest.mark.parametrize(
    ("sigma", "a", "match"),
    [
        ([0.1], 1.0, "gain a"),
        ([0.1], -0.1, "gain a"),
        ([0.1], 1, "gain a"),
        ([-0.1], 0.5, "sigma"),
        ([np.nan], 0.5, "sigma"),
    ],
)
def test_bad_noise_is_refused(sigma, a, match):
    with pytest.raises(ValueError, match=match):
        LowPassActionNoise(np.array(sigma), a)


def test_plant_sets_the_time_constant_to_the_time_scale():
    out = horizons.from_plant(ENV_ID, {"noise_tau_s": "plant"})
    assert out["noise_tau_s"] == pytest.approx(
        horizons.EXPLORATION_FACTOR * sum(horizons.time_scale(ENV_ID)), abs=1e-5
    )


@pytest.mark.parametrize(
    ("entry", "match"),
    [
        ({"noise_type": "ou"}, "'normal' or 'lowpass'"),
        ({"noise_type": "lowpass"}, "noise_tau_s"),
        ({"noise_type": "normal", "noise_tau_s": 30.0}, "noise_tau_s"),
        ({"noise_type": "lowpass", "noise_tau_s": 0.0}, "positive"),
        ({"noise_type": "lowpass", "noise_tau_s": "30"}, "positive"),
        ({"noise_type": "lowpass", "noise_tau_s": True}, "positive"),
    ],
)
def test_bad_noise_settings_are_config_errors(tmp_path, entry, match):
    refused_entry(tmp_path, ENV_ID, "td3", entry, match)


def test_td3_explores_with_the_low_pass_noise_per_decision(tmp_path):
    """The model gets the noise of the entry, with the gain of its decision interval
    (action repeat x control interval) and the plant's time constant; training runs."""
    path = tmp_path / "td3.yml"
    path.write_text(
        yaml.safe_dump(
            {
                ENV_ID: {
                    "n_envs": 2,
                    "policy": "MlpPolicy",
                    "learning_starts": 50,
                    "buffer_size": 2000,
                    "batch_size": 16,
                    "train_freq": 1,
                    "gradient_steps": 1,
                    "noise_type": "lowpass",
                    "noise_std": 0.1,
                    "noise_tau_s": "plant",
                    "policy_kwargs": "dict(net_arch=[8])",
                    "action_repeat": 2,
                }
            }
        )
    )
    hp = train_config.read_hyperparams(path, ENV_ID, "td3")
    model = sb3_models.sb3_model(
        train_config.algo_class("td3"),
        hp,
        vec_env.make_training_env(ENV_ID, 2, 0, hp)[0],
        0,
        None,
        decision_s=4.0,
    )
    assert isinstance(model.action_noise, LowPassActionNoise)
    assert model.action_noise.a == pytest.approx(np.exp(-4.0 / hp["noise_tau_s"]))
    meta = training.train(
        training.checked_run(ENV_ID, "td3", path, timesteps=200, seed=0, out=tmp_path, quiet=True)
    )
    assert meta["timesteps_trained"] >= 200
    assert meta["hyperparameters"]["noise_tau_s"] == hp["noise_tau_s"]
