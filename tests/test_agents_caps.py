"""SAC with CAPS (agents/caps.py): the regularizer's value, its gradient joining SAC's own
actor step (and nothing else), and bad weights refused."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch as th

from agents.caps import SACCAPS


def _model(**caps) -> SACCAPS:
    model = SACCAPS(
        "MlpPolicy",
        gym.make("Pendulum-v1"),
        learning_starts=50,
        batch_size=32,
        policy_kwargs={"net_arch": [16]},
        seed=0,
        device="cpu",
        **caps,
    )
    model.learn(100)  # fills the replay buffer
    return model


def test_caps_loss_is_the_papers_temporal_and_spatial_terms():
    model = _model(caps_temporal=2.0, caps_spatial=0.0)
    obs = th.tensor(np.random.default_rng(0).normal(size=(8, 3)), dtype=th.float32)
    nxt = obs + 0.3
    with th.no_grad():
        mu, mu_next = model.actor(obs, deterministic=True), model.actor(nxt, deterministic=True)
        expected = 2.0 * (mu - mu_next).norm(dim=1).mean()
        assert model.caps_loss(obs, nxt).item() == pytest.approx(expected.item(), rel=1e-6)
        model.caps_temporal, model.caps_spatial = 0.0, 1.0
        assert model.caps_loss(obs, nxt).item() > 0.0  # the perturbed states differ
        model.caps_spatial = 0.0
        assert model.caps_loss(obs, nxt).item() == 0.0


def _actor_after_one_train(caps_temporal: float) -> list[np.ndarray]:
    model = _model(caps_temporal=0.0, caps_spatial=0.0)  # the same model every time
    model.caps_temporal = caps_temporal
    th.manual_seed(1)
    np.random.seed(1)  # noqa: NPY002 (SB3's replay buffer samples with the global generator)
    model.train(gradient_steps=1, batch_size=32)
    assert "step" not in vars(model.actor.optimizer)  # the optimizer's own step again
    assert "step" not in vars(model.critic.optimizer)
    return [p.detach().numpy().copy() for p in model.actor.parameters()]


def test_caps_gradient_joins_the_actor_step():
    """A negligible and a large weight draw the same batches; only the gradient differs."""
    tiny = _actor_after_one_train(1e-30)
    again = _actor_after_one_train(1e-30)
    large = _actor_after_one_train(10.0)
    assert all(np.array_equal(a, b) for a, b in zip(tiny, again, strict=True))
    assert not all(np.array_equal(a, b) for a, b in zip(tiny, large, strict=True))


@pytest.mark.parametrize(
    "bad",
    [
        {"caps_temporal": -1.0},
        {"caps_spatial": float("nan")},
        {"caps_sigma": "0.1"},
        {"caps_temporal": True},
    ],
)
def test_bad_weights_are_refused(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        SACCAPS("MlpPolicy", gym.make("Pendulum-v1"), **bad)
