"""A trained SB3 model as a Policy (baselines/policy.py): it takes the env's raw
observation and carries its own observation pipeline (controller memory, then the
VecNormalize statistics frozen at the end of training) with the memory's state kept per
row across calls; ``reset()`` or ``episode_start`` restarts it. A residual agent adds its
scaled action to its base controller's (agents/residual.py); an incremental agent's
action is a bounded valve move per interval (agents/moves.py). ``predict`` refuses a
non-finite or misshapen observation with a ``ValueError`` before any state changes, as the
baselines do
(``baselines.policy.check_predict_args``).

The deterministic action of an MLP actor (PPO's, SAC's, TD3's) is computed in float64
NumPy from the model's weights (:class:`MlpActor`): the same action as SB3's float32
``predict`` to about 1e-6, but the same for a row whether it is acted on alone or in a
batch (torch's float32 products round differently with the batch size, and a closed loop
amplifies that: 1.1e-6 after 16 steps of SAC on the FSH), and about 10 times faster.
Other models (RecurrentPPO's LSTM) act through SB3's ``predict``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from agents.caps import SACCAPS
from agents.moves import command_state
from agents.repeat import Decisions
from agents.residual import ResidualBase
from agents.wrappers import MemoryConfig, MemoryState
from baselines.loops import restart_rows
from baselines.policy import check_predict_args, observation_size


class MlpActor:
    """The deterministic action of an SB3 MLP policy in float64 NumPy (module docstring).

    ``MlpActor.of(model)`` is None for a model of another structure.
    """

    _ACT = {"Tanh": np.tanh, "ReLU": lambda z: np.maximum(z, 0.0)}

    def __init__(self, layers: list, squash: bool, low: np.ndarray, high: np.ndarray) -> None:
        self.layers, self.squash, self.low, self.high = layers, squash, low, high

    @classmethod
    def of(cls, model: Any) -> MlpActor | None:
        import torch

        pol = getattr(model, "policy", None)
        space = getattr(pol, "action_space", None)
        if pol is None or not hasattr(space, "low"):
            return None
        # gSDE changes the exploration noise, not the deterministic action (the mean), but
        # for PPO's squash_output (a tanh on the mean)
        if hasattr(pol, "action_net") and hasattr(pol, "mlp_extractor"):  # PPO, A2C
            if getattr(pol, "squash_output", False):
                return None
            modules = [*pol.mlp_extractor.policy_net, pol.action_net]
            extractor, squash = pol.pi_features_extractor, False
        elif hasattr(getattr(pol, "actor", None), "latent_pi"):  # SAC
            modules = [*pol.actor.latent_pi, pol.actor.mu, torch.nn.Tanh()]
            extractor, squash = pol.actor.features_extractor, True
        elif isinstance(getattr(getattr(pol, "actor", None), "mu", None), torch.nn.Sequential):
            modules = [*pol.actor.mu]  # TD3: ends in Tanh
            extractor, squash = pol.actor.features_extractor, True
        else:
            return None
        if type(extractor).__name__ != "FlattenExtractor":
            return None
        layers = []
        for m in modules:
            if isinstance(m, torch.nn.Linear):
                w = m.weight.detach().cpu().numpy().astype(np.float64)
                b = m.bias.detach().cpu().numpy().astype(np.float64)
                layers.append((np.ascontiguousarray(w.T), b))
            elif type(m).__name__ in cls._ACT:
                layers.append(cls._ACT[type(m).__name__])
            else:
                return None
        low = np.asarray(space.low, dtype=np.float64)
        high = np.asarray(space.high, dtype=np.float64)
        return cls(layers, squash, low, high)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        z = np.asarray(x, dtype=np.float64)
        for layer in self.layers:
            z = layer(z) if callable(layer) else z @ layer[0] + layer[1]
        if self.squash:  # tanh output in [-1, 1] -> the action space (SB3's unscale_action)
            return self.low + 0.5 * (z + 1.0) * (self.high - self.low)
        return np.clip(z, self.low, self.high)


def frozen_stats(vecnormalize: Any) -> dict[str, Any] | None:
    """The observation statistics of an SB3 VecNormalize (mean, var, epsilon, clip_obs) as
    :func:`normalize_obs` takes them; None when it does not normalize observations."""
    if not getattr(vecnormalize, "norm_obs", False):
        return None
    rms = vecnormalize.obs_rms
    return {
        "mean": rms.mean.tolist(),
        "var": rms.var.tolist(),
        "epsilon": vecnormalize.epsilon,
        "clip_obs": vecnormalize.clip_obs,
    }


def normalize_obs(obs: np.ndarray, stats: dict[str, Any] | None) -> np.ndarray:
    """SB3 VecNormalize's observation normalization with frozen ``stats`` (mean, var,
    epsilon, clip_obs), float32 as VecNormalize returns it; obs unchanged for None."""
    if not stats:
        return obs
    z = (obs - np.asarray(stats["mean"])) / np.sqrt(np.asarray(stats["var"]) + stats["epsilon"])
    return np.clip(z, -stats["clip_obs"], stats["clip_obs"]).astype(np.float32)


class AgentPolicy:
    """A trained model with its observation pipeline (module docstring).

    Args:
        model: The SB3 model (anything with SB3's ``predict``).
        env: The env it acts on (observation layout, plant; the base of a residual).
        memory: Controller-memory options (agents.wrappers.MemoryConfig fields) or None.
        obs_norm: Frozen VecNormalize statistics or None.
        residual_scale: If set, the action is the base controller's plus this times the
            model's (agents/residual.py).
        residual_base: The base controller of a residual agent that observes it (a
            registered baseline's name); None: the industrial reference, unobserved.
        max_move: If set, the model's action is a valve move of at most this fraction of
            stroke per control interval (agents/moves.py); not with ``residual_scale``.
        action_filter_s: If set, the model's action is a valve position through a
            first-order filter of this time constant (agents/moves.py ``LowPassState``).
        tied_valves: Valves that share one of the model's actions (agents/moves.py; with
            ``max_move`` or ``action_filter_s``).
        action_repeat: If set, the model decides every this many control intervals and its
            action is held in between (agents/repeat.py); a recurrent model's state moves
            on its decisions only, as it did in training.
    """

    #: Batched and unbatched actions agree to this (read by steamtemp_gym.testing's
    #: check_batched_equals_unbatched): float64 products in MlpActor; 1e-6 for a model
    #: acting through torch's float32 ``predict`` (measured: 1.5e-8 on the PPO zoo).
    batch_tolerance = 1e-9

    def __init__(
        self,
        model: Any,
        env: Any,
        memory: dict | None = None,
        obs_norm: dict | None = None,
        residual_scale: float | None = None,
        max_move: float | None = None,
        residual_base: str | None = None,
        action_filter_s: float | None = None,
        tied_valves: list[str] | None = None,
        action_repeat: int | None = None,
    ) -> None:
        if residual_scale is not None and (max_move, action_filter_s) != (None, None):
            raise ValueError(
                "an agent is either residual (residual_scale) or incremental "
                "(max_move) or filtered (action_filter_s), not two of them"
            )
        self.model = model
        self.n_obs = observation_size(env)
        self.memory = None
        if memory is not None:
            self.memory = MemoryState(env, MemoryConfig.from_kwargs(memory))
        self.obs_norm = None  # the statistics as arrays once, not at every step
        if obs_norm:
            self.obs_norm = {
                **obs_norm,
                "mean": np.asarray(obs_norm["mean"], dtype=np.float64),
                "var": np.asarray(obs_norm["var"], dtype=np.float64),
            }
        self.residual_scale = residual_scale
        self.base = None
        if residual_scale is not None:
            self.base = ResidualBase(env, residual_scale, residual_base)
        elif residual_base is not None:
            raise ValueError("residual_base needs residual_scale (a residual agent)")
        self.moves = command_state(env, max_move, action_filter_s, tied_valves)
        #: The LSTM state of a recurrent model (sb3-contrib's RecurrentPPO), per row.
        self.recurrent = hasattr(getattr(model, "policy", None), "lstm_actor")
        self.actor = None if self.recurrent else MlpActor.of(model)
        if self.actor is None:
            self.batch_tolerance = 1e-6
        self._lstm = None
        self._n: int | None = None
        #: A critic trained on privileged signals (agents/privileged.py): the actor reads the
        #: agent's entries only, so SB3's ``predict`` gets them padded with zeros.
        self.critic_only = 0
        space = getattr(getattr(model, "policy", None), "observation_space", None)
        if hasattr(getattr(model, "policy", None), "actor_inputs"):
            self.critic_only = space.shape[0] - model.policy.actor_inputs
        self.decisions = None
        if action_repeat is not None:
            self.decisions = Decisions(action_repeat, incremental=max_move is not None)

    def reset(self) -> None:
        self._n = None
        self._lstm = None
        if self.base is not None:
            self.base.reset()

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(check_predict_args(observation, episode_start, self.n_obs)).astype(
            np.float64, copy=False
        )
        n = obs.shape[0]
        restart = restart_rows(self._n != n, n, episode_start)
        self._n = n
        if self.moves is not None and restart.any():
            self.moves.restart(obs, restart)
        x = obs
        if self.base is not None:
            self.base.step(obs, restart)
            x = self.base.extend(obs)
        x = self.memory(x, restart) if self.memory is not None else x
        x = normalize_obs(x, self.obs_norm)
        due = None
        if self.decisions is not None:  # only the rows that decide in this interval
            due = self.decisions.due(restart)
            x = x[due]
        if len(x) == 0:
            action = None
        elif self.recurrent:
            action = self._recurrent(x, restart, due, deterministic)
        elif self.actor is not None and deterministic:
            action = self.actor(x)
        else:
            if self.critic_only:
                x = np.concatenate([x, np.zeros((len(x), self.critic_only), x.dtype)], axis=1)
            action, _ = self.model.predict(x, deterministic=deterministic)
        if action is not None:
            action = np.asarray(action, dtype=np.float32).reshape(len(x), -1)
        if due is not None:
            action = self.decisions.act(due, action)
        if self.base is not None:
            action = self.base.combine(action)
        if self.moves is not None:
            action = self.moves(action)
        return (action[0] if np.ndim(observation) == 1 else action), None

    def _recurrent(
        self, x: np.ndarray, restart: np.ndarray, due: np.ndarray | None, deterministic: bool
    ) -> np.ndarray:
        """A recurrent model's action for the deciding rows ``x`` (all rows where ``due`` is
        None); their LSTM states move on, the restarted rows' from a fresh state."""
        rows = np.ones(len(restart), dtype=bool) if due is None else due
        state = None
        if self._lstm is not None and not restart[rows].all():
            state = tuple(s[:, rows] for s in self._lstm)
        action, new = self.model.predict(
            x, state=state, episode_start=restart[rows], deterministic=deterministic
        )
        if self._lstm is None or self._lstm[0].shape[1] != len(restart):
            self._lstm = tuple(
                np.zeros((s.shape[0], len(restart), *s.shape[2:]), s.dtype) for s in new
            )
        for full, part in zip(self._lstm, new, strict=True):
            full[:, rows] = part
        return action


def model_class(name: str):
    """The SB3 or sb3-contrib class of a model class name (a zoo .json's ``sb3_class``)."""
    import stable_baselines3 as sb3

    if hasattr(sb3, name):
        return getattr(sb3, name)
    if name == "SACCAPS":
        return SACCAPS
    try:
        import sb3_contrib
    except ImportError:
        raise ValueError(
            f"{name} needs sb3-contrib: pip install sb3-contrib (part of the "
            "project's [agents] extra)"
        ) from None
    if not hasattr(sb3_contrib, name):
        raise ValueError(f"unknown model class {name!r}")
    return getattr(sb3_contrib, name)
