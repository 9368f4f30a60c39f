"""leaderboard.json's summary and leaderboard.md from the episode rows.

The statistics (agents/stats.py) per plant and policy, over scenario x seed: the mean and
IQM of the normalized score (0 = the industrial reference ``cascade_pi_ff``'s mean return
on that scenario, 1 = the clairvoyant ``oracle``'s; agents/stats.py ``normalize``) and of
the return, with 95 % stratified-bootstrap CIs; the probability of improvement over
``cascade_pi_ff``; the rank per plant (by the IQM of the normalized score; the references
``oracle`` and ``frozen_valve`` are listed, never ranked) and overall (the mean of the
per-plant ranks). A trained agent scored over several training runs (policy names
``sb3:<algo>@run<k>``, agents/specs.py) is one policy, ``sb3:<algo>``, over training run x
scenario x seed: its normalized score's and return's CIs resample the training runs and,
within each, the episodes (agents/stats.py ``training_run_bootstrap_ci``), and each
statistic also gives its value per run and their range. The engineering metrics are means over
scenario x seed of the episodes where they apply (a metric that does not apply, e.g.
settling time without a setpoint step, is left out, never NaN; ``max_abs_dev_K`` is left
out of an episode with a setpoint step, where it measures the step). Each plant's
``robustness`` entry summarizes the model-mismatch rows (agents/leaderboard_mismatch.py),
which take no part in the scores. The format is
docs/leaderboard_schema.json, described in docs/leaderboard.md.
"""

from __future__ import annotations

from collections import defaultdict
from typing import Any

import numpy as np

import baselines
from agents import leaderboard_mismatch as mismatch
from agents import specs, stats
from steamtemp_gym.checks import head

#: Version of leaderboard.json's format (docs/leaderboard_schema.json).
SCHEMA_VERSION = 7
#: The 0 of the normalized score: the cascade as a commissioned unit runs it.
ZERO = baselines.INDUSTRIAL_REFERENCE
#: The 1: the clairvoyant NMPC on the true plant (agents/oracle.py).
ONE = "oracle"
#: Policies listed and plotted but never ranked (not admissible controllers).
REFERENCES = ("oracle", "frozen_valve")
REFERENCE = "frozen_valve"
#: The policy the probability of improvement compares against.
VERSUS = ZERO
TABLE_METRICS = ("iae_K_s", "max_abs_dev_K", "time_outside_5K_s", "overshoot_pct",
                 "settling_time_s", "spray_used_kg", "valve_travel", "valve_reversals",
                 "quiet_p2p_K", "return")  # fmt: skip
#: The metrics of the ranking tables of leaderboard.md, in column order.
RANK_METRICS = ("iae_K_s", "max_abs_dev_K", "time_outside_5K_s", "valve_travel")
SUMMARY_METRICS = ("iae_K_s", "max_abs_dev_K", "time_outside_5K_s", "time_outside_8K_s",
                   "spray_used_kg", "valve_travel", "valve_reversals", "return")  # fmt: skip


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


def _estimate(tasks: list[np.ndarray], by_run: list[list[np.ndarray]] | None = None,
              ) -> dict[str, Any]:  # fmt: skip
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
            out[name] = {"value": point, "ci95": [lo, hi], "per_run": each,
                         "run_range": [min(each), max(each)]}  # fmt: skip
    out["tasks"] = len(tasks)
    out["runs"] = int(sum(len(t) for t in tasks))
    return out


def agent_names(policies: list[str]) -> list[str]:
    """The policies a summary lists for the names that ran: one per trained agent scored
    over several training runs (specs.split_run), in order of first appearance."""
    return list(dict.fromkeys(specs.split_run(p)[0] for p in policies))


