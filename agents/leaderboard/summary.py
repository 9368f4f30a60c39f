"""leaderboard.json's summary from the episode rows.

The statistics (agents/stats.py) per plant and policy, over scenario x seed: the mean and
IQM of the normalized score (0 = the industrial reference ``cascade_pi_ff``'s mean return
on that scenario, 1 = the clairvoyant ``oracle``'s; agents/stats.py ``normalize``) and of
the return, with 95 % stratified-bootstrap CIs; the probability of improvement over
``cascade_pi_ff``; the rank per plant (by the IQM of the normalized score; the references
``oracle`` and ``frozen_valve`` are listed, never ranked; the admissible policies first) and
overall (:data:`ORDER_RULE`). A trained agent scored over several training runs (policy names
``sb3:<algo>@run<k>``, agents/specs.py) is one policy, ``sb3:<algo>``, over training run x
scenario x seed: its normalized score's and return's CIs resample the training runs and,
within each, the episodes (agents/stats.py ``training_run_bootstrap_ci``), and each
statistic also gives its value per run and their range. The engineering metrics are means over
scenario x seed of the episodes where they apply (a metric that does not apply, e.g.
settling time without a setpoint step, is left out, never NaN; ``max_abs_dev_K`` is left
out of an episode with a setpoint step, where it measures the step). Each plant's
``robustness`` entry summarizes the model-mismatch rows (agents/leaderboard/mismatch.py),
which take no part in the scores. The format is
docs/leaderboard_schema.json, described in docs/leaderboard_outputs.md.
"""

from __future__ import annotations

from collections import defaultdict
from typing import Any

import numpy as np

import baselines
from agents import specs, stats
from agents.leaderboard import mismatch

#: Version of leaderboard.json's format (docs/leaderboard_schema.json).
SCHEMA_VERSION = 9
#: The 0 of the normalized score: the cascade as a commissioned unit runs it.
ZERO = specs.ZERO
#: The 1: the clairvoyant NMPC on the true plant (agents/oracle.py).
ONE = specs.ONE
#: What the 1 is, by the oracle's engine (agents/oracle.py: ENGINES; every output of the
#: leaderboard says which).
ONE_LABELS = {
    "optimum": "the clairvoyant optimum of each episode on the true plant, certified "
    "(agents/optimum)",
    "cem": "a receding-horizon CEM search on the true plant (--oracle cem): a lower bound of "
    "the clairvoyant optimum",
}
#: Policies listed and plotted but never ranked (not admissible controllers).
REFERENCES = specs.REFERENCES
REFERENCE = specs.FROZEN_VALVE
#: The policy the probability of improvement compares against.
VERSUS = ZERO
TABLE_METRICS = (
    "iae_K_s",
    "max_abs_dev_K",
    "time_outside_5K_s",
    "overshoot_pct",
    "settling_time_s",
    "spray_used_kg",
    "valve_travel",
    "valve_reversals",
    "quiet_p2p_K",
    "return",
)
SUMMARY_METRICS = (
    "iae_K_s",
    "max_abs_dev_K",
    "time_outside_5K_s",
    "time_outside_8K_s",
    "spray_used_kg",
    "valve_travel",
    "valve_reversals",
    "return",
)


def _applicable(m: dict[str, Any]) -> dict[str, float]:
    """The metrics of one episode that apply to it (finite, not a step's own size)."""
    out = {k: float(v) for k, v in m.items() if v is not None and np.isfinite(v)}
    if "overshoot_pct" in out:
        out.pop("max_abs_dev_K", None)
    return out


def _means(ms: list[dict[str, float]], keys) -> dict[str, float]:
    out = {}
    for k in keys:
        v = [m[k] for m in ms if k in m]
        if v:
            out[k] = float(np.mean(v))
    return out


