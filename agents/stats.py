"""Aggregate statistics of the leaderboard, as RL benchmarks report them.

The method is that of Agarwal, Schwarzer, Castro, Courville and Bellemare, "Deep
Reinforcement Learning at the Edge of the Statistical Precipice", NeurIPS 2021 (the
``rliable`` library): a policy's score on a plant is a matrix of runs (seeds) by tasks
(scenarios); it is summarized by the mean and the interquartile mean (IQM: the mean of
the middle 50 % of all runs x tasks, :func:`iqm`) with 95 % confidence intervals from a
*stratified* bootstrap (:func:`stratified_bootstrap_ci`: runs resampled with replacement
within each task, the task set fixed, percentile interval); the probability of improvement
``P(X > Y)`` (:func:`probability_of_improvement`: the Mann-Whitney statistic per task,
averaged over tasks) and performance profiles (:func:`performance_profile`: the fraction
of runs above a threshold, averaged over tasks).

Tasks may have different run counts (a failed episode leaves its seed out), so scores
are lists of 1-d arrays, one per task.

A trained agent with several independent *training* runs has, per training run, such a
list (episodes = evaluation seeds, per task). Its CI comes from a two-level bootstrap
(:func:`training_run_bootstrap_ci`): each replicate draws as many training runs as there
are, with replacement, and within each drawn run its episodes with replacement, task by
task; the statistic is taken over every drawn episode. It thus carries the spread between
training runs, which resampling the pooled episodes would hide (Agarwal et al. 2021 take
the training run as the unit that is resampled). With one training run it is
:func:`stratified_bootstrap_ci` of that run, draw for draw.

``rliable`` itself is not a dependency (it pulls pandas, statsmodels, arch and seaborn);
tests/test_stats.py checks this implementation on hand-computable cases and against the
plain (unstratified) percentile bootstrap.

Normalized score (:func:`normalize`): per task (plant x scenario), 0 is the mean episode
return over seeds of ``cascade_pi_ff``, the cascade PI as a well-commissioned unit runs it
(load-scheduled gains, load feed-forward), and 1 is that of the ``oracle``, the
clairvoyant NMPC on the true plant (agents/oracle.py), which no causal controller can beat
up to its optimizer's suboptimality. A policy's score is the share of the achievable
improvement over the industrial reference that it realizes; negative when it is worse
than the reference. Where the oracle's margin is small (a disturbance that saturates the
valves whatever the controller does), the scale is held at :data:`MIN_SPAN` of the
reference's cost (:func:`score_span`): the division is always by a per-task constant of
means over seeds, never by a near-zero gap. (The previous scales, 0 = ``cascade_pi`` and
1 = zero cost, and before that 0 = the frozen valve, are recorded in
docs/leaderboard_outputs.md.)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from scipy.stats import trim_mean

from steamtemp_gym.metrics import limit_cycles

Scores = Sequence[np.ndarray]  # one 1-d array of run scores per task
#: Bootstrap replicates (rliable's examples use 2,000 to 50,000; 2,000 keeps the percentile
#: interval's Monte-Carlo error near 0.01 of its width).
N_BOOTSTRAP = 2000
CONFIDENCE = 0.95


def iqm(x: np.ndarray, axis: int | None = None) -> np.ndarray | float:
    """Interquartile mean: the mean after cutting the lowest and highest 25 % of values."""
    return trim_mean(x, 0.25, axis=axis)


def mean(x: np.ndarray, axis: int | None = None) -> np.ndarray | float:
    """Plain mean (the same signature as :func:`iqm`)."""
    return np.mean(x, axis=axis)


AGGREGATES: dict[str, Callable] = {"mean": mean, "iqm": iqm}


def _tasks(scores: Scores) -> list[np.ndarray]:
    tasks = [np.asarray(s, dtype=float).ravel() for s in scores]
    tasks = [t for t in tasks if t.size]
    if not tasks:
        raise ValueError("no scores: every task is empty")
    if not all(np.isfinite(t).all() for t in tasks):
        raise ValueError("scores must be finite")
    return tasks


def stratified_bootstrap_ci(
    scores: Scores,
    statistic: Callable = iqm,
    n_boot: int = N_BOOTSTRAP,
    confidence: float = CONFIDENCE,
    seed: int = 0,
) -> tuple[float, float, float]:
    """Point estimate and percentile confidence interval of ``statistic`` over all runs.

    Each replicate draws, for every task independently, as many runs as it has, with
    replacement (the stratified bootstrap of rliable's ``StratifiedBootstrap``), and
    applies ``statistic`` to all drawn runs together.

    Returns:
        ``(point, lower, upper)``.
    """
    tasks = _tasks(scores)
    rng = np.random.default_rng(seed)
    drawn = [t[rng.integers(0, t.size, (n_boot, t.size))] for t in tasks]
    reps = statistic(np.concatenate(drawn, axis=1), axis=1)
    q = 100 * (1 - confidence) / 2
    lo, hi = np.percentile(reps, [q, 100 - q])
    return float(statistic(np.concatenate(tasks))), float(lo), float(hi)


def training_run_bootstrap_ci(
    runs: Sequence[Scores],
    statistic: Callable = iqm,
    n_boot: int = N_BOOTSTRAP,
    confidence: float = CONFIDENCE,
    seed: int = 0,
) -> tuple[float, float, float]:
    """Point estimate and percentile confidence interval of ``statistic`` over the episodes
    of several training runs, resampling the runs and, within each, its episodes.

    Args:
        runs: Per training run, its scores per task (the same tasks, in the same order; a
            task may be empty in a run).

    Each replicate draws ``len(runs)`` runs with replacement; a run drawn in a slot
    contributes, for every task, as many of its episodes on that task as it has, drawn
    with replacement (module docstring). One run: :func:`stratified_bootstrap_ci`.

    Returns:
        ``(point, lower, upper)``; the point is ``statistic`` of every episode of every run.

    Raises:
        ValueError: no run, runs with different task counts, a run without any score,
            a non-finite score.
    """
    if len(runs) == 0:
        raise ValueError("no training runs")
    if len({len(r) for r in runs}) > 1:
        raise ValueError(f"the training runs have different task counts: {[len(r) for r in runs]}")
    if len(runs) == 1:
        return stratified_bootstrap_ci(runs[0], statistic, n_boot, confidence, seed)
    cells = [[np.asarray(s, dtype=float).ravel() for s in r] for r in runs]
    for k, r in enumerate(cells):
        try:
            _tasks(r)
        except ValueError as exc:
            raise ValueError(f"training run {k}: {exc}") from None
    n_runs = len(cells)
    rng = np.random.default_rng(seed)
    pick = rng.integers(0, n_runs, (n_boot, n_runs))  # the run in each slot of a replicate
    rows, slots = np.arange(n_boot)[:, None], np.arange(n_runs)[None, :]
    per_task = []  # per task: per run, its drawn episodes in every (replicate, slot)
    for t in range(len(cells[0])):
        per_task.append(
            [c[t][rng.integers(0, c[t].size, (n_boot, n_runs, c[t].size))] for c in cells]
        )
    if all(len({d.shape for d in drawn}) == 1 for drawn in per_task):  # equal sizes per task
        parts = [np.stack(drawn)[pick, rows, slots].reshape(n_boot, -1) for drawn in per_task]
        reps = statistic(np.concatenate(parts, axis=1), axis=1)
    else:
        reps = np.array(
            [
                statistic(
                    np.concatenate(
                        [drawn[pick[b, j]][b, j] for drawn in per_task for j in range(n_runs)]
                    )
                )
                for b in range(n_boot)
            ]
        )
    q = 100 * (1 - confidence) / 2
    lo, hi = np.percentile(reps, [q, 100 - q])
    return float(statistic(np.concatenate([t for r in cells for t in r]))), float(lo), float(hi)


def per_run(runs: Sequence[Scores], statistic: Callable = iqm) -> list[float]:
    """``statistic`` of each training run's scores over all its tasks."""
    return [float(statistic(np.concatenate(_tasks(r)))) for r in runs]


def percentile_bootstrap_ci(
    x: np.ndarray,
    statistic: Callable = iqm,
    n_boot: int = N_BOOTSTRAP,
    confidence: float = CONFIDENCE,
    seed: int = 0,
) -> tuple[float, float, float]:
    """The plain (unstratified) percentile bootstrap of all values pooled; a reference for
    tests (with a single task it draws the same replicates as the stratified one)."""
    return stratified_bootstrap_ci([np.ravel(x)], statistic, n_boot, confidence, seed)


def _prob_greater(x: np.ndarray, y: np.ndarray) -> float:
    """Mann-Whitney ``P(X > Y) + P(X = Y) / 2`` of two samples."""
    d = x[:, None] - y[None, :]
    return float(np.mean((d > 0) + 0.5 * (d == 0)))


def probability_of_improvement(
    x: Scores,
    y: Scores,
    n_boot: int = N_BOOTSTRAP,
    confidence: float = CONFIDENCE,
    seed: int = 0,
) -> tuple[float, float, float]:
    """``P(X > Y)``: for each task the probability that a run of X scores higher than a run
    of Y (ties count half), averaged over tasks; stratified-bootstrap percentile interval
    (runs of X and of Y resampled within each task).

    Args:
        x, y: Per-task scores of the two policies, tasks in the same order.

    Returns:
        ``(point, lower, upper)``.
    """
    if len(x) != len(y):
        raise ValueError(f"x has {len(x)} tasks, y has {len(y)}")
    pairs = [
        (np.asarray(a, float).ravel(), np.asarray(b, float).ravel())
        for a, b in zip(x, y, strict=True)
    ]
    pairs = [(a, b) for a, b in pairs if a.size and b.size]
    if not pairs:
        raise ValueError("no task has runs of both policies")
    point = float(np.mean([_prob_greater(a, b) for a, b in pairs]))
    rng = np.random.default_rng(seed)
    reps = np.zeros(n_boot)
    for a, b in pairs:
        ra = a[rng.integers(0, a.size, (n_boot, a.size))]
        rb = b[rng.integers(0, b.size, (n_boot, b.size))]
        d = ra[:, :, None] - rb[:, None, :]
        reps += np.mean((d > 0) + 0.5 * (d == 0), axis=(1, 2))
    reps /= len(pairs)
    q = 100 * (1 - confidence) / 2
    lo, hi = np.percentile(reps, [q, 100 - q])
    return point, float(lo), float(hi)


def performance_profile(scores: Scores, taus: np.ndarray) -> np.ndarray:
    """Fraction of runs scoring above each ``tau``, averaged over tasks (rliable's
    score distribution), shape ``taus.shape``."""
    tasks = _tasks(scores)
    taus = np.asarray(taus, dtype=float)
    return np.mean(
        [np.mean(t[:, None] > taus.ravel()[None, :], axis=0) for t in tasks], axis=0
    ).reshape(taus.shape)


#: The valve-travel budget: a policy is admissible on a plant when its mean valve travel there
#: is at most this multiple of the industrial reference's (cascade_pi_ff) and it never trips.
TRAVEL_BUDGET = 2.0

#: The actuator-realism bound: on any one episode a baseline's valve travel stays within this
#: multiple of the industrial reference's on the same episode (the registry-wide realism test
#: and the baseline tuner's minimum-load check, :func:`realism_breach`).
REALISM_TRAVEL_MAX = 3.0


def realism_breach(m: dict[str, Any], ref: dict[str, Any]) -> str | None:
    """What a plant engineer would reject in one episode, against the industrial reference's
    metrics ``ref`` on the same episode, or None: a trip, valve travel above
    :data:`REALISM_TRAVEL_MAX` times the reference's, or a limit cycle in the quiet stretch
    (:func:`steamtemp_gym.metrics.limit_cycles`). ``m`` and ``ref`` are the metrics of
    :func:`agents.evaluation.run_episode`."""
    if m["tripped"]:
        return "tripped"
    travel, ref_travel = float(m["valve_travel"]), float(ref["valve_travel"])
    if travel > REALISM_TRAVEL_MAX * ref_travel:
        ratio = f"{travel / ref_travel:.2f}x" if ref_travel > 0 else "infinitely"
        return f"travel {travel:.2f} = {ratio} the reference's {ref_travel:.2f}"
    p2p, ref_p2p = (
        math.nan if x.get("quiet_p2p_K") is None else float(x["quiet_p2p_K"]) for x in (m, ref)
    )
    if limit_cycles(p2p, ref_p2p):
        return f"quiet p2p {p2p:.2f} K against the reference's {ref_p2p:.2f} K"
    return None


#: Smallest scale of the normalized score, as a fraction of the reference's cost |R0|.
MIN_SPAN = 0.05


def score_span(zero: float, one: float) -> float:
    """The normalized score's scale of a task: ``one - zero``, at least ``MIN_SPAN |zero|``."""
    if not (np.isfinite(zero) and np.isfinite(one)):
        raise ValueError(f"score ends must be finite, got {zero!r}, {one!r}")
    return float(max(one - zero, MIN_SPAN * abs(zero), 1e-9))


def normalize(value: np.ndarray, zero: float, one: float) -> np.ndarray:
    """``(value - zero) / score_span(zero, one)``: 0 at ``zero``, 1 at ``one``."""
    return (np.asarray(value, dtype=float) - zero) / score_span(zero, one)


def ranks(values: dict[str, float]) -> dict[str, int]:
    """Competition ranks (1 = highest value; equal values share a rank)."""
    order = sorted(values, key=lambda k: -values[k])
    out: dict[str, int] = {}
    for i, k in enumerate(order):
        out[k] = out[order[i - 1]] if i and values[k] == values[order[i - 1]] else i + 1
    return out
