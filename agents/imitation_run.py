"""A training run of an imitation algorithm (agents/imitation.py) with a training run's
files: DAgger, and for a fine-tuned one (``FINE_TUNED``) PPO from DAgger's best checkpoint
with the actor anchored to the expert.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import torch
from stable_baselines3 import PPO

from agents import imitation
from agents.checkpoints import checkpointing, progress
from agents.files import git_revision
from agents.run_clock import RunClock
from agents.run_record import RunSpec, metadata
from agents.sb3_models import critic_warmup, sb3_model
from agents.train_config import FINE_TUNED, IMITATION_DEFAULTS
from agents.vec_env import make_training_env


def run(spec: RunSpec, reference: dict, venv: Any) -> dict[str, Any]:
    """A run of an imitation algorithm (agents/imitation.py) with a training run's files;
    a fine-tuned one (``FINE_TUNED``) goes on from DAgger's best checkpoint with PPO for
    ``spec.total`` timesteps (:func:`fine_tune`), in what is left of its minutes after
    DAgger's ``dagger_minutes``. ``venv``: the training stack (closed: DAgger makes its
    own)."""
    venv.close()
    hp, max_minutes = spec.hp, spec.max_minutes
    model_path, meta_path = spec.paths()
    revision = git_revision()
    clock = RunClock()
    log = None if spec.quiet else (lambda m: print(m, file=sys.stderr, flush=True))
    tuned = spec.algo in FINE_TUNED
    dagger_minutes = hp.get("dagger_minutes") if tuned else None
    if max_minutes is not None:
        dagger_minutes = min(dagger_minutes or max_minutes, max_minutes)
    model, best, curve, record, data = imitation.train(
        spec.env_id,
        spec.algo,
        hp,
        spec.seed,
        spec.n_envs,
        reference,
        model_path,
        log,
        dagger_minutes,
        clock,
    )
    pairs = curve[-1]["timesteps"]
    for point in curve:
        point["phase"] = "dagger"
    if tuned and (max_minutes is None or clock.cpu() < 60.0 * max_minutes):
        model = fine_tune(spec, model_path, reference, data, best, curve, clock)
    meta = metadata(spec, revision, model, best, clock, reference, curve)
    meta["timesteps_trained"] = pairs + (model.num_timesteps if tuned else 0)
    meta["imitation"] = record
    meta_path.write_text(json.dumps(meta, indent=1), encoding="utf-8")
    return meta


def fine_tune(
    spec: RunSpec,
    model_path: Path,
    reference: dict,
    data: list,
    best: dict,
    curve: list,
    clock: RunClock,
) -> Any:
    """PPO from DAgger's best checkpoint (saved at ``model_path``, its statistics in
    ``best``): the observations standardized as DAgger froze them, the critic learning
    alone for ``critic_warmup_steps``, the actor anchored to the expert's actions
    (``imitation.anchor``); validated as any run, the best checkpoint (DAgger's included)
    kept; ``clock``: the run's (its budget counts DAgger's minutes). Returns the fine-tuned
    model."""
    hp, stats, total = spec.hp, best["obs_norm"], spec.total
    venv, native, _ = make_training_env(
        spec.env_id, spec.n_envs, spec.seed, {**hp, "normalize": False}
    )
    venv = imitation.frozen_normalization(venv, stats, hp.get("gamma", 0.99))
    model = sb3_model(spec.cls, hp, venv, spec.seed, spec.tensorboard)
    model.policy.load_state_dict(PPO.load(model_path, device="cpu").policy.state_dict())
    with torch.no_grad():
        model.policy.log_std.fill_(hp["policy_kwargs"].get("log_std_init", 0.0))
    rl_curve: list[dict[str, Any]] = []
    evaluate = checkpointing(
        model,
        venv,
        native,
        hp,
        spec.env_id,
        reference,
        total,
        rl_curve,
        best,
        model_path,
        offset=curve[-1]["timesteps"],
    )
    weight = hp.get("anchor_weight", IMITATION_DEFAULTS["anchor_weight"])
    fraction = hp.get("anchor_fraction", IMITATION_DEFAULTS["anchor_fraction"])
    callbacks = [
        progress(evaluate, rl_curve, total, clock, spec.name, spec.quiet, spec.max_minutes),
        imitation.anchor(data, stats, weight, int(total * fraction), spec.seed),
    ]
    if hp.get("critic_warmup_steps"):
        callbacks.append(critic_warmup(hp["critic_warmup_steps"]))
    model.learn(total_timesteps=total, callback=callbacks, progress_bar=False)
    if not rl_curve:
        evaluate(model.num_timesteps, clock)
    curve.extend({**point, "phase": "rl"} for point in rl_curve)
    venv.close()
    return model