def _estimate(
    tasks: list[np.ndarray],
    by_run: list[list[np.ndarray]] | None = None,
) -> dict[str, Any]:
    """Mean and IQM with CIs over ``tasks`` (scores per task); with ``by_run`` (per training
    run, its scores per task; several runs) the CIs resample the runs too and each
    statistic gets ``per_run`` and ``run_range``."""
    out: dict[str, Any] = {}
    for name, f in stats.AGGREGATES.items():
        if by_run is None:
            point, lo, hi = stats.stratified_bootstrap_ci(tasks, f)
            out[name] = {"value": point, "ci95": [lo, hi]}
        else:
            point, lo, hi = stats.training_run_bootstrap_ci(by_run, f)
            each = stats.per_run(by_run, f)
            out[name] = {
                "value": point,
                "ci95": [lo, hi],
                "per_run": each,
                "run_range": [min(each), max(each)],
            }
    out["tasks"] = len(tasks)
    out["runs"] = int(sum(len(t) for t in tasks))
    return out


def agent_names(policies: list[str]) -> list[str]:
    """The policies a summary lists for the names that ran: one per trained agent scored
    over several training runs (specs.split_run), in order of first appearance."""
    return list(dict.fromkeys(specs.split_run(p)[0] for p in policies))


def _by_run(
    values: dict[str, np.ndarray],
    runs: dict[str, np.ndarray],
    ks: list[int],
) -> list[list[np.ndarray]] | None:
    """Per training run in ``ks`` with values, its part of each task's ``values`` (``runs``:
    the run of each value); None for fewer than two such runs."""
    parts = [[v[runs[sc] == k] for sc, v in values.items()] for k in ks]
    parts = [p for p in parts if any(v.size for v in p)]
    return parts if len(parts) > 1 else None


#: Breaches listed per policy and plant in the summary's ``realism`` entry.
REALISM_LISTED = 3


def _realism(rows: list[dict]) -> dict[tuple[str, str], dict[str, Any]]:
    """Per (env, policy): the episodes compared with the industrial reference's on the same
    scenario and seed, how many of them a plant engineer would reject
    (:func:`agents.stats.realism_breach`: a trip, travel above 3x the reference's, a limit
    cycle in the quiet stretch) and the first :data:`REALISM_LISTED` of those."""
    ref = {
        (r["env"], r["scenario"], r["seed"]): r["metrics"]
        for r in rows
        if r["policy"] == ZERO and not r.get("error")
    }
    out: dict[tuple[str, str], dict[str, Any]] = {}
    for r in rows:
        name = specs.split_run(r["policy"])[0]
        m0 = ref.get((r["env"], r["scenario"], r["seed"]))
        if r.get("error") or m0 is None or name in (ZERO, *REFERENCES):
            continue
        e = out.setdefault((r["env"], name), {"episodes": 0, "breaches": 0, "listed": []})
        e["episodes"] += 1
        why = stats.realism_breach(r["metrics"], m0)
        if why:
            e["breaches"] += 1
            if len(e["listed"]) < REALISM_LISTED:
                e["listed"].append(f"{r['policy']} {r['scenario']} seed {r['seed']}: {why}")
    return out


def summarize(rows: list[dict], run: dict[str, Any]) -> dict[str, Any]:
    """The summary of leaderboard.json (rows: this run's grid, failed ones included). The
    model-mismatch rows go to each plant's ``robustness`` entry only
    (agents/leaderboard/mismatch.py)."""
    all_rows, rows = rows, [r for r in rows if not mismatch.is_label(r["scenario"])]
    realism = _realism(rows)
    by = defaultdict(lambda: defaultdict(lambda: defaultdict(list)))  # env, scenario, policy
    run_of = defaultdict(lambda: defaultdict(lambda: defaultdict(list)))  # training run of each
    failed = defaultdict(int)
    for r in rows:
        name, k = specs.split_run(r["policy"])
        if r.get("error"):
            failed[r["env"], name] += 1
        else:
            by[r["env"]][r["scenario"]][name].append(r["metrics"])
            run_of[r["env"]][r["scenario"]][name].append(0 if k is None else k)
    plants: dict[str, Any] = {}
    norm_scores: dict[str, dict[str, list[np.ndarray]]] = {}
    for env_id in run["envs"]:
        plants[env_id], norm_scores[env_id] = _plant(
            env_id, by[env_id], run_of[env_id], failed, realism, run
        )
        robust = mismatch.summarize(all_rows, env_id, plants[env_id]["policies"], ZERO, REFERENCES)
        if robust is not None:
            plants[env_id]["robustness"] = robust
    return {
        "schema_version": SCHEMA_VERSION,
        "run": run,
        "plants": plants,
        "ranking": _overall(plants),
    }, norm_scores


