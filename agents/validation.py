"""The validation of a training run: the episodes every agent is validated on, the
commissioning checks every checkpoint must pass, and which validated checkpoint a run keeps
(agents/train.py's module docstring).

The validation episodes (``random`` scenario) change load and disturbances to their end, so
they never show a loop that keeps oscillating once the plant is quiet. Every checkpoint
therefore also runs the baseline tuner's commissioning checks (agents/tuning_terms.py: at
both ends of the load range, a setpoint and a heat-absorption step followed by a quiet
stretch, five noise seeds each) and is judged against the industrial reference on the same
episodes as every tuned baseline is (a trip, a limit cycle in the quiet stretch, valve
travel beyond the realism bound).
"""

from __future__ import annotations

from typing import Any

import numpy as np

import baselines
from agents.evaluation import run_batch
from agents.tuning_terms import check_breach, check_metrics

#: Seeds of the validation episodes (``random`` scenario); training uses --seed + i.
#: Sixteen: the seed-to-seed spread of a return (about 70 on the FSH) over 16 is about 18,
#: below the differences between checkpoints worth choosing between.
VALIDATION_SEED = 1_000_000
N_VALIDATION = 16


def validate(
    env_id: str, policy, n: int = N_VALIDATION, seed: int = VALIDATION_SEED
) -> dict[str, float]:
    """Mean return, IAE and valve travel of ``policy`` over the validation episodes (default
    reward), run as one batch in the native vector env by agents.evaluation.run_batch (row k
    is ``gym.make(env_id, scenario="random")`` reset with seed ``seed`` + k, bit for bit).
    ``policy``: a Policy, or a factory ``venv -> Policy``."""
    import gymnasium as gym

    venv = gym.make_vec(
        env_id, num_envs=n, vectorization_mode="vector_entry_point", scenario="random"
    )
    if not hasattr(policy, "predict"):
        policy = policy(venv)
    runs = run_batch(venv, policy, [seed + k for k in range(n)])
    venv.close()
    out = {
        key: float(np.mean([r["metrics"][key] for r in runs]))
        for key in ("return", "iae_K_s", "valve_travel")
    }
    seconds = sum(float(r["trace"]["time_s"][-1] - r["trace"]["time_s"][0]) for r in runs)
    out["travel_per_s"] = n * out["valve_travel"] / max(seconds, 1e-9)
    return out


def reference_result(env_id: str) -> dict[str, Any]:
    """The industrial reference's (``cascade_pi_ff``) :func:`validate` result on ``env_id``,
    and under ``checks`` its metrics on the commissioning checks (the unit of
    :func:`scored`'s travel ratio and the judge of its checks)."""

    def make(v):
        return baselines.make(baselines.INDUSTRIAL_REFERENCE, v)

    return {**validate(env_id, make), "checks": check_metrics(env_id, make)}


def scored(env_id: str, policy, ref: dict[str, Any]) -> dict[str, Any]:
    """:func:`validate` of ``policy`` (a Policy) with ``travel_ratio`` (its valve travel over
    the reference's ``ref``, :func:`reference_result`), and its commissioning checks: ``check``,
    what a plant engineer would reject in them ("" if nothing), and ``check_travel_ratio``,
    the largest travel ratio to the reference's over them."""
    out: dict[str, Any] = validate(env_id, policy)
    out["travel_ratio"] = out["valve_travel"] / ref["valve_travel"]
    out["check"], out["check_travel_ratio"] = check_breach(
        check_metrics(env_id, lambda venv: policy), ref["checks"]
    )
    return out


def better_checkpoint(new: dict[str, Any], best: dict[str, Any], budget: float) -> bool:
    """Whether validation result ``new`` beats ``best`` (both with ``return`` and
    ``travel_ratio``, and ``check`` where the checks ran): a checkpoint within the travel
    budget that passes its checks first, by the higher return; then one that passes its
    checks; then one within the budget, by the higher return; otherwise the lower travel."""
    if not best:
        return True

    def rank(s: dict[str, Any]) -> tuple:
        within, passed = s["travel_ratio"] <= budget, not s.get("check")
        return (within and passed, passed, within, s["return"] if within else -s["travel_ratio"])

    return rank(new) > rank(best)


__all__ = [
    "N_VALIDATION",
    "VALIDATION_SEED",
    "better_checkpoint",
    "reference_result",
    "scored",
    "validate",
]
