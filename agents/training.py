"""One training run of steamtemp-train: the training envs, the SB3 model, validation at
every sixteenth of the budget with the best checkpoint kept, and the run's metadata (module
docstring of agents/train.py).
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import steamtemp_gym
from agents.files import git_revision, steamtemp_paths, stem
from agents.run_clock import RunClock, one_core
from agents.run_record import metadata, price_record
from agents.train_config import (
    EXPERTS,
    FINE_TUNED,
    HYPERPARAMS,
    IMITATION_DEFAULTS,
    SPECIAL,
    ConfigError,
    algo_class,
    read_hyperparams,
)
from agents.validation import (  # noqa: F401 - re-exported
    N_VALIDATION,
    VALIDATION_SEED,
    better_checkpoint,
    reference_result,
    scored,
)
from agents.vec_env import make_training_env  # noqa: F401 - re-exported

#: Where in the budget the agent is validated (and the best kept): every sixteenth.
EVAL_FRACTIONS = tuple(k / 16 for k in range(1, 17))


def _schedule(value: Any):
    if isinstance(value, str) and value.startswith("lin_"):
        v0 = float(value[4:])
        return lambda progress_remaining: progress_remaining * v0
    return value


def _obs_stats(venv) -> dict[str, Any] | None:
    """The frozen observation statistics of the training stack's VecNormalize (None
    without one), of the actor's entries only where a critic sees privileged signals."""
    from stable_baselines3.common.vec_env import VecNormalize

    from agents import privileged
    from agents.policy import frozen_stats

    stats = frozen_stats(venv) if isinstance(venv, VecNormalize) else None
    extra = privileged.find(venv)
    return stats if extra is None else privileged.actor_stats(stats, extra.n_actor)


def _checked_input(env_id: str, algo: str, hyperparams: Path | None, timesteps: int | None,
                   n_envs: int | None, max_minutes: float | None) -> tuple:  # fmt: skip
    """(env id, algorithm class, hyperparameter file, checked hyperparameters, timesteps,
    n_envs) of a run, or a ConfigError naming what is wrong."""
    from steamtemp_gym.envs import resolve_id

    try:
        env_id = resolve_id(env_id)  # the namespace may be left out
    except ValueError:
        pass  # refused below, with the valid ids
    if env_id not in steamtemp_gym.ENV_IDS:
        raise ConfigError(f"unknown env {env_id!r}; valid: {list(steamtemp_gym.ENV_IDS)}")
    cls = algo_class(algo)
    path = Path(hyperparams) if hyperparams else HYPERPARAMS / f"{algo}.yml"
    hp = read_hyperparams(path, env_id, algo)
    total = int(timesteps if timesteps is not None else hp.get("n_timesteps", 100_000))
    n_envs = int(n_envs if n_envs is not None else hp.get("n_envs", 1))
    if total < 1 or n_envs < 1:
        raise ConfigError(f"timesteps and n_envs must be >= 1, got {total} and {n_envs}")
    if max_minutes is not None and max_minutes <= 0:
        raise ConfigError(f"--max-minutes must be > 0, got {max_minutes}")
    return env_id, cls, path, hp, total, n_envs


def sb3_model(cls: Any, hp: dict[str, Any], venv: Any, seed: int,
               tensorboard: str | None, decision_s: float | None = None) -> Any:  # fmt: skip
    """The SB3 model of ``cls`` on ``venv``: the constructor's hyperparameters, the learning
    rate schedule and, where configured, SAC/TD3's Gaussian action noise: white
    (``normal``) or low-pass with time constant ``noise_tau_s`` (``lowpass``,
    agents/exploration.py; ``decision_s``: the seconds between decisions)."""
    from stable_baselines3.common.noise import NormalActionNoise

    from agents.exploration import LowPassActionNoise

    kwargs = {k: v for k, v in hp.items() if k not in SPECIAL}
    kwargs["learning_rate"] = _schedule(kwargs.get("learning_rate", 3e-4))
    policy, policy_kwargs = hp.get("policy", "MlpPolicy"), dict(hp["policy_kwargs"])
    if hp.get("privileged_critic"):
        from agents import privileged

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
            sigma, float(np.exp(-decision_s / hp["noise_tau_s"])))
    model = cls(policy, venv, seed=seed, device="cpu", verbose=0,
                policy_kwargs=policy_kwargs or None, tensorboard_log=tensorboard,
                **kwargs)  # fmt: skip
    if hp.get("residual_base") is not None:
        zero_output(model)
    return model