def _by_run(values: dict[str, np.ndarray], runs: dict[str, np.ndarray], ks: list[int],
            ) -> list[list[np.ndarray]] | None:  # fmt: skip
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
    ref = {(r["env"], r["scenario"], r["seed"]): r["metrics"] for r in rows
           if r["policy"] == ZERO and not r.get("error")}  # fmt: skip
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
    (agents/leaderboard_mismatch.py)."""
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
        scs = [s for s in run["scenarios"] if s in by[env_id]]
        policies = [p for p in agent_names(run["policies"][env_id])
                    if any(p in by[env_id][s] for s in scs)]  # fmt: skip
        runs_of = {p: {s: np.array(run_of[env_id][s][p], dtype=int) for s in scs
                       if p in by[env_id][s]} for p in policies}  # fmt: skip
        ks = {p: sorted({int(k) for v in runs_of[p].values() for k in v}) for p in policies}
        refs, tasks_norm = {}, {}
        for sc in scs:
            ret = {p: np.array([m["return"] for m in by[env_id][sc][p]]) for p in by[env_id][sc]}
            base = {p: float(v.mean()) for p, v in ret.items() if p in baselines.NAMES}
            ref: dict[str, Any] = {}
            if ZERO in ret:
                ref.update(zero_policy=ZERO, zero_return=float(ret[ZERO].mean()))
            if ONE in ret:
                ref.update(one_policy=ONE, one_return=float(ret[ONE].mean()))
            if base:
                ref["best_baseline"] = max(base, key=base.get)
            ref["normalized"] = False
            if "zero_return" in ref and "one_return" in ref:
                ref["headroom"] = ref["one_return"] - ref["zero_return"]
                ref["span"] = stats.score_span(ref["zero_return"], ref["one_return"])
                ref["normalized"] = True
                tasks_norm[sc] = {p: stats.normalize(v, ref["zero_return"], ref["one_return"])
                                  for p, v in ret.items()}  # fmt: skip
            refs[sc] = ref
        pol_out: dict[str, Any] = {}
        norm_scores[env_id] = {}
        for p in policies:
            ms = [m for s in scs for m in by[env_id][s].get(p, [])]
            rets = {s: np.array([m["return"] for m in by[env_id][s][p]]) for s in scs
                    if by[env_id][s].get(p)}  # fmt: skip
            norm = {s: tasks_norm[s][p] for s in tasks_norm if p in tasks_norm[s]}
            entry: dict[str, Any] = {
                "episodes": len(ms),
                "failed": failed[env_id, p],
                "trips": int(sum(m["tripped"] for m in ms)),
                "return": _estimate(list(rets.values()), _by_run(rets, runs_of[p], ks[p])),
                "metrics": _means([_applicable(m) for m in ms], SUMMARY_METRICS),
            }
            if len(ks[p]) > 1:
                entry["training_runs"] = ks[p]
            if (env_id, p) in realism:
                entry["realism"] = realism[env_id, p]
            if norm:
                entry["normalized_score"] = _estimate(list(norm.values()),
                                                      _by_run(norm, runs_of[p], ks[p]))
                norm_scores[env_id][p] = list(norm.values())
            if p != VERSUS:
                common = [s for s in scs if by[env_id][s].get(p) and by[env_id][s].get(VERSUS)]
                if common:
                    x = [np.array([m["return"] for m in by[env_id][s][p]]) for s in common]
                    y = [np.array([m["return"] for m in by[env_id][s][VERSUS]]) for s in common]
                    point, lo, hi = stats.probability_of_improvement(x, y)
                    entry[f"p_improvement_over_{VERSUS}"] = {"value": point, "ci95": [lo, hi],
                                                            "tasks": len(common)}  # fmt: skip
            pol_out[p] = entry
        _admissibility(pol_out, float(run.get("travel_budget", stats.TRAVEL_BUDGET)))
        ranked = {p: e["normalized_score"]["iqm"]["value"] for p, e in pol_out.items()
                  if p not in REFERENCES and "normalized_score" in e}  # fmt: skip
        first = {p: v for p, v in ranked.items() if pol_out[p].get("admissible")}
        for group, offset in ((first, 0), ({p: v for p, v in ranked.items() if p not in first},
                                           len(first))):  # fmt: skip
            for p, k in stats.ranks(group).items():
                pol_out[p]["rank"] = offset + k
        per_sc = {}
        for sc in scs:
            per_sc[sc] = {}
            for p in policies:
                ms = by[env_id][sc].get(p)
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
        plants[env_id] = {"reference": refs, "policies": pol_out, "scenarios": per_sc}
        robust = mismatch.summarize(all_rows, env_id, pol_out, ZERO, REFERENCES)
        if robust is not None:
            plants[env_id]["robustness"] = robust
    return {"schema_version": SCHEMA_VERSION, "run": run, "plants": plants,
            "ranking": _overall(plants)}, norm_scores  # fmt: skip


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
            e["admissible"] = bool(e["travel_ratio"] <= budget and e["trips"] == 0
                                   and e["failed"] == 0)  # fmt: skip


def _overall(plants: dict[str, Any]) -> list[dict[str, Any]]:
    """Mean per-plant rank of each policy; policies ranked on more plants first."""
    ranks = defaultdict(list)
    for p in plants.values():
        for name, e in p["policies"].items():
            if "rank" in e:
                ranks[name].append(e["rank"])
    out = [{"policy": n, "mean_rank": float(np.mean(r)), "plants": len(r)}
           for n, r in ranks.items()]  # fmt: skip
    out.sort(key=lambda e: (-e["plants"], e["mean_rank"]))
    for i, e in enumerate(out):
        e["position"] = i + 1
    return out


# --------------------------------------------------------------------------- markdown
#: How leaderboard.md shows each metric: column header (with its unit), scale from the
#: metric's unit to the shown one, decimals.
COLUMNS: dict[str, tuple[str, float, int]] = {
    "iae_K_s": ("IAE [K s]", 1.0, 0),
    "max_abs_dev_K": ("max\\|dev\\| [K]", 1.0, 2),
    "time_outside_5K_s": ("t>5K [s]", 1.0, 0),
    "time_outside_8K_s": ("t>8K [s]", 1.0, 0),
    "overshoot_pct": ("overshoot [%]", 1.0, 1),
    "settling_time_s": ("settling time [s]", 1.0, 0),
    "spray_used_kg": ("spray [t]", 1e-3, 1),
    "valve_travel": ("valve travel [strokes]", 1.0, 2),
    "valve_reversals": ("valve reversals", 1.0, 0),
    "quiet_p2p_K": ("quiet p2p [K]", 1.0, 2),
    "return": ("return", 1.0, 1),
}


def num(v: float | None, decimals: int = 2, scale: float = 1.0) -> str:
    """``v * scale`` rounded to ``decimals`` (no exponent, no minus sign on a zero); "-"
    for None or a non-finite value."""
    if v is None or not np.isfinite(v):
        return "-"
    text = f"{v * scale:.{decimals}f}"
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text


def _col(key: str, v: float | None) -> str:
    _, scale, decimals = COLUMNS[key]
    return num(v, decimals, scale)


def _ci(est: dict[str, Any] | None, decimals: int = 2) -> str:
    if not est:
        return "-"
    lo, hi = est["ci95"]
    return f"{num(est['value'], decimals)} [{num(lo, decimals)}, {num(hi, decimals)}]"


def _multi_run(summary: dict[str, Any]) -> bool:
    """Whether any policy of the summary is a trained agent over several training runs."""
    return any("training_runs" in e for p in summary["plants"].values()
               for e in p["policies"].values())  # fmt: skip


def _run_range(est: dict[str, Any] | None, decimals: int = 2) -> str:
    """``min to max (k runs)`` of a statistic's per-run values; "-" without them."""
    if not est or "per_run" not in est:
        return "-"
    lo, hi = est["run_range"]
    return f"{num(lo, decimals)} to {num(hi, decimals)} ({len(est['per_run'])} runs)"


