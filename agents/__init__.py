"""Agents: the evaluation loop, the leaderboard CLI and the trained-agent zoo.

``agents.load(env_id, algo) -> Policy`` loads a shipped trained agent from
``agents/zoo/`` (ValueError listing what is shipped otherwise).
"""

from __future__ import annotations

from pathlib import Path

ZOO = Path(__file__).with_name("zoo")


def shipped() -> list[tuple[str, str]]:
    """(env_id, algo) pairs of the shipped trained agents."""
    out = []
    for f in sorted(ZOO.glob("*.zip")) if ZOO.exists() else []:
        env, algo = f.stem.rsplit("__", 1)
        out.append((env.replace("__", "/"), algo))
    return out


def load(env_id: str, algo: str):
    """A shipped trained agent as a Policy (SB3 model; predict has the Policy signature)."""
    if (env_id, algo) not in shipped():
        raise ValueError(f"no trained agent {algo!r} shipped for {env_id!r}; shipped: {shipped()}")
    import stable_baselines3 as sb3

    cls = getattr(sb3, algo.upper())
    model = cls.load(ZOO / f"{env_id.replace('/', '__')}__{algo}.zip", device="cpu")
    model.reset = lambda: None  # SB3 policies here are stateless
    return model
