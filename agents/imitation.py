"""Imitation of a causal expert by DAgger, into a PPO model that RL can fine-tune.

``steamtemp-train --algo ppo_imitation_mpc`` (and the zoo's entries of that name) trains
an agent to act as ``mpc_linear`` does from what the agents observe (the env's observation
and the controller memory, agents/wrappers.py), with the dataset aggregation of Ross,
Gordon and Bagnell, "A reduction of imitation learning and structured prediction to
no-regret online learning", AISTATS 2011:

1. iteration 0 runs the expert on ``n_envs`` training episodes (``random`` scenario,
   seeds ``seed + k``) and records (memory-extended observation, expert action) pairs;
   the observation's standardization is frozen from these;
2. each later iteration i runs, per step and row, the expert's action with probability
   ``beta_decay ** i`` and the learner's otherwise, on new training episodes; the expert
   runs in shadow on the same observations and is told the command that was applied
   (``mpc_linear.applied``), so its estimate stays that of the plant as it is driven, and
   labels every visited state with its action;
3. after each iteration the actor (the PPO policy's mean: its ``mlp_extractor.policy_net``
   and ``action_net``) is fitted to every pair so far by mean squared error, plus
   ``move_weight`` times the error of its moves from one step to the next against the
   expert's (agents/behaviour_cloning.py's ``regress``: matching the actions alone, the
   learner strokes the valve on the measurement noise: 1.7-2.9x the reference's travel
   on the FSH where the expert's is 1.7x), and validated as steamtemp-train validates
   (agents/training.py); the best checkpoint within the travel budget is kept.

The result is a PPO model with its memory and frozen normalization in steamtemp-train's
layout, so agents.load, the leaderboard and PPO fine-tuning read it as any trained agent.
Position actions (the expert's own units). Without the controller memory an MLP sees one
observation and cannot hold what the expert's estimator holds: the plain behaviour cloning
of docs/offline.md scores far below its expert.
"""

from __future__ import annotations

from typing import Any

import numpy as np

import baselines
from agents.behaviour_cloning import regress, standardization
from agents.memory import MemoryConfig
from agents.moves import command_state
from agents.policy import AgentPolicy, MlpActor, normalize_obs
from agents.run_clock import RunClock
from agents.train_config import DAGGER_KEYS, EXPERTS, IMITATION_DEFAULTS
from agents.tuning_terms import TUNING_TRAVEL_BUDGET
from agents.validation import better_checkpoint, scored
from agents.vec_env import make_training_env
from agents.wrappers import MemoryState


def actor_net(model: Any) -> Any:
    """The PPO policy's deterministic actor as one torch module (its own parameters)."""
    import torch

    pol = model.policy
    return torch.nn.Sequential(*pol.mlp_extractor.policy_net, pol.action_net)


def collect(
    env_id: str,
    expert_name: str,
    memory: dict,
    seeds: list[int],
    beta: float,
    learner: Any,
    rng: np.random.Generator,
    filter_s: float | None = None,
) -> tuple[np.ndarray, ...]:
    """(memory-extended observations, expert actions, the same at the next step) of every
    step but an episode's last, one episode per seed, the applied action being the
    expert's with probability ``beta`` per step and row and ``learner(x)`` otherwise
    (module docstring); ``filter_s``: the learner's positions pass the output filter
    (agents/moves.py ``LowPassState``), started at each step from the applied command."""
    import gymnasium as gym

    n = len(seeds)
    venv = gym.make_vec(
        env_id, num_envs=n, vectorization_mode="vector_entry_point", scenario="random"
    )
    expert = baselines.make(expert_name, venv)
    mem = MemoryState(venv, MemoryConfig.from_kwargs(memory))
    shape = command_state(venv, None, filter_s)
    obs, _ = venv.reset(seed=[int(s) for s in seeds])
    pairs: list[tuple[np.ndarray, ...]] = []
    start = np.ones(n, dtype=bool)
    live = np.ones(n, dtype=bool)
    last = None
    while live.any():
        x = mem(obs, start)
        a_exp = np.asarray(expert.predict(obs, episode_start=start)[0], np.float64).reshape(n, -1)
        if last is not None:
            pairs.append((last[0][live], last[1][live], x[live], a_exp[live]))
        last = (x, a_exp)
        act = a_exp
        if beta < 1.0:
            mine = rng.random(n) >= beta
            own = np.clip(learner(x), -1.0, 1.0)
            if shape is not None:
                if shape.u is None or start.any():
                    shape.restart(obs, start)
                own = shape(own).astype(np.float64)
            act = np.where(mine[:, None], own, a_exp)
            if shape is not None:  # the filter goes on from the command applied
                shape.u = 0.5 * (act + 1.0)
            expert.applied(act)
        start = np.zeros(n, dtype=bool)
        obs, _, term, trunc, _ = venv.step(act.astype(np.float32))
        live &= ~(term | trunc)
    venv.close()
    return tuple(np.concatenate(p) for p in zip(*pairs, strict=True))


