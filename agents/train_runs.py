"""The training runs of ``steamtemp-train --zoo``: which entries of the shipped
hyperparameter files are trained, each run's seed and arguments, and one run at nice 10
(locally or as a Ray task; agents/ray_backend.py).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import yaml

import steamtemp_gym
from agents.files import steamtemp_paths
from agents.train_config import ALGOS, HYPERPARAMS, ConfigError
from agents.training import checked_run, train
from steamtemp_gym.envs import resolve_id

ZOO = Path(__file__).with_name("zoo")
#: Run k of ``--zoo --runs K`` trains with seed ``--seed + RUN_SEED_STRIDE * k``: more than
#: any n_envs, so no two runs share a training env's seed.
RUN_SEED_STRIDE = 1000
#: Most runs per agent (run seeds stay far below agents.validation.VALIDATION_SEED).
MAX_RUNS = 100
#: A zoo run's budget (minutes of one core, its CPU time) where neither --max-minutes nor its
#: YAML entry gives one.
ZOO_MINUTES = 10.0


def entries_of(path: Path) -> list[str]:
    """Env ids with an entry in the hyperparameter file ``path`` (none if it is missing);
    ConfigError for a file that is not YAML."""
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8")) if path.exists() else {}
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError(f"--hyperparams {path}: cannot read it as YAML: {exc}") from None
    return [env_id for env_id in steamtemp_gym.ENV_IDS if isinstance(doc, dict) and env_id in doc]


def zoo_entries_of(algo: str) -> list[str]:
    """Env ids with an entry in the shipped hyperparameter file of ``algo``."""
    return entries_of(HYPERPARAMS / f"{algo}.yml")


def finished(job: dict[str, Any]) -> bool:
    """Whether the run of a :func:`zoo_jobs` job has written its files (model and
    metadata) in its output directory."""
    model, meta = steamtemp_paths(Path(job["out"]), job["env_id"], job["algo"], job["run"])
    return model.is_file() and meta.is_file()


def zoo_entries() -> list[tuple[str, str]]:
    """(env id, algo) of every entry of the shipped hyperparameter files, PPO first."""
    return [(env_id, algo) for algo in ALGOS for env_id in zoo_entries_of(algo)]


def run_seed(seed: int, run: int) -> int:
    """The seed of training run ``run`` of an agent: ``seed + RUN_SEED_STRIDE * run``."""
    return seed + RUN_SEED_STRIDE * run


def _nice() -> None:
    """Lower this process's priority to nice 10 (no further if it is already lower)."""
    os.nice(max(0, 10 - os.nice(0)))


def zoo_run(job: dict[str, Any]) -> dict[str, Any]:
    """One training run of ``--zoo`` at nice 10 (a Ray task with ``--backend ray``):
    :func:`train` with the keyword arguments ``job``; its metadata."""
    _nice()
    return train(checked_run(**job))


def zoo_jobs(
    entries: list[tuple[str, str]],
    out: Path,
    seed: int,
    runs: int | None,
    max_minutes: float | None,
    **options: Any,
) -> list[dict[str, Any]]:
    """The :func:`zoo_run` jobs of ``entries``: one per entry without ``runs`` (file names
    without a run index, ``seed``), else ``runs`` per entry (run k: :func:`run_seed`);
    each run bounded by ``max_minutes``, or if None by its entry's ``max_minutes`` or
    :data:`ZOO_MINUTES`; ``options``: further arguments of :func:`train` (those that are
    not None)."""
    ks = [None] if runs is None else list(range(runs))
    extra = {k: v for k, v in options.items() if v is not None}
    return [
        {
            "env_id": env_id,
            "algo": algo,
            "out": Path(out).resolve(),
            "run": k,
            "seed": seed if k is None else run_seed(seed, k),
            "max_minutes": max_minutes,
            "default_minutes": ZOO_MINUTES,
            **extra,
        }
        for env_id, algo in entries
        for k in ks
    ]


def zoo_env(name: str | None) -> str | None:
    """``--env`` of ``--zoo`` as a registered id (the namespace may be left out)."""
    if not name:
        return None

    try:
        return resolve_id(name)
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
