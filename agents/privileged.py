"""An asymmetric actor-critic: in training the critic sees what the plant knows and the
agent cannot measure; the actor, and so the policy that ships, sees the agent's
observation only.

An agent has to estimate and control at once from a short window of noisy measurements,
while ``mpc_linear`` acts on a Kalman filter with disturbance states and the load-rate
feed-forward. The critic is only used in training, so it may see more (Pinto et al.,
"Asymmetric actor critic for image-based robot learning", RSS 2018): a value function
that knows the hidden state and what the scenario will do gives the actor advantages with
less of the estimation noise in them.

:class:`VecPrivileged` appends to every observation the privileged signals of
:func:`signal_names`, read from the native vector env's state after each decision:

- the plant's outputs the agent does not observe, scaled as the observation is
  (``(value - center) / scale``): the true outlet and inner temperatures, the hidden heat
  absorption, the metal temperature and the design spray;
- the disturbances of the step (load, load rate, heat-absorption bias with its coloured
  part, fouling, spray-water temperature offset) and the coloured part alone;
- the scenario's load demand and setpoint offset :data:`LOOK_AHEAD_S` ahead.

:class:`PrivilegedCriticPolicy` is SB3's ``ActorCriticPolicy`` whose actor network reads
the first ``actor_inputs`` entries of the observation (the agent's, controller memory
included) and whose critic reads all of it. Its actor is an MLP on the agent's observation
like any PPO actor, so ``agents.policy.MlpActor`` computes the shipped policy's action from
it and the frozen normalization statistics of the agent's entries; the privileged entries
never reach it.

At the last step of an episode the native env has already started the next one, so the
terminal observation (which PPO's value bootstraps from at a time limit) carries the
privileged signals of the decision before: one decision stale, at one transition per
episode.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.torch_layers import MlpExtractor
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper

from steamtemp_gym.envs.kernels import E_TIME
from steamtemp_gym.plants.base import DIST
from steamtemp_gym.scenarios.model import CHANNELS

#: How far ahead (s) the critic sees the scenario's load demand and setpoint offset.
LOOK_AHEAD_S = (30.0, 60.0, 120.0, 300.0)
#: The scenario channels the critic sees ahead.
AHEAD_CHANNELS = ("load", "setpoint_offset_C")


def hidden_outputs(plant: Any) -> list[Any]:
    """The plant's output signals the agent does not observe."""
    return [s for s in plant.outputs if not s.observed]


def signal_names(plant: Any) -> list[str]:
    """The names of the privileged entries, in the order :class:`VecPrivileged` appends
    them."""
    ahead = [f"{ch}@+{t:g}s" for ch in AHEAD_CHANNELS for t in LOOK_AHEAD_S]
    return [s.name for s in hidden_outputs(plant)] + list(DIST) + ["heat_absorption_noise"] + ahead


def schedule_ahead(state: Any, times: np.ndarray, channel: str) -> np.ndarray:
    """(B, len(times)) the scenario channel ``channel`` of every row of a core ``state``
    (envs/state.py) at ``times`` s after its current time: linear between breakpoints, held
    at the ends, as the env's schedules are."""
    c = CHANNELS.index(channel)
    bt = state.bp_t[state.slot, c]  # (B, K)
    bv = state.bp_v[state.slot, c]
    n = state.bp_n[state.slot, c]
    t = state.ep[:, E_TIME][:, None] + times[None, :]  # (B, H)
    valid = np.arange(bt.shape[1])[None, :] < n[:, None]
    before = ((bt[:, None, :] <= t[:, :, None]) & valid[:, None, :]).sum(-1) - 1
    last = (n - 1)[:, None]
    i0 = np.clip(before, 0, last)
    i1 = np.clip(before + 1, 0, last)
    t0, t1 = np.take_along_axis(bt, i0, 1), np.take_along_axis(bt, i1, 1)
    v0, v1 = np.take_along_axis(bv, i0, 1), np.take_along_axis(bv, i1, 1)
    span = t1 - t0
    w = np.divide(t - t0, span, out=np.zeros_like(t), where=span > 0)
    return v0 + np.clip(w, 0.0, 1.0) * (v1 - v0)