def _learner(model: Any, stats: dict[str, Any] | None) -> Any:
    """The model's deterministic action of a raw memory-extended observation."""
    actor = MlpActor.of(model)
    return lambda z: actor(normalize_obs(z, stats))


def _fit(
    net: Any,
    data: list[tuple[np.ndarray, ...]],
    stats: dict[str, Any],
    settings: dict[str, Any],
    seed: int,
) -> float:
    """Fit the actor to every pair in ``data`` (:func:`collect`'s), with the move term where
    ``move_weight`` > 0; the last epoch's mean squared error."""
    import torch

    def tensor(j: int, obs: bool) -> Any:
        a = np.concatenate([d[j] for d in data])
        a = normalize_obs(a, stats) if obs else np.clip(a, -1.0, 1.0)
        return torch.as_tensor(a, dtype=torch.float32)

    moves = None
    if settings["move_weight"] > 0:
        moves = (tensor(2, True), tensor(3, False), settings["move_weight"])
    return regress(
        net,
        tensor(0, True),
        tensor(1, False),
        epochs=settings["fit_epochs"],
        max_seconds=settings["fit_seconds"],
        seed=seed,
        moves=moves,
    )


def train(
    env_id: str,
    algo: str,
    hp: dict[str, Any],
    seed: int,
    n_envs: int,
    reference: dict[str, float],
    save_to: Any,
    log: Any = None,
    max_minutes: float | None = None,
    clock: RunClock | None = None,
) -> tuple[Any, dict, list, dict, list]:
    """DAgger (module docstring): returns (model, best checkpoint, validation curve,
    imitation record, the aggregated pairs); the best model is saved to ``save_to``.
    Training episodes: seeds ``seed + i * n_envs + k`` in iteration i. ``max_minutes``: CPU
    minutes on ``clock`` (the run's; a new one if None)."""
    from stable_baselines3 import PPO

    settings = {k: hp.get(k, IMITATION_DEFAULTS[k]) for k in DAGGER_KEYS}
    expert, memory, filter_s = EXPERTS[algo], hp["env_wrapper"], hp.get("action_filter_s")
    venv, native, _ = make_training_env(env_id, 1, seed, {**hp, "normalize": False})
    model = PPO(
        hp.get("policy", "MlpPolicy"),
        venv,
        seed=seed,
        device="cpu",
        verbose=0,
        policy_kwargs=hp["policy_kwargs"] or None,
        **{k: hp[k] for k in ("gamma", "gae_lambda") if k in hp},
    )
    net, rng = actor_net(model), np.random.default_rng(seed)
    clock = clock or RunClock()
    data: list[tuple[np.ndarray, ...]] = []
    stats, best, curve = None, {}, []
    record = {"expert": expert, **settings, "iterations": []}
    for i in range(settings["dagger_iterations"]):
        beta = settings["beta_decay"] ** i
        seeds = [seed + i * n_envs + k for k in range(n_envs)]
        data.append(
            collect(env_id, expert, memory, seeds, beta, _learner(model, stats), rng, filter_s)
        )
        stats = stats or standardization(data[0][0])
        mse = _fit(net, data, stats, settings, seed + i)
        score = scored(
            env_id,
            AgentPolicy(model, native, memory=memory, obs_norm=stats, action_filter_s=filter_s),
            reference,
        )
        pairs = int(sum(len(d[0]) for d in data))
        curve.append(
            {
                "timesteps": pairs,
                "fraction": (i + 1) / settings["dagger_iterations"],
                **clock.stamp(),
                **score,
            }
        )
        record["iterations"].append({"beta": beta, "pairs": pairs, "mse": mse})
        if log:
            log(
                f"[{algo}] iteration {i}: beta {beta:.3g}, {pairs:,} pairs, mse {mse:.3g}, "
                f"validation return {score['return']:.1f}, travel {score['travel_ratio']:.2f}x"
            )
        if better_checkpoint(score, best, TUNING_TRAVEL_BUDGET):
            best.update(score, timesteps=pairs, obs_norm=stats)
            model.save(save_to)
        if max_minutes is not None and clock.cpu() > 60.0 * max_minutes:
            break
    venv.close()
    return model, best, curve, record, data