def zero_output(model: Any) -> None:
    """Zero the last layer of ``model``'s actor (PPO's ``action_net``, SAC's and TD3's last
    linear layer): a residual agent's deterministic action starts at 0, so training starts
    from its base controller."""
    import torch

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


def scored_policy(model: Any, venv: Any, native: Any, hp: dict[str, Any]) -> Any:
    """The policy the leaderboard would score of ``model`` as it is now: its deterministic
    action through the entry's memory, normalization (frozen at the moment), moves,
    filter, ties and action repeat (agents/policy.py)."""
    from agents.policy import AgentPolicy

    return AgentPolicy(model, native, memory=hp["env_wrapper"], obs_norm=_obs_stats(venv),
                       residual_scale=hp.get("residual_scale"),
                       residual_base=hp.get("residual_base"), max_move=hp.get("max_move"),
                       action_filter_s=hp.get("action_filter_s"),
                       tied_valves=hp.get("tied_valves"),
                       action_repeat=hp.get("action_repeat"))  # fmt: skip


def _checkpointing(model: Any, venv: Any, native: Any, hp: dict[str, Any], env_id: str,
                   reference: dict[str, float], total: int, curve: list, best: dict,
                   save_to: Path, offset: int = 0) -> Callable[[int, RunClock], None]:  # fmt: skip
    """``evaluate(steps, clock)``: validate the model as it is, add the result to ``curve``
    (with the run's CPU and wall seconds on ``clock``),
    and where it beats ``best`` (:func:`better_checkpoint`) keep it there and save the model
    to ``save_to``; ``offset``: what the run trained on before (added to ``steps``)."""
    from agents.tuning_terms import TUNING_TRAVEL_BUDGET

    def evaluate(steps: int, clock: RunClock) -> None:
        score = scored(env_id, scored_policy(model, venv, native, hp), reference)
        curve.append({"timesteps": offset + steps, "fraction": steps / total, **clock.stamp(),
                      **score})  # fmt: skip
        # within the tuned baselines' margin under the budget (agents/tuning_terms.py)
        if better_checkpoint(score, best, TUNING_TRAVEL_BUDGET):
            best.update(score, timesteps=offset + steps, obs_norm=_obs_stats(venv))
            model.save(save_to)

    return evaluate


def _progress(evaluate: Callable[[int, RunClock], None], curve: list, total: int,
              clock: RunClock, name: str, quiet: bool,
              max_minutes: float | None) -> Any:  # fmt: skip
    """The SB3 callback of a run: ``evaluate`` at every mark of :data:`EVAL_FRACTIONS` of the
    step budget ``total``, or with ``max_minutes`` (CPU minutes on ``clock``) at those of
    the time budget and at the end of whichever budget ends the run (a time stop ends the
    training), a progress line on stderr every 10 CPU seconds unless ``quiet``."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Progress(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            # with a time budget the step budget's marks would only add validations: its end
            self.marks = ([int(f * total) for f in EVAL_FRACTIONS] if max_minutes is None
                          else [total])  # fmt: skip
            # the marks still ahead (a fine-tuning starts part way into its run's budget)
            self.clock = ([] if max_minutes is None else
                          [60.0 * max_minutes * f for f in EVAL_FRACTIONS[:-1]
                           if 60.0 * max_minutes * f > clock.cpu()])  # fmt: skip
            self.last_line = 0.0

        def _on_step(self) -> bool:
            steps, wall = self.num_timesteps, clock.cpu()
            due = bool(self.marks and steps >= self.marks[0])
            due |= bool(self.clock and wall >= self.clock[0])
            while self.marks and steps >= self.marks[0]:
                self.marks.pop(0)
            while self.clock and wall >= self.clock[0]:
                self.clock.pop(0)
            if due:
                evaluate(steps, clock)
            if not quiet and wall - self.last_line > 10.0:
                self.last_line = wall
                eta = wall / max(steps, 1) * (total - steps)
                last = f", validation return {curve[-1]['return']:.1f}" if curve else ""
                print(f"[{name}] {steps:,}/{total:,} steps ({100 * steps / total:.0f} %), "
                      f"{steps / max(wall, 1e-9):,.0f} steps per CPU-s, ETA {eta / 60:.1f} "
                      f"CPU-min{last}",
                      file=sys.stderr, flush=True)  # fmt: skip
            if max_minutes is not None and wall > 60.0 * max_minutes:
                evaluate(steps, clock)
                return False
            return True

    return Progress()


def actor_parameters(model: Any) -> list:
    """The parameters of a PPO policy's actor: its own layers, its output and log std."""
    pol = model.policy
    return [*pol.mlp_extractor.policy_net.parameters(), *pol.action_net.parameters(),
            pol.log_std]  # fmt: skip