def _plant(
    env_id: str,
    by: dict,
    run_of: dict,
    failed: dict,
    realism: dict,
    run: dict[str, Any],
) -> tuple[dict[str, Any], dict[str, list[np.ndarray]]]:
    """A plant's entry of the summary (its reference returns, policies and scenarios) and each
    policy's normalized scores per scenario. ``by``: scenario -> policy -> the metrics of the
    plant's finished episodes; ``run_of``: the training run of each; ``failed`` and
    ``realism``: per (env, policy)."""
    scs = [s for s in run["scenarios"] if s in by]
    policies = [p for p in agent_names(run["policies"][env_id]) if any(p in by[s] for s in scs)]
    runs_of = {
        p: {s: np.array(run_of[s][p], dtype=int) for s in scs if p in by[s]} for p in policies
    }
    ks = {p: sorted({int(k) for v in runs_of[p].values() for k in v}) for p in policies}
    refs, tasks_norm = {}, {}
    for sc in scs:
        refs[sc], norm = _reference(by[sc])
        if norm is not None:
            tasks_norm[sc] = norm
    pol_out: dict[str, Any] = {}
    norm_scores: dict[str, list[np.ndarray]] = {}
    for p in policies:
        norm = {s: tasks_norm[s][p] for s in tasks_norm if p in tasks_norm[s]}
        pol_out[p] = _policy_entry(
            by, scs, p, norm, runs_of[p], ks[p], failed[env_id, p], realism.get((env_id, p))
        )
        if norm:
            norm_scores[p] = list(norm.values())
    _admissibility(pol_out, float(run.get("travel_budget", stats.TRAVEL_BUDGET)))
    _rank(pol_out)
    per_sc = {}
    for sc in scs:
        per_sc[sc] = {}
        for p in policies:
            ms = by[sc].get(p)
            if not ms:
                continue
            cell: dict[str, Any] = {"seeds": len(ms)}
            if len(ks[p]) > 1:
                cell["training_runs"] = len(set(runs_of[p][sc].tolist()))
            cell.update(_means([_applicable(m) for m in ms], TABLE_METRICS))
            cell["trips"] = int(sum(m["tripped"] for m in ms))
            if sc in tasks_norm and p in tasks_norm[sc]:
                cell["normalized_score"] = float(np.mean(tasks_norm[sc][p]))
            per_sc[sc][p] = cell
    return {"reference": refs, "policies": pol_out, "scenarios": per_sc}, norm_scores


def _reference(
    by_policy: dict[str, list[dict]],
) -> tuple[dict[str, Any], dict[str, np.ndarray] | None]:
    """A scenario's entry of a plant's ``reference`` (the score's ends, the best baseline)
    and each policy's normalized scores there (None without both ends)."""
    ret = {p: np.array([m["return"] for m in ms]) for p, ms in by_policy.items()}
    base = {p: float(v.mean()) for p, v in ret.items() if p in baselines.NAMES}
    ref: dict[str, Any] = {}
    if ZERO in ret:
        ref.update(zero_policy=ZERO, zero_return=float(ret[ZERO].mean()))
    if ONE in ret:
        ref.update(one_policy=ONE, one_return=float(ret[ONE].mean()))
    if base:
        ref["best_baseline"] = max(base, key=base.get)
    ref["normalized"] = False
    if "zero_return" not in ref or "one_return" not in ref:
        return ref, None
    ref["headroom"] = ref["one_return"] - ref["zero_return"]
    ref["span"] = stats.score_span(ref["zero_return"], ref["one_return"])
    ref["normalized"] = True
    return ref, {
        p: stats.normalize(v, ref["zero_return"], ref["one_return"]) for p, v in ret.items()
    }