#: How the tables describe a trained agent over several training runs.
RUNS_NOTE = ("A trained agent with several training runs is one row over training run × "
             "scenario × seed; its CIs resample the runs and, within each, the episodes; "
             "runs: the range of its per-run IQM.")


def stat_label(n_seeds: int) -> str:
    """How the headline statistic is labelled everywhere (console, markdown, plots)."""
    return (f"IQM of the normalized score over scenario × seed ({n_seeds} seeds), "
            "95 % stratified-bootstrap CI")  # fmt: skip


#: Marks a policy that is not admissible on a plant (travel over budget, a trip or a failure).
INADMISSIBLE = "†"


def _travel(pe: dict[str, Any]) -> str:
    return f"{pe['travel_ratio']:.1f}x" if "travel_ratio" in pe else "-"


def _headline_cell(pe: dict[str, Any]) -> str:
    """Score with CI, (rank), travel ratio and the inadmissible mark of one plant."""
    est = pe.get("normalized_score", {}).get("iqm")
    if not est or "rank" not in pe:
        return "-"
    mark = f" {INADMISSIBLE}" if pe.get("admissible") is False else ""
    return f"{_ci(est)} ({pe['rank']}), travel {_travel(pe)}{mark}"


def admissibility_note(summary: dict[str, Any]) -> str:
    """What the travel column and the mark mean, with the run's budget."""
    b = summary["run"].get("travel_budget", stats.TRAVEL_BUDGET)
    return (f"travel: mean valve travel over {ZERO}'s on the same episodes; {INADMISSIBLE}: not "
            f"admissible on that plant (travel above {b:g}x {ZERO}'s, a trip or a failed "
            "episode), ranked after every admissible policy.")  # fmt: skip


