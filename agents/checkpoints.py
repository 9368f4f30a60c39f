"""Validation during a training run: the policy the leaderboard would score of the model as
it is, its validation at the marks of the run's budget with the best checkpoint kept, and
the SB3 callback that validates, reports progress and ends the run at its budget.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecNormalize

from agents import privileged
from agents.policy import AgentPolicy, frozen_stats
from agents.run_clock import RunClock
from agents.tuning_terms import TUNING_TRAVEL_BUDGET
from agents.validation import better_checkpoint, scored

#: Where in the budget the agent is validated (and the best kept): every sixteenth.
EVAL_FRACTIONS = tuple(k / 16 for k in range(1, 17))


def obs_stats(venv: Any) -> dict[str, Any] | None:
    """The frozen observation statistics of the training stack's VecNormalize (None
    without one), of the actor's entries only where a critic sees privileged signals."""
    stats = frozen_stats(venv) if isinstance(venv, VecNormalize) else None
    extra = privileged.find(venv)
    return stats if extra is None else privileged.actor_stats(stats, extra.n_actor)


def scored_policy(model: Any, venv: Any, native: Any, hp: dict[str, Any]) -> Any:
    """The policy the leaderboard would score of ``model`` as it is now: its deterministic
    action through the entry's memory, normalization (frozen at the moment), moves,
    filter, ties and action repeat (agents/policy.py)."""
    return AgentPolicy(
        model,
        native,
        memory=hp["env_wrapper"],
        obs_norm=obs_stats(venv),
        residual_scale=hp.get("residual_scale"),
        residual_base=hp.get("residual_base"),
        max_move=hp.get("max_move"),
        action_filter_s=hp.get("action_filter_s"),
        tied_valves=hp.get("tied_valves"),
        action_repeat=hp.get("action_repeat"),
    )


def checkpointing(
    model: Any,
    venv: Any,
    native: Any,
    hp: dict[str, Any],
    env_id: str,
    reference: dict[str, float],
    total: int,
    curve: list,
    best: dict,
    save_to: Path,
    offset: int = 0,
) -> Callable[[int, RunClock], None]:
    """``evaluate(steps, clock)``: validate the model as it is, add the result to ``curve``
    (with the run's CPU and wall seconds on ``clock``),
    and where it beats ``best`` (:func:`better_checkpoint`) keep it there and save the model
    to ``save_to``; ``offset``: what the run trained on before (added to ``steps``)."""

    def evaluate(steps: int, clock: RunClock) -> None:
        score = scored(env_id, scored_policy(model, venv, native, hp), reference)
        curve.append(
            {"timesteps": offset + steps, "fraction": steps / total, **clock.stamp(), **score}
        )
        # within the tuned baselines' margin under the budget (agents/tuning_terms.py)
        if better_checkpoint(score, best, TUNING_TRAVEL_BUDGET):
            best.update(score, timesteps=offset + steps, obs_norm=obs_stats(venv))
            model.save(save_to)

    return evaluate


def progress(
    evaluate: Callable[[int, RunClock], None],
    curve: list,
    total: int,
    clock: RunClock,
    name: str,
    quiet: bool,
    max_minutes: float | None,
) -> Any:
    """The SB3 callback of a run: ``evaluate`` at every mark of :data:`EVAL_FRACTIONS` of the
    step budget ``total``, or with ``max_minutes`` (CPU minutes on ``clock``) at those of
    the time budget and at the end of whichever budget ends the run (a time stop ends the
    training), a progress line on stderr every 10 CPU seconds unless ``quiet``."""

    class Progress(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            # with a time budget the step budget's marks would only add validations: its end
            self.marks = (
                [int(f * total) for f in EVAL_FRACTIONS] if max_minutes is None else [total]
            )
            # the marks still ahead (a fine-tuning starts part way into its run's budget)
            self.clock = (
                []
                if max_minutes is None
                else [
                    60.0 * max_minutes * f
                    for f in EVAL_FRACTIONS[:-1]
                    if 60.0 * max_minutes * f > clock.cpu()
                ]
            )
            self.last_line = 0.0

        def _on_step(self) -> bool:
            steps, wall = self.num_timesteps, clock.cpu()
            due = bool(self.marks and steps >= self.marks[0])
            due |= bool(self.clock and wall >= self.clock[0])
            while self.marks and steps >= self.marks[0]:
                self.marks.pop(0)
            while self.clock and wall >= self.clock[0]:
                self.clock.pop(0)
            if due:
                evaluate(steps, clock)
            if not quiet and wall - self.last_line > 10.0:
                self.last_line = wall
                eta = wall / max(steps, 1) * (total - steps)
                last = f", validation return {curve[-1]['return']:.1f}" if curve else ""
                print(
                    f"[{name}] {steps:,}/{total:,} steps ({100 * steps / total:.0f} %), "
                    f"{steps / max(wall, 1e-9):,.0f} steps per CPU-s, ETA {eta / 60:.1f} "
                    f"CPU-min{last}",
                    file=sys.stderr,
                    flush=True,
                )
            if max_minutes is not None and wall > 60.0 * max_minutes:
                evaluate(steps, clock)
                return False
            return True

    return Progress()