def _policy_entry(
    by: dict,
    scs: list[str],
    p: str,
    norm: dict[str, np.ndarray],
    runs: dict[str, np.ndarray],
    ks: list[int],
    failed: int,
    realism: dict[str, Any] | None,
) -> dict[str, Any]:
    """A policy's entry of a plant's ``policies`` over scenario x seed (``norm``: its
    normalized scores per scenario; ``runs``: the training run of each episode; ``ks``:
    its training runs)."""
    ms = [m for s in scs for m in by[s].get(p, [])]
    rets = {s: np.array([m["return"] for m in by[s][p]]) for s in scs if by[s].get(p)}
    entry: dict[str, Any] = {
        "episodes": len(ms),
        "failed": failed,
        "trips": int(sum(m["tripped"] for m in ms)),
        "return": _estimate(list(rets.values()), _by_run(rets, runs, ks)),
        "metrics": _means([_applicable(m) for m in ms], SUMMARY_METRICS),
    }
    if len(ks) > 1:
        entry["training_runs"] = ks
    if realism is not None:
        entry["realism"] = realism
    if norm:
        entry["normalized_score"] = _estimate(list(norm.values()), _by_run(norm, runs, ks))
    if p != VERSUS:
        common = [s for s in scs if by[s].get(p) and by[s].get(VERSUS)]
        if common:
            x = [np.array([m["return"] for m in by[s][p]]) for s in common]
            y = [np.array([m["return"] for m in by[s][VERSUS]]) for s in common]
            point, lo, hi = stats.probability_of_improvement(x, y)
            entry[f"p_improvement_over_{VERSUS}"] = {
                "value": point,
                "ci95": [lo, hi],
                "tasks": len(common),
            }
    return entry


def _rank(pol_out: dict[str, Any]) -> None:
    """Each ranked policy's ``rank`` on the plant: by the IQM of the normalized score, the
    admissible ones first (the references are never ranked)."""
    ranked = {
        p: e["normalized_score"]["iqm"]["value"]
        for p, e in pol_out.items()
        if p not in REFERENCES and "normalized_score" in e
    }
    first = {p: v for p, v in ranked.items() if pol_out[p].get("admissible")}
    for group, offset in (
        (first, 0),
        ({p: v for p, v in ranked.items() if p not in first}, len(first)),
    ):
        for p, k in stats.ranks(group).items():
            pol_out[p]["rank"] = offset + k


def _admissibility(pol_out: dict[str, Any], budget: float) -> None:
    """Each policy's ``travel_ratio`` (its mean valve travel over the reference's) and
    ``admissible``: ratio <= ``budget``, no trip and no failed episode (references and runs
    without the reference get no verdict)."""
    zero = pol_out.get(ZERO, {}).get("metrics", {}).get("valve_travel")
    for p, e in pol_out.items():
        travel = e["metrics"].get("valve_travel")
        if not zero or travel is None:
            continue
        e["travel_ratio"] = travel / zero
        if p not in REFERENCES:
            e["admissible"] = bool(
                e["travel_ratio"] <= budget and e["trips"] == 0 and e["failed"] == 0
            )


#: How the cross-plant ranking orders the policies (the tables' captions quote it).
ORDER_RULE = (
    "ordered by the mean over plants of the policy's IQM score, where on a plant where it is "
    f"not admissible (†) a positive score counts as 0 (the score of {ZERO}, which an "
    "operator would put back); policies scored on fewer plants come after"
)


def counted_score(entry: dict[str, Any]) -> float:
    """A policy's IQM score on a plant as the cross-plant ranking counts it
    (:data:`ORDER_RULE`): as it is where admissible, at most 0 where not."""
    score = entry["normalized_score"]["iqm"]["value"]
    return score if entry.get("admissible") is not False else min(score, 0.0)


def _overall(plants: dict[str, Any]) -> list[dict[str, Any]]:
    """The cross-plant ranking (:data:`ORDER_RULE`) of the policies ranked on some plant:
    ``score`` (the mean of :func:`counted_score` over the plants), ``plants`` (how many),
    ``admissible_plants``, ``mean_rank`` (the mean per-plant rank) and ``position``; equal
    scores are ordered by mean rank, then name."""
    entries = defaultdict(list)
    for p in plants.values():
        for name, e in p["policies"].items():
            if "rank" in e:
                entries[name].append(e)
    out = [
        {
            "policy": n,
            "score": float(np.mean([counted_score(e) for e in es])),
            "plants": len(es),
            "admissible_plants": sum(e.get("admissible") is not False for e in es),
            "mean_rank": float(np.mean([e["rank"] for e in es])),
        }
        for n, es in entries.items()
    ]
    out.sort(key=lambda e: (-e["plants"], -e["score"], e["mean_rank"], e["policy"]))
    for i, e in enumerate(out):
        e["position"] = i + 1
    return out