def headline_rows(summary: dict[str, Any]) -> tuple[list[str], list[list[str]]]:
    """Header and rows of the headline table (policy x plant)."""
    plants = list(summary["plants"])
    header = ["#", "policy", *[p.split("/")[-1] for p in plants], "mean rank"]
    rows = []
    for e in summary["ranking"]:
        cells = []
        for env_id in plants:
            cells.append(_headline_cell(summary["plants"][env_id]["policies"].get(
                e["policy"], {})))  # fmt: skip
        rank = f"{e['mean_rank']:.1f}" + (f" ({e['plants']} plants)" if e["plants"] < len(
            plants) else "")  # fmt: skip
        rows.append([str(e["position"]), e["policy"], *cells, rank])
    for ref in REFERENCES:  # listed below the ranking, never ranked
        ests = [summary["plants"][p]["policies"].get(ref, {}).get("normalized_score", {}).get(
            "iqm") for p in plants]  # fmt: skip
        if any(ests):
            rows.append(["ref.", ref, *[_ci(est) if est else "-" for est in ests], "-"])
    return header, rows


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    return ["| " + " | ".join(header) + " |", "|" + "---|" * len(header),
            *["| " + " | ".join(r) + " |" for r in rows]]  # fmt: skip


def headline_markdown(summary: dict[str, Any], margins: bool = True) -> str:
    """The headline table with its label (also in the README), and below it the score's
    ends per plant (:func:`margin_markdown`) unless ``margins`` is False."""
    n = len(summary["run"]["seeds"])
    lines = [f"{stat_label(n)}: the share of the achievable improvement over the industrial "
             f"reference that a policy realizes (0 = {ZERO}, the cascade a commissioned unit "
             f"runs; 1 = {ONE}, the clairvoyant NMPC on the true plant; per scenario); "
             f"(k) = rank on that plant; {admissibility_note(summary)}"
             + (f" {RUNS_NOTE}" if _multi_run(summary) else ""), ""]  # fmt: skip
    lines += _table(*headline_rows(summary))
    if margins:
        lines += ["", *margin_markdown(summary)]
    return "\n".join(lines) + "\n"


def margin_markdown(summary: dict[str, Any]) -> list[str]:
    """The score's two ends per plant: mean returns over scenario x seed of the reference
    and the oracle, the oracle's margin, and the scenarios where the span was floored."""
    header = ["plant", f"{ZERO} return", f"{ONE} return", "margin", "floored scenarios"]
    body = []
    for env_id, p in summary["plants"].items():
        refs = [r for r in p["reference"].values() if r.get("normalized")]
        if not refs:
            continue
        zero = float(np.mean([r["zero_return"] for r in refs]))
        one = float(np.mean([r["one_return"] for r in refs]))
        floored = sum(r["span"] > r["headroom"] for r in refs)
        body.append([env_id.split("/")[-1], num(zero, 1), num(one, 1), f"{one - zero:+.1f}",
                     f"{floored} of {len(refs)}"])  # fmt: skip
    if not body:
        return [f"Not normalized: the run has no {ZERO} or no {ONE} episodes."]
    return [f"Mean return over scenario × seed of the score's ends (the oracle's margin is "
            f"the achievable improvement; where it is below {stats.MIN_SPAN:.0%} of "
            f"{ZERO}'s cost the scale is held there: floored):", "",
            *_table(header, body)]  # fmt: skip


