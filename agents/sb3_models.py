"""The SB3 model of a hyperparameter entry, and the parts of a PPO policy that residual,
imitation and fine-tuned runs reach into: its actor's last layer zeroed (a residual starts
at its base), its actor's parameters, and a warm-up that holds the actor still while the
critic learns.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.noise import NormalActionNoise

from agents import privileged
from agents.exploration import LowPassActionNoise
from agents.train_config import SPECIAL


def schedule(value: Any) -> Any:
    """A learning rate: a number, or ``lin_<x>`` for x falling linearly to 0 over the run."""
    if isinstance(value, str) and value.startswith("lin_"):
        v0 = float(value[4:])
        return lambda progress_remaining: progress_remaining * v0
    return value


def sb3_model(
    cls: Any,
    hp: dict[str, Any],
    venv: Any,
    seed: int,
    tensorboard: str | None,
    decision_s: float | None = None,
) -> Any:
    """The SB3 model of ``cls`` on ``venv``: the constructor's hyperparameters, the learning
    rate schedule and, where configured, SAC/TD3's Gaussian action noise: white
    (``normal``) or low-pass with time constant ``noise_tau_s`` (``lowpass``,
    agents/exploration.py; ``decision_s``: the seconds between decisions)."""
    kwargs = {k: v for k, v in hp.items() if k not in SPECIAL}
    kwargs["learning_rate"] = schedule(kwargs.get("learning_rate", 3e-4))
    policy, policy_kwargs = hp.get("policy", "MlpPolicy"), dict(hp["policy_kwargs"])
    if hp.get("privileged_critic"):
        extra = privileged.find(venv)
        if extra is None:
            raise ValueError("a privileged critic needs the training stack's VecPrivileged")
        policy, policy_kwargs["actor_inputs"] = privileged.PrivilegedCriticPolicy, extra.n_actor
    n_u = venv.action_space.shape[0]
    sigma = hp.get("noise_std", 0.1) * np.ones(n_u)
    if hp.get("noise_type") == "normal":
        kwargs["action_noise"] = NormalActionNoise(np.zeros(n_u), sigma)
    elif hp.get("noise_type") == "lowpass":
        kwargs["action_noise"] = LowPassActionNoise(
            sigma, float(np.exp(-decision_s / hp["noise_tau_s"]))
        )
    model = cls(
        policy,
        venv,
        seed=seed,
        device="cpu",
        verbose=0,
        policy_kwargs=policy_kwargs or None,
        tensorboard_log=tensorboard,
        **kwargs,
    )
    if hp.get("residual_base") is not None:
        zero_output(model)
    return model


def zero_output(model: Any) -> None:
    """Zero the last layer of ``model``'s actor (PPO's ``action_net``, SAC's and TD3's last
    linear layer): a residual agent's deterministic action starts at 0, so training starts
    from its base controller."""
    pol = model.policy
    if hasattr(pol, "action_net"):
        layers = [pol.action_net]
    else:
        mus = [a.mu for a in (pol.actor, getattr(pol, "actor_target", None)) if a is not None]
        layers = [[m for m in mu.modules() if isinstance(m, torch.nn.Linear)][-1] for mu in mus]
    with torch.no_grad():
        for layer in layers:
            layer.weight.zero_()
            layer.bias.zero_()


def actor_parameters(model: Any) -> list:
    """The parameters of a PPO policy's actor: its own layers, its output and log std."""
    pol = model.policy
    return [*pol.mlp_extractor.policy_net.parameters(), *pol.action_net.parameters(), pol.log_std]


def critic_warmup(steps: int) -> Any:
    """SB3 callback holding a PPO policy's actor still for its first ``steps`` timesteps, so
    that the critic learns the values of the starting policy before any advantage moves
    the actor (a residual starts at its base, an imitation at its expert: their first
    advantages are noise around a good policy)."""

    class Warmup(BaseCallback):
        def _set(self, on: bool) -> None:
            for p in actor_parameters(self.model):
                p.requires_grad_(on)

        def _on_training_start(self) -> None:
            self._set(False)

        def _on_step(self) -> bool:
            return True

        def _on_rollout_end(self) -> None:
            if self.num_timesteps >= steps:
                self._set(True)

    return Warmup()
