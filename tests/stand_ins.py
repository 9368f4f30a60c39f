"""Stand-ins the agent tests share."""

from __future__ import annotations

import numpy as np


class Model:
    """A stand-in model: a fixed pseudo-random action sequence, whatever it observes, for
    ``n_rows`` rows at a time; ``calls`` counts its decisions."""

    def __init__(self, n_act: int, n_rows: int, seed: int = 0) -> None:
        self.rng = np.random.default_rng(seed)
        self.shape = (n_rows, n_act)
        self.calls = 0

    def predict(self, x, deterministic=True):
        assert len(x) == self.shape[0]
        self.calls += 1
        return self.rng.uniform(-1.5, 1.5, self.shape).astype(np.float32), None


def ppo_yaml(tmp_path, env_id: str, n_steps: int, **extra):
    """An RL-Zoo YAML file of a tiny PPO on ``env_id`` (``n_steps`` per rollout and batch,
    one epoch, 8-unit nets) with the entries ``extra``; its path."""
    import yaml

    hp = {
        "n_envs": 2,
        "policy": "MlpPolicy",
        "normalize": "dict(norm_obs=True)",
        "n_steps": n_steps,
        "batch_size": n_steps,
        "n_epochs": 1,
        "policy_kwargs": "dict(net_arch=dict(pi=[8], vf=[8]))",
        **extra,
    }
    path = tmp_path / "ppo.yml"
    path.write_text(yaml.safe_dump({env_id: hp}))
    return path


def refused_entry(tmp_path, env_id: str, algo: str, entry: dict, match: str) -> None:
    """Assert that reading the RL-Zoo entry ``{"policy": "MlpPolicy", **entry}`` of
    ``env_id`` for ``algo`` raises a ConfigError matching ``match``."""
    import pytest
    import yaml

    from agents import train_config

    path = tmp_path / "refused.yml"
    path.write_text(yaml.safe_dump({env_id: {"policy": "MlpPolicy", **entry}}))
    with pytest.raises(train_config.ConfigError, match=match):
        train_config.read_hyperparams(path, env_id, algo)