def _iqm_score(entry: dict[str, Any]) -> float:
    return entry.get("normalized_score", {}).get("iqm", {}).get("value", -np.inf)


def agents_markdown(summary: dict[str, Any]) -> str:
    """Per plant, each trained agent (``sb3:*``) against ``cascade_pi`` and the best other
    baseline (by the IQM of the normalized score): IQM normalized score with its CI, mean
    return and mean IAE over scenario × seed, trips. The zoo table of docs/agents.md."""
    n = len(summary["run"]["seeds"])
    multi = _multi_run(summary)
    lines = [f"{stat_label(n)}; return and IAE: means over scenario × seed. **Bold**: the "
             f"best of the plant's rows; {admissibility_note(summary)}"
             + (f" {RUNS_NOTE}" if multi else ""), ""]  # fmt: skip
    header = ["plant", "policy", "IQM norm. score", *(["runs"] if multi else []),
              "mean return", COLUMNS["iae_K_s"][0], f"travel / {ZERO}'s", "trips"]  # fmt: skip
    body = []
    for env_id, p in summary["plants"].items():
        pols = p["policies"]
        others = [k for k in pols if k in baselines.NAMES and k != VERSUS]
        best_base = max(others, key=lambda k: _iqm_score(pols[k])) if others else None
        picks = [k for k in (VERSUS, best_base) if k in pols]
        picks += sorted(k for k in pols if k.startswith("sb3:"))
        if not picks:  # a run without cascade_pi, baselines or agents on this plant
            continue
        top = max(picks, key=lambda k: _iqm_score(pols[k]))
        best_ret = max(pols[k]["metrics"].get("return", -np.inf) for k in picks)
        best_iae = min(pols[k]["metrics"].get("iae_K_s", np.inf) for k in picks)
        for k in picks:
            e, met = pols[k], pols[k]["metrics"]
            score = _ci(e.get("normalized_score", {}).get("iqm"))
            ret, iae = _col("return", met.get("return")), _col("iae_K_s", met.get("iae_K_s"))
            spread = [_run_range(e.get("normalized_score", {}).get("iqm"))] if multi else []
            body.append([env_id.split("/")[-1],
                         f"{k} (best baseline)" if k == best_base else k,
                         f"**{score}**" if k == top else score, *spread,
                         f"**{ret}**" if met.get("return") == best_ret else ret,
                         f"**{iae}**" if met.get("iae_K_s") == best_iae else iae,
                         _travel(e) + (f" {INADMISSIBLE}" if e.get("admissible") is False
                                       else ""), str(e["trips"])])  # fmt: skip
    return "\n".join(lines + _table(header, body)) + "\n"


def baselines_markdown(summary: dict[str, Any]) -> str:
    """Every baseline on every plant: mean IAE of the main steam, valve travel relative to
    the reference's and valve reversals, over scenario x seed (the README's baseline table's
    actuator columns); † = not admissible."""
    plants = list(summary["plants"])
    header = ["baseline", *[f"{p.split('/')[-1]}: IAE [K s] / travel / reversals / rejected"
                            for p in plants]]  # fmt: skip
    body = []
    for name in baselines.NAMES:
        cells = []
        for env_id in plants:
            pe = summary["plants"][env_id]["policies"].get(name)
            if pe is None:
                cells.append("-")
                continue
            met = pe["metrics"]
            mark = f" {INADMISSIBLE}" if pe.get("admissible") is False else ""
            cells.append(f"{num(met.get('iae_K_s'), 0)} / {_travel(pe)} / "
                         f"{num(met.get('valve_reversals'), 0)} / "
                         f"{_rejected(pe)}{mark}")  # fmt: skip
        if any(c != "-" for c in cells):
            body.append([f"`{name}`", *cells])
    n = len(summary["run"]["seeds"])
    lines = [f"Means over scenario × seed ({n} seeds); {admissibility_note(summary)[:-1]}; "
             f"rejected: the episodes a plant engineer would reject against cascade_pi_ff's "
             f"on the same scenario and seed (a trip, valve travel above "
             f"{num(stats.REALISM_TRAVEL_MAX, 0)}x, or a limit cycle in the quiet stretch "
             f"after the last scheduled change).", ""]  # fmt: skip
    return "\n".join(lines + _table(header, body)) + "\n"