def frozen_normalization(venv: Any, stats: dict[str, Any], gamma: float) -> Any:
    """SB3's VecNormalize over ``venv`` with the observations standardized by the frozen
    ``stats`` (agents.behaviour_cloning.standardization's) and the rewards by their running
    return scale."""
    from stable_baselines3.common.running_mean_std import RunningMeanStd
    from stable_baselines3.common.vec_env import VecNormalize

    class FrozenStats(RunningMeanStd):  # statistics that do not move
        def update(self, arr: np.ndarray) -> None:
            del arr

    out = VecNormalize(
        venv,
        norm_obs=True,
        norm_reward=True,
        gamma=gamma,
        clip_obs=stats["clip_obs"],
        epsilon=stats["epsilon"],
    )
    out.obs_rms = FrozenStats(shape=out.obs_rms.mean.shape)
    out.obs_rms.mean = np.asarray(stats["mean"], np.float64)
    out.obs_rms.var = np.asarray(stats["var"], np.float64)
    return out


def anchor(
    data: list[tuple[np.ndarray, ...]], stats: dict[str, Any], weight: float, until: int, seed: int
) -> Any:
    """SB3 callback keeping a PPO actor near the expert early in RL fine-tuning: PPO's loss
    gains ``w`` times the expert actions' negative log-likelihood under the policy's
    Gaussian, as far as its mean moves it (the squared error of the mean over twice the
    policy's variance, on a minibatch of DAgger's pairs ``data`` per optimizer step; the
    gradient is added in a step pre-hook of PPO's optimizer, after PPO's own gradient and
    its clipping). ``w`` falls linearly from ``weight`` at the start to 0 at ``until``
    timesteps. While the actor is held still (critic warm-up) there is no term."""
    import torch
    from stable_baselines3.common.callbacks import BaseCallback

    x = torch.as_tensor(normalize_obs(np.concatenate([d[0] for d in data]), stats))
    y = torch.as_tensor(
        np.clip(np.concatenate([d[1] for d in data]), -1.0, 1.0), dtype=torch.float32
    )
    gen = torch.Generator().manual_seed(seed)

    class Anchor(BaseCallback):
        def _on_training_start(self) -> None:
            net, pol = actor_net(self.model), self.model.policy

            def add_term(optimizer: Any, args: Any, kwargs: Any) -> None:
                w = weight * max(0.0, 1.0 - self.num_timesteps / until)
                if w <= 0.0 or not pol.log_std.requires_grad:
                    return
                idx = torch.randint(len(x), (self.model.batch_size,), generator=gen)
                var = torch.exp(2.0 * pol.log_std.detach())
                loss = w * torch.mean((net(x[idx]) - y[idx]) ** 2 / (2.0 * var))
                loss.backward()

            self.handle = pol.optimizer.register_step_pre_hook(add_term)

        def _on_step(self) -> bool:
            return True

        def _on_training_end(self) -> None:
            self.handle.remove()

    return Anchor()


__all__ = ["actor_net", "anchor", "collect", "frozen_normalization", "train"]