class VecPrivileged(VecEnvWrapper):
    """The agent's observation with the privileged signals appended (module docstring).

    Args:
        venv: The training stack (what the actor sees).
        env: The native vector env under it (``SteamTempVectorEnv``), whose state is read.
    """

    def __init__(self, venv: VecEnv, env: Any) -> None:
        self.core = env.core
        plant = self.core.plant
        hidden = hidden_outputs(plant)
        self.i_hidden = np.array([plant.index[s.name] for s in hidden], dtype=np.int64)
        self.center = np.array([s.center for s in hidden])
        self.scale = np.array([s.scale for s in hidden])
        self.times = np.asarray(LOOK_AHEAD_S)
        self.n_actor = venv.observation_space.shape[0]
        self.n_privileged = len(signal_names(plant))
        n = self.n_actor + self.n_privileged
        space = spaces.Box(-np.inf, np.inf, shape=(n,), dtype=np.float32)
        super().__init__(venv, observation_space=space)
        self._last = np.zeros((venv.num_envs, self.n_privileged), dtype=np.float32)

    def privileged(self) -> np.ndarray:
        """(B, n) the privileged signals of every row now."""
        s = self.core.state
        hidden = (s.Z[:, self.i_hidden] - self.center) / self.scale
        ahead = [schedule_ahead(s, self.times, ch) for ch in AHEAD_CHANNELS]
        cols = [np.nan_to_num(hidden), s.D, s.ou[:, None], *ahead]
        return np.concatenate(cols, axis=1).astype(np.float32)

    def _with(self, obs: np.ndarray, extra: np.ndarray) -> np.ndarray:
        return np.concatenate([obs, extra], axis=-1).astype(np.float32)

    def reset(self) -> np.ndarray:
        obs = self.venv.reset()
        self._last = self.privileged()
        return self._with(obs, self._last)

    def step_wait(self):
        obs, rewards, dones, infos = self.venv.step_wait()
        now = self.privileged()
        for b in np.flatnonzero(dones):
            term = infos[b].get("terminal_observation")
            if term is not None:  # the next episode has begun: the decision before's
                infos[b]["terminal_observation"] = self._with(term, self._last[b])
        self._last = now
        return self._with(obs, now), rewards, dones, infos


class SplitExtractor(MlpExtractor):
    """SB3's MLP extractor whose policy network reads the first ``actor_inputs`` features
    and whose value network reads all of them."""

    def __init__(
        self,
        feature_dim: int,
        actor_inputs: int,
        net_arch: Any,
        activation_fn: type[torch.nn.Module],
        device: Any = "auto",
    ) -> None:
        super().__init__(feature_dim, net_arch, activation_fn, device)
        self.actor_inputs = actor_inputs
        self.policy_net = MlpExtractor(actor_inputs, net_arch, activation_fn, device).policy_net

    def forward(self, features: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.forward_actor(features), self.forward_critic(features)

    def forward_actor(self, features: torch.Tensor) -> torch.Tensor:
        return self.policy_net(features[..., : self.actor_inputs])


class PrivilegedCriticPolicy(ActorCriticPolicy):
    """PPO's actor-critic policy with an actor on the agent's ``actor_inputs`` observation
    entries and a critic on all of them (module docstring)."""

    def __init__(self, *args: Any, actor_inputs: int, **kwargs: Any) -> None:
        if not (isinstance(actor_inputs, int) and actor_inputs >= 1):
            raise ValueError(f"actor_inputs must be an integer >= 1, got {actor_inputs!r}")
        self.actor_inputs = actor_inputs
        super().__init__(*args, **kwargs)

    def _build_mlp_extractor(self) -> None:
        if self.actor_inputs >= self.features_dim:
            raise ValueError(
                f"actor_inputs ({self.actor_inputs}) must be fewer than the "
                f"critic's {self.features_dim} inputs"
            )
        self.mlp_extractor = SplitExtractor(
            self.features_dim, self.actor_inputs, self.net_arch, self.activation_fn, self.device
        )

    def _get_constructor_parameters(self) -> dict[str, Any]:
        return {**super()._get_constructor_parameters(), "actor_inputs": self.actor_inputs}


def actor_stats(stats: dict[str, Any] | None, n_actor: int) -> dict[str, Any] | None:
    """Frozen normalization statistics (agents.policy.frozen_stats) of the actor's
    ``n_actor`` entries only: what the shipped policy normalizes its observation with."""
    if not stats:
        return stats
    return {**stats, "mean": stats["mean"][:n_actor], "var": stats["var"][:n_actor]}


def find(venv: Any) -> VecPrivileged | None:
    """The :class:`VecPrivileged` in a training stack of VecEnv wrappers, or None."""
    while venv is not None:
        if isinstance(venv, VecPrivileged):
            return venv
        venv = getattr(venv, "venv", None)
    return None


__all__ = [
    "AHEAD_CHANNELS",
    "LOOK_AHEAD_S",
    "PrivilegedCriticPolicy",
    "SplitExtractor",
    "VecPrivileged",
    "actor_stats",
    "find",
    "schedule_ahead",
    "signal_names",
]