def _rejected(pe: dict[str, Any]) -> str:
    """``k/n``: a policy's rejected episodes of those compared (``-`` where none were)."""
    r = pe.get("realism")
    return f"{r['breaches']}/{r['episodes']}" if r else "-"


def realism_markdown(summary: dict[str, Any]) -> str:
    """Every baseline-plant pair with an episode a plant engineer would reject
    (:func:`agents.stats.realism_breach` against ``cascade_pi_ff`` on the same scenario and
    seed): how many of its episodes, and the first of them with their numbers."""
    rows, clean = [], 0
    for name in baselines.NAMES:
        for env_id, plant in summary["plants"].items():
            r = plant["policies"].get(name, {}).get("realism")
            if not r:
                continue
            if not r["breaches"]:
                clean += 1
                continue
            listed = "; ".join(x.split(" ", 1)[1] for x in r["listed"])
            more = "; ..." if r["breaches"] > len(r["listed"]) else ""
            rows.append([f"`{name}`", env_id.split("/")[-1], f"{r['breaches']}/{r['episodes']}",
                         listed + more])  # fmt: skip
    n = len(summary["run"]["seeds"])
    head = (f"Over every scenario and seed ({n} seeds) of the run, {clean} of "
            f"{clean + len(rows)} baseline-plant pairs have no episode a plant engineer would "
            f"reject against `cascade_pi_ff`'s on the same scenario and seed (a trip, valve "
            f"travel above {num(stats.REALISM_TRAVEL_MAX, 0)}x, or a limit cycle in the quiet "
            f"stretch: the quiet peak-to-peak above max(2x the reference's, 1.5 K)).")
    if not rows:
        return head + "\n"
    return "\n".join([head + " The others:", "",
                      *_table(["baseline", "plant", "rejected", "first episodes"], rows)]) + "\n"


#: The columns of :func:`comparison_markdown`, in order.
COMPARISON_METRICS = ("return", "iae_K_s", "valve_travel", "quiet_p2p_K")


def comparison_markdown(summary: dict[str, Any], policies: list[str]) -> str:
    """Per plant and scenario, the mean over seeds of the return, IAE, valve travel and
    quiet peak-to-peak of each of ``policies``, side by side (``a / b / c`` per cell; "-"
    where a policy was not run or a metric does not apply)."""
    n = len(summary["run"]["seeds"])
    lines = [f"Means over seeds ({n} seeds); each cell is {' / '.join(policies)}; quiet "
             "p2p: the main-steam error's peak-to-peak over the quiet stretch after the "
             "scenario's last scheduled change (- where it does not apply).", ""]  # fmt: skip
    header = ["scenario", *(COLUMNS[m][0] for m in COMPARISON_METRICS)]
    for env_id, plant in summary["plants"].items():
        body = []
        for sc, cells in plant["scenarios"].items():
            body.append([sc, *(" / ".join(_col(m, cells.get(p, {}).get(m)) for p in policies)
                               for m in COMPARISON_METRICS)])  # fmt: skip
        lines += [f"#### {env_id.split('/')[-1]}", "", *_table(header, body), ""]
    return "\n".join(lines)


