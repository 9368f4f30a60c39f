"""What a training run writes beside its model: the metadata ``<stem>.json`` that
``agents.load`` reads (env, hyperparameters, memory, normalization, action form) and that
records how the run went (seed, decisions, CPU and wall time, the validation curve, the
travel price's course, what a privileged critic saw).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import baselines
import steamtemp_gym
from agents import privileged
from agents.files import steamtemp_paths, stem
from agents.run_clock import RunClock
from agents.train_config import HYPERPARAMS
from agents.tuning_terms import TUNING_TRAVEL_BUDGET
from agents.validation import N_VALIDATION, VALIDATION_SEED
from steamtemp_gym import plants


@dataclass(frozen=True)
class RunSpec:
    """A training run's input, checked (agents/training.py): the env, the algorithm and
    its SB3 class, the hyperparameter file and its entry read from it, the seed, the run's
    index in the file names (None: names without one), the envs, the decisions and minutes
    of one core it may train for, where its files go, its TensorBoard log and whether it
    reports progress."""

    env_id: str
    algo: str
    cls: Any
    path: Path
    hp: dict[str, Any]
    seed: int
    run: int | None
    n_envs: int
    total: int
    out: Path
    max_minutes: float | None
    tensorboard: str | None
    quiet: bool

    @property
    def name(self) -> str:
        """The stem of the run's files."""
        return stem(self.env_id, self.algo, self.run)

    def paths(self) -> tuple[Path, Path]:
        """The run's model ``.zip`` and metadata ``.json`` (made: their directory)."""
        Path(self.out).mkdir(parents=True, exist_ok=True)
        return steamtemp_paths(self.out, self.env_id, self.algo, self.run)


def shown_path(path: Path) -> str:
    """``path`` as recorded in the metadata: relative to the project for a shipped file (no
    machine's directory in the zoo's metadata), as given otherwise."""
    try:
        return Path(path).resolve().relative_to(HYPERPARAMS.parent.parent).as_posix()
    except ValueError:
        return str(path)


def metadata(
    spec: RunSpec,
    revision: str,
    model: Any,
    best: dict[str, Any],
    clock: RunClock,
    reference: dict[str, float],
    curve: list,
) -> dict[str, Any]:
    """The run's ``<stem>.json``: everything ``agents.load`` needs and how the run went."""
    env_id, hp = spec.env_id, spec.hp
    return {
        "env_id": env_id,
        "algo": spec.algo,
        "sb3_class": spec.cls.__name__,
        "package_version": steamtemp_gym.__version__,
        "git_revision": revision,
        "hyperparams_file": shown_path(spec.path),
        "hyperparameters": json.loads(json.dumps(hp, default=str)),
        "seed": spec.seed,
        "run": spec.run,
        "n_envs": spec.n_envs,
        "timesteps_budget": spec.total,
        "timesteps_trained": model.num_timesteps,
        "timesteps_of_best": best["timesteps"],
        "wall_time_s": clock.wall(),
        "cpu_time_s": clock.cpu(),
        "validation": {
            "scenario": "random",
            "seeds": [VALIDATION_SEED + k for k in range(N_VALIDATION)],
            "best": {
                k: best[k]
                for k in (
                    "return",
                    "iae_K_s",
                    "valve_travel",
                    "travel_ratio",
                    "check",
                    "check_travel_ratio",
                )
            },
            "reference": {
                "policy": baselines.INDUSTRIAL_REFERENCE,
                **{k: v for k, v in reference.items() if k != "checks"},
            },
            "travel_budget": TUNING_TRAVEL_BUDGET,
            "curve": curve,
        },
        "normalization": best["obs_norm"],
        "memory": hp["env_wrapper"],
        "residual_scale": hp.get("residual_scale"),
        "residual_base": hp.get("residual_base"),
        "max_move": hp.get("max_move"),
        "action_filter_s": hp.get("action_filter_s"),
        "tied_valves": hp.get("tied_valves"),
        "train_reward": hp.get("train_reward"),
        "action_repeat": hp.get("action_repeat"),
        "privileged_critic": privileged_record(env_id, hp),
    }


def privileged_record(env_id: str, hp: dict[str, Any]) -> dict[str, Any] | None:
    """What a critic trained on privileged signals saw besides the agent's observation (the
    shipped actor never sees it), None for an ordinary critic."""
    if not hp.get("privileged_critic"):
        return None

    names = privileged.signal_names(plants.make(env_id))
    return {"signals": names, "look_ahead_s": list(privileged.LOOK_AHEAD_S)}


def price_record(prices: list[tuple[int, float, float, float]]) -> dict[str, Any]:
    """The travel price's course for the metadata: the first rollout's travel over the
    reference's (the untrained policy with its exploration, before any update), the last
    price, and at most 100 (timesteps, the policy's travel ratio, the rollout's, price)
    points."""
    keep = prices[:: max(1, len(prices) // 100)]
    return {
        "exploration_travel_ratio": prices[0][2] if prices else None,
        "final_price": prices[-1][3] if prices else None,
        "course": [list(p) for p in keep],
    }
