"""Agents: the evaluation loop, the leaderboard CLI, training and the trained-agent zoo.

``agents.load(env_id, algo) -> Policy`` loads a shipped trained agent from
``agents/zoo/`` (ValueError listing what is shipped otherwise): the SB3 model with its
observation pipeline (controller memory, normalization statistics; agents/policy.py),
as ``steamtemp-train`` (agents/train.py) wrote it. A trained agent's files elsewhere
(``steamtemp-train --out``, an RL Zoo run) are found by ``agents.files.find``.
"""

from __future__ import annotations

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

    Raises:
        ValueError: no such agent (listing the shipped ones for the shipped zoo).
    """
    from agents.files import steamtemp_files

    if zoo is None and (env_id, algo) not in shipped():
        raise ValueError(f"no trained agent {algo!r} shipped for {env_id!r}; shipped: {shipped()}")
    return steamtemp_files(Path(zoo) if zoo is not None else ZOO, env_id, algo).load()