def markdown(summary: dict[str, Any], rows: list[dict]) -> str:
    """leaderboard.md."""
    run = summary["run"]
    n = len(run["seeds"])
    lines = ["# steamtemp_gym leaderboard", "",
             f"Seeds {run['seeds']}; scenarios: {', '.join(run['scenarios'])}. "
             "Return: the default reward summed over an episode (higher is better). "
             f"Normalized score per scenario: (R - R0) / (R1 - R0) with R0 the mean return "
             f"over seeds of {ZERO} (the industrial reference: load-scheduled cascade PI "
             f"with load feed-forward) and R1 that of {ONE} (the clairvoyant NMPC on the "
             f"true plant, an upper bound on any causal controller): the share of the "
             f"achievable improvement a policy realizes, negative when it is worse than "
             f"{ZERO}. {ONE} and {REFERENCE} (every actuator held at its reset opening) are "
             "references, listed and never ranked.",
             "", "## Headline", "", headline_markdown(summary),
             "## Trained agents against the baselines", "", agents_markdown(summary)]  # fmt: skip
    robust = mismatch.markdown(summary, ZERO)
    if robust:
        lines += ["## Robustness to model mismatch", "", robust]
    multi = _multi_run(summary)
    for env_id, p in summary["plants"].items():
        pols = p["policies"]
        order = sorted(pols, key=lambda k: (pols[k].get("rank", 10**6), k))
        lines += [f"## {env_id}", "", f"Ranking: statistics over scenario × seed ({n} seeds), "
                  f"95 % stratified-bootstrap CIs; P(> {VERSUS}): probability that an "
                  f"episode of the policy has a higher return than one of {VERSUS} on the "
                  "same scenario, averaged over scenarios. IAE, max\\|dev\\| and time outside "
                  "±5 K: mean over scenario × seed where they apply."
                  + (f" {RUNS_NOTE}" if multi else ""), ""]  # fmt: skip
        header = ["rank", "policy", "IQM norm. score", *(["runs"] if multi else []),
                  "mean norm. score", "IQM return",
                  f"P(> {VERSUS})", *(COLUMNS[k][0] for k in RANK_METRICS),
                  f"travel / {ZERO}'s", COLUMNS["valve_reversals"][0], "admissible", "trips",
                  "failed"]  # fmt: skip
        body = []
        for k in order:
            e = pols[k]
            ns = e.get("normalized_score", {})
            met = e["metrics"]
            ratio = f"{e['travel_ratio']:.2f}" if "travel_ratio" in e else "-"
            verdict = {True: "yes", False: f"no {INADMISSIBLE}"}.get(e.get("admissible"), "-")
            body.append([str(e.get("rank", "ref." if k in REFERENCES else "-")), k,
                         _ci(ns.get("iqm")), *([_run_range(ns.get("iqm"))] if multi else []),
                         _ci(ns.get("mean")),
                         _ci(e["return"]["iqm"], 0),
                         _ci(e.get(f"p_improvement_over_{VERSUS}")),
                         *(_col(k, met.get(k)) for k in RANK_METRICS), ratio,
                         _col("valve_reversals", met.get("valve_reversals")), verdict,
                         str(e["trips"]), str(e["failed"])])  # fmt: skip
        lines += _table(header, body) + [""]
        lines += ["<details><summary>per scenario (mean over seeds)</summary>", ""]
        for sc, cells in p["scenarios"].items():
            ref = p["reference"][sc]
            note = (f"0 = {ZERO} (return {num(ref['zero_return'], 1)}), 1 = {ONE} (return "
                    f"{num(ref['one_return'], 1)}), scale {num(ref['span'], 1)}"
                    if ref["normalized"]
                    else f"not normalized ({ZERO} or {ONE} not run)")  # fmt: skip
            cols = [m for m in TABLE_METRICS if any(m in c for c in cells.values())]
            lines += [f"### {env_id.split('/')[-1]} - {sc}", "", f"Normalized score: {note}.", ""]
            header = ["policy", "seeds", "norm. score", *(COLUMNS[m][0] for m in cols), "trips"]
            body = [[k, str(c["seeds"]), num(c.get("normalized_score")),
                     *[_col(m, c.get(m)) for m in cols], str(c["trips"])]
                    for k, c in cells.items()]  # fmt: skip
            lines += _table(header, body) + [""]
        lines += ["</details>", ""]
    failed = [r for r in rows if r.get("error")]
    if failed:
        lines += ["## Failed episodes", ""]
        body = [[r["env"], r["scenario"], r["policy"], str(r["seed"]),
                 head(str(r["error"]), 160).replace("|", "\\|").replace("\n", " ")]
                for r in failed]  # fmt: skip
        lines += _table(["env", "scenario", "policy", "seed", "error"], body) + [""]
    return "\n".join(lines)


def console(summary: dict[str, Any]) -> str:
    """The headline table as plain text for the terminal (same statistic and label)."""
    header, rows = headline_rows(summary)
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    n = len(summary["run"]["seeds"])
    return "\n".join([stat_label(n) + " (rank on the plant):", fmt.format(*header),
                      *[fmt.format(*r) for r in rows]])  # fmt: skip