def critic_warmup(steps: int) -> Any:
    """SB3 callback holding a PPO policy's actor still for its first ``steps`` timesteps, so
    that the critic learns the values of the starting policy before any advantage moves
    the actor (a residual starts at its base, an imitation at its expert: their first
    advantages are noise around a good policy)."""
    from stable_baselines3.common.callbacks import BaseCallback

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


def _imitation(env_id: str, algo: str, cls: Any, path: Path, hp: dict[str, Any], seed: int,
               run: int | None, n_envs: int, total: int, out: Path, reference: dict,
               venv: Any, quiet: bool, max_minutes: float | None,
               tensorboard: str | None) -> dict[str, Any]:  # fmt: skip
    """A run of an imitation algorithm (agents/imitation.py) with a training run's files;
    a fine-tuned one (``FINE_TUNED``) goes on from DAgger's best checkpoint with
    PPO for ``total`` timesteps (:func:`_fine_tune`), in what is left of ``max_minutes``
    after DAgger's ``dagger_minutes``."""
    from agents import imitation

    venv.close()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    model_path, meta_path = steamtemp_paths(out, env_id, algo, run)
    revision = git_revision()
    clock = RunClock()
    log = None if quiet else (lambda m: print(m, file=sys.stderr, flush=True))
    tuned = algo in FINE_TUNED
    dagger_minutes = hp.get("dagger_minutes") if tuned else None
    if max_minutes is not None:
        dagger_minutes = min(dagger_minutes or max_minutes, max_minutes)
    model, best, curve, record, data = imitation.train(env_id, algo, hp, seed, n_envs,
                                                       reference, model_path, log,
                                                       dagger_minutes, clock)  # fmt: skip
    pairs = curve[-1]["timesteps"]
    for point in curve:
        point["phase"] = "dagger"
    if tuned:
        if max_minutes is None or clock.cpu() < 60.0 * max_minutes:
            model = _fine_tune(env_id, cls, hp, seed, n_envs, total, model_path, reference,
                               data, best, curve, quiet, max_minutes, tensorboard,
                               stem(env_id, algo, run), clock)  # fmt: skip
    meta = metadata(env_id, algo, cls, revision, path, hp, seed, run, n_envs, total, model,
                     best, clock, reference, curve)  # fmt: skip
    meta["timesteps_trained"] = pairs + (model.num_timesteps if tuned else 0)
    meta["imitation"] = record
    meta_path.write_text(json.dumps(meta, indent=1), encoding="utf-8")
    return meta


def _fine_tune(env_id: str, cls: Any, hp: dict[str, Any], seed: int, n_envs: int, total: int,
               model_path: Path, reference: dict, data: list, best: dict, curve: list,
               quiet: bool, max_minutes: float | None, tensorboard: str | None,
               name: str, clock: RunClock) -> Any:  # fmt: skip
    """PPO from DAgger's best checkpoint (saved at ``model_path``, its statistics in
    ``best``): the observations standardized as DAgger froze them, the critic learning
    alone for ``critic_warmup_steps``, the actor anchored to the expert's actions
    (``imitation.anchor``); validated as any run, the best checkpoint (DAgger's included)
    kept; ``clock``: the run's (its budget ``max_minutes`` counts DAgger's minutes).
    Returns the fine-tuned model."""
    import torch
    from stable_baselines3 import PPO

    from agents import imitation

    stats = best["obs_norm"]
    venv, native, _ = make_training_env(env_id, n_envs, seed, {**hp, "normalize": False})
    venv = imitation.frozen_normalization(venv, stats, hp.get("gamma", 0.99))
    model = sb3_model(cls, hp, venv, seed, tensorboard)
    model.policy.load_state_dict(PPO.load(model_path, device="cpu").policy.state_dict())
    with torch.no_grad():
        model.policy.log_std.fill_(hp["policy_kwargs"].get("log_std_init", 0.0))
    rl_curve: list[dict[str, Any]] = []
    evaluate = _checkpointing(model, venv, native, hp, env_id, reference, total, rl_curve,
                              best, model_path, offset=curve[-1]["timesteps"])  # fmt: skip
    callbacks = [_progress(evaluate, rl_curve, total, clock, name, quiet, max_minutes),
                 imitation.anchor(data, stats, hp.get("anchor_weight",
                                  IMITATION_DEFAULTS["anchor_weight"]),
                                  int(total * hp.get("anchor_fraction",
                                      IMITATION_DEFAULTS["anchor_fraction"])), seed)]  # fmt: skip
    if hp.get("critic_warmup_steps"):
        callbacks.append(critic_warmup(hp["critic_warmup_steps"]))
    model.learn(total_timesteps=total, callback=callbacks, progress_bar=False)
    if not rl_curve:
        evaluate(model.num_timesteps, clock)
    curve.extend({**point, "phase": "rl"} for point in rl_curve)
    venv.close()
    return model


