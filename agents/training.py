"""One training run of steamtemp-train: the training envs, the SB3 model
(agents/sb3_models.py), validation at every sixteenth of the budget with the best
checkpoint kept (agents/checkpoints.py), the travel price where the entry has one, and the
run's metadata (agents/run_record.py); an imitation algorithm's run is
agents/imitation_run.py's (module docstring of agents/train.py).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import steamtemp_gym
from agents import imitation_run
from agents.checkpoints import checkpointing, progress, scored_policy
from agents.files import git_revision
from agents.moves import filter_gain, tie_map
from agents.run_clock import RunClock, one_core
from agents.run_record import RunSpec, metadata, price_record
from agents.sb3_models import critic_warmup, sb3_model
from agents.train_config import EXPERTS, HYPERPARAMS, ConfigError, algo_class, read_hyperparams
from agents.travel_price import OFF_POLICY_EVERY, price_callback, price_replay, travel_probe
from agents.validation import reference_result
from agents.vec_env import make_training_env
from steamtemp_gym.envs import resolve_id


def checked_run(
    env_id: str,
    algo: str,
    hyperparams: Path | None = None,
    timesteps: int | None = None,
    seed: int = 0,
    n_envs: int | None = None,
    out: Path = Path("trained"),
    max_minutes: float | None = None,
    tensorboard: str | None = None,
    quiet: bool = False,
    run: int | None = None,
    default_minutes: float | None = None,
) -> RunSpec:
    """The run :func:`train` makes of steamtemp-train's arguments, or a ConfigError naming
    what is wrong. ``run``: the training run's index in the file names (None: names without
    one). ``max_minutes`` None: the entry's ``max_minutes``, else ``default_minutes``."""
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
    if max_minutes is None:
        max_minutes = hp.get("max_minutes", default_minutes)
    return RunSpec(
        env_id,
        algo,
        cls,
        path,
        hp,
        seed,
        run,
        n_envs,
        total,
        Path(out),
        max_minutes,
        tensorboard,
        quiet,
    )


def train(spec: RunSpec) -> dict[str, Any]:
    """Train one agent (agents/train.py's module docstring): the run ``spec``, checked input
    (:func:`checked_run` makes it of steamtemp-train's arguments); returns its metadata."""
    hp = spec.hp
    one_core()  # a run's budget is minutes of one core
    reference = reference_result(spec.env_id)
    venv, native, price = make_training_env(
        spec.env_id, spec.n_envs, spec.seed, hp, reference_rate=reference["travel_per_s"]
    )
    if spec.algo in EXPERTS:
        return imitation_run.run(spec, reference, venv)
    plant, repeat = native.unwrapped.plant, hp.get("action_repeat") or 1
    model = sb3_model(spec.cls, hp, venv, spec.seed, spec.tensorboard, plant.dt_s * repeat)
    off_policy = getattr(model, "replay_buffer", None) is not None
    if price is not None and off_policy:
        price_replay(model, price)  # charged when sampled, at the price of the moment
    model_path, meta_path = spec.paths()
    revision = git_revision()  # the code this run trains with
    clock = RunClock()
    curve: list[dict[str, Any]] = []
    best: dict[str, Any] = {}
    prices: list[tuple[int, float, float]] = []
    evaluate = checkpointing(
        model, venv, native, hp, spec.env_id, reference, spec.total, curve, best, model_path
    )
    if hp.get("residual_base") is not None:  # zero output: the base itself (zero_output)
        evaluate(0, clock)
    callbacks = [
        progress(evaluate, curve, spec.total, clock, spec.name, spec.quiet, spec.max_minutes)
    ]
    if price is not None:

        def probe(k: int) -> float:  # the policy of the moment, in closed loop
            policy = scored_policy(model, venv, native, hp)
            return travel_probe(spec.env_id, policy, k, reference["travel_per_s"])

        callbacks.append(_pricing(hp, plant, price, prices, off_policy, probe))
    if hp.get("critic_warmup_steps"):
        callbacks.append(critic_warmup(hp["critic_warmup_steps"]))
    model.learn(total_timesteps=spec.total, callback=callbacks, progress_bar=False)
    if not curve:  # a budget below the first mark's granularity
        evaluate(model.num_timesteps, clock)
    meta = metadata(spec, revision, model, best, clock, reference, curve)
    if price is not None:
        meta["travel_price"] = price_record(prices)
    meta_path.write_text(json.dumps(meta, indent=1), encoding="utf-8")
    venv.close()
    return meta


def _pricing(
    hp: dict[str, Any],
    plant: Any,
    price: Any,
    prices: list,
    off_policy: bool,
    probe: Callable[[int], float],
) -> Any:
    """The travel price's callback (agents/travel_price.py) of an entry with a price: its
    moves, filter and ties, and the closed-loop ``probe`` of the policy's travel where the
    entry asks for one (always for an off-policy agent)."""
    repeat = hp.get("action_repeat") or 1
    filter_s = hp.get("action_filter_s")
    # the filter's gain per decision: it runs every interval on the held position
    alpha = None
    if filter_s is not None:
        alpha = 1.0 - (1.0 - filter_gain(plant.dt_s, filter_s)) ** repeat
    expand = tie_map(tuple(plant.valves), hp.get("tied_valves"))
    every = hp.get("price_probe_every")
    if off_policy:  # always in closed loop
        every = every or OFF_POLICY_EVERY
    return price_callback(
        price, prices, hp.get("max_move"), alpha, expand, repeat, probe if every else None, every
    )
