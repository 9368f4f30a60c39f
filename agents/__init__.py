"""Agents: the evaluation loop, the leaderboard CLI, training and the trained-agent zoo.

``agents.load(env_id, algo) -> Policy`` loads a shipped trained agent from
``agents/zoo/`` (ValueError listing what is shipped otherwise): the SB3 model with its
observation pipeline (controller memory, normalization statistics; agents/policy.py),
as ``steamtemp-train`` (agents/train.py) wrote it.
"""

from __future__ import annotations

import json
from pathlib import Path

ZOO = Path(__file__).with_name("zoo")


def shipped() -> list[tuple[str, str]]:
    """(env_id, algo) pairs of the shipped trained agents (a model .zip with its .json)."""
    out = []
    for f in sorted(ZOO.glob("*.zip")) if ZOO.exists() else []:
        if f.with_suffix(".json").exists():
            env, algo = f.stem.rsplit("__", 1)
            out.append((env.replace("__", "/"), algo))
    return out


def load(env_id: str, algo: str, zoo: Path | str | None = None):
    """A trained agent as a Policy: ``predict`` takes the env's raw observation.

    Args:
        env_id: Registered id.
        algo: Algorithm name of the file (``ppo``, ``sac``, ``td3``, ``ppo_residual``,
            ``recurrentppo``, ``sac_caps``).
        zoo: Directory holding ``<env>__<algo>.zip`` and ``.json`` (default: the shipped zoo).
    """
    directory = Path(zoo) if zoo is not None else ZOO
    stem = directory / f"{env_id.replace('/', '__')}__{algo}"
    if zoo is None and (env_id, algo) not in shipped():
        raise ValueError(f"no trained agent {algo!r} shipped for {env_id!r}; shipped: {shipped()}")
    if not (stem.with_suffix(".zip").exists() and stem.with_suffix(".json").exists()):
        raise ValueError(f"no trained agent {stem}.zip/.json")
    import gymnasium as gym

    from agents.policy import AgentPolicy
    from agents.train import model_class

    meta = json.loads(stem.with_suffix(".json").read_text(encoding="utf-8"))
    model = model_class(meta["sb3_class"]).load(stem.with_suffix(".zip"), device="cpu")
    return AgentPolicy(
        model,
        gym.make(env_id),
        memory=meta["memory"],
        obs_norm=meta["normalization"],
        residual_scale=meta["residual_scale"],
    )