def train(env_id: str, algo: str, hyperparams: Path | None = None, timesteps: int | None = None,
          seed: int = 0, n_envs: int | None = None, out: Path = Path("trained"),
          max_minutes: float | None = None, tensorboard: str | None = None,
          quiet: bool = False, run: int | None = None,
          default_minutes: float | None = None) -> dict[str, Any]:  # fmt: skip
    """Train one agent (agents/train.py's module docstring); returns its metadata. Input is
    checked first. ``run``: the training run's index in the file names (None: names without
    one). ``max_minutes`` None: the entry's ``max_minutes``, else ``default_minutes``."""
    env_id, cls, path, hp, total, n_envs = _checked_input(env_id, algo, hyperparams, timesteps,
                                                          n_envs, max_minutes)  # fmt: skip
    if max_minutes is None:
        max_minutes = hp.get("max_minutes", default_minutes)
    one_core()  # a run's budget is minutes of one core
    reference = reference_result(env_id)
    venv, native, price = make_training_env(env_id, n_envs, seed, hp,
                                            reference_rate=reference["travel_per_s"])  # fmt: skip
    if algo in EXPERTS:
        return _imitation(env_id, algo, cls, path, hp, seed, run, n_envs, total, out,
                          reference, venv, quiet, max_minutes, tensorboard)  # fmt: skip
    plant, repeat = native.unwrapped.plant, hp.get("action_repeat") or 1
    model = sb3_model(cls, hp, venv, seed, tensorboard, plant.dt_s * repeat)
    off_policy = getattr(model, "replay_buffer", None) is not None
    if price is not None and off_policy:
        from agents.travel_price import price_replay

        price_replay(model, price)  # charged when sampled, at the price of the moment
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    name = stem(env_id, algo, run)
    model_path, meta_path = steamtemp_paths(out, env_id, algo, run)
    revision = git_revision()  # the code this run trains with
    clock = RunClock()
    curve: list[dict[str, Any]] = []
    best: dict[str, Any] = {}
    prices: list[tuple[int, float, float]] = []
    evaluate = _checkpointing(model, venv, native, hp, env_id, reference, total, curve, best,
                              model_path)  # fmt: skip
    if hp.get("residual_base") is not None:  # zero output: the base itself (zero_output)
        evaluate(0, clock)
    callbacks = [_progress(evaluate, curve, total, clock, name, quiet, max_minutes)]
    if price is not None:
        from agents.moves import filter_gain, tie_map
        from agents.travel_price import OFF_POLICY_EVERY, price_callback, travel_probe

        filter_s = hp.get("action_filter_s")
        # the filter's gain per decision: it runs every interval on the held position
        alpha = (None if filter_s is None
                 else 1.0 - (1.0 - filter_gain(plant.dt_s, filter_s)) ** repeat)  # fmt: skip
        expand = tie_map(tuple(plant.valves), hp.get("tied_valves"))
        probe, every = None, hp.get("price_probe_every")
        if off_policy:  # always in closed loop
            every = every or OFF_POLICY_EVERY
        if every:
            def probe(k: int) -> float:
                return travel_probe(env_id, scored_policy(model, venv, native, hp), k,
                                    reference["travel_per_s"])  # fmt: skip
        callbacks.append(price_callback(price, prices, hp.get("max_move"), alpha, expand,
                                        repeat, probe, every))  # fmt: skip
    if hp.get("critic_warmup_steps"):
        callbacks.append(critic_warmup(hp["critic_warmup_steps"]))
    model.learn(total_timesteps=total, callback=callbacks, progress_bar=False)
    if not curve:  # a budget below the first mark's granularity
        evaluate(model.num_timesteps, clock)
    meta = metadata(env_id, algo, cls, revision, path, hp, seed, run, n_envs, total, model,
                     best, clock, reference, curve)  # fmt: skip
    if price is not None:
        meta["travel_price"] = price_record(prices)
    meta_path.write_text(json.dumps(meta, indent=1), encoding="utf-8")
    venv.close()
    return meta
