"""The validation of a training run: the episodes every agent is validated on, and which
validated checkpoint a run keeps (agents/train.py's module docstring).
"""

from __future__ import annotations

import numpy as np

#: Seeds of the validation episodes (``random`` scenario); training uses --seed + i.
#: Sixteen: the seed-to-seed spread of a return (about 70 on the FSH) over 16 is about 18,
#: below the differences between checkpoints worth choosing between.
VALIDATION_SEED = 1_000_000
N_VALIDATION = 16


def validate(env_id: str, policy, n: int = N_VALIDATION,
             seed: int = VALIDATION_SEED) -> dict[str, float]:  # fmt: skip
    """Mean return, IAE and valve travel of ``policy`` over the validation episodes (default
    reward), run as one batch in the native vector env by agents.evaluation.run_batch (row k
    is ``gym.make(env_id, scenario="random")`` reset with seed ``seed`` + k, bit for bit).
    ``policy``: a Policy, or a factory ``venv -> Policy``."""
    import gymnasium as gym

    from agents.evaluation import run_batch

    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point",
                        scenario="random")  # fmt: skip
    if not hasattr(policy, "predict"):
        policy = policy(venv)
    runs = run_batch(venv, policy, [seed + k for k in range(n)])
    venv.close()
    out = {key: float(np.mean([r["metrics"][key] for r in runs]))
           for key in ("return", "iae_K_s", "valve_travel")}  # fmt: skip
    seconds = sum(float(r["trace"]["time_s"][-1] - r["trace"]["time_s"][0]) for r in runs)
    out["travel_per_s"] = n * out["valve_travel"] / max(seconds, 1e-9)
    return out


def better_checkpoint(new: dict[str, float], best: dict[str, float], budget: float) -> bool:
    """Whether validation result ``new`` beats ``best`` (both with ``return`` and
    ``travel_ratio``): within the travel budget first, then the higher return; outside it,
    the lower travel."""
    if not best:
        return True
    ok_new, ok_best = new["travel_ratio"] <= budget, best["travel_ratio"] <= budget
    if ok_new != ok_best:
        return ok_new
    return new["return"] > best["return"] if ok_new else new["travel_ratio"] < best["travel_ratio"]


__all__ = ["N_VALIDATION", "VALIDATION_SEED", "better_checkpoint", "validate"]
