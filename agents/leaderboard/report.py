"""leaderboard.md and the console's headline table from leaderboard.json's summary
(agents/leaderboard/summary.py): the headline table (policy x plant), the trained agents
against the baselines, the robustness to model mismatch (agents/leaderboard/mismatch.py),
the ranking and per-scenario tables of each plant and the failed episodes; also the README's
headline and the zoo's table of docs/agents/zoo.md (the other generated tables of the docs:
agents/leaderboard/pages.py). Described in docs/leaderboard_outputs.md.
"""

from __future__ import annotations

from typing import Any

import numpy as np

import baselines
from agents import stats
from agents.leaderboard import mismatch
from agents.leaderboard.summary import (
    ONE,
    ONE_LABELS,
    ORDER_RULE,
    REFERENCE,
    REFERENCES,
    TABLE_METRICS,
    VERSUS,
    ZERO,
)
from steamtemp_gym.checks import head

#: The metrics of the ranking tables of leaderboard.md, in column order.
RANK_METRICS = ("iae_K_s", "max_abs_dev_K", "time_outside_5K_s", "valve_travel")


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


def cell(key: str, v: float | None) -> str:
    _, scale, decimals = COLUMNS[key]
    return num(v, decimals, scale)


def _ci(est: dict[str, Any] | None, decimals: int = 2) -> str:
    if not est:
        return "-"
    lo, hi = est["ci95"]
    return f"{num(est['value'], decimals)} [{num(lo, decimals)}, {num(hi, decimals)}]"


def _multi_run(summary: dict[str, Any]) -> bool:
    """Whether any policy of the summary is a trained agent over several training runs."""
    return any(
        "training_runs" in e for p in summary["plants"].values() for e in p["policies"].values()
    )


def _run_range(est: dict[str, Any] | None, decimals: int = 2) -> str:
    """``min to max (k runs)`` of a statistic's per-run values; "-" without them."""
    if not est or "per_run" not in est:
        return "-"
    lo, hi = est["run_range"]
    return f"{num(lo, decimals)} to {num(hi, decimals)} ({len(est['per_run'])} runs)"


#: How the tables describe a trained agent over several training runs.
RUNS_NOTE = (
    "A trained agent with several training runs is one row over training run × "
    "scenario × seed; its CIs resample the runs and, within each, the episodes; "
    "runs: the range of its per-run IQM."
)


def stat_label(n_seeds: int) -> str:
    """How the headline statistic is labelled everywhere (console, markdown, plots)."""
    return (
        f"IQM of the normalized score over scenario × seed ({n_seeds} seeds), "
        "95 % stratified-bootstrap CI"
    )


#: Marks a policy that is not admissible on a plant (travel over budget, a trip or a failure).
INADMISSIBLE = "†"


def budget(summary: dict[str, Any]) -> float:
    """The run's valve-travel budget (a multiple of the reference's travel)."""
    return float(summary["run"].get("travel_budget", stats.TRAVEL_BUDGET))


#: Most decimals :func:`ratio` writes to tell a travel ratio from the budget.
RATIO_DECIMALS = 4


def ratio(r: float, limit: float | None = None, decimals: int = 1) -> str:
    """A travel ratio as ``1.7x``, with more decimals (up to :data:`RATIO_DECIMALS`) where
    ``decimals`` would round it onto ``limit`` (the budget) or across it: 2.04 against 2
    reads ``2.04x``, 1.96 ``1.96x``, so the text shows on which side it is."""
    d = decimals
    while limit is not None and d < RATIO_DECIMALS and r != limit:
        shown = round(r, d)
        if shown != limit and (shown > limit) == (r > limit):
            break
        d += 1
    return f"{r:.{d}f}x"


def travel_cell(pe: dict[str, Any], limit: float | None = None) -> str:
    return ratio(pe["travel_ratio"], limit) if "travel_ratio" in pe else "-"


def inadmissible_reason(pe: dict[str, Any], limit: float) -> str:
    """Why a policy is not admissible on a plant, e.g. ``travel 2.04x > 2x, 1 trip``
    ("" where it is admissible or has no verdict)."""
    if pe.get("admissible") is not False:
        return ""
    why = []
    if pe.get("travel_ratio", 0.0) > limit:
        why.append(f"travel {ratio(pe['travel_ratio'], limit)} > {limit:g}x")
    for key, word in (("trips", "trip"), ("failed", "failed episode")):
        n = pe.get(key, 0)
        if n:
            why.append(f"{n} {word}{'s' if n > 1 else ''}")
    return ", ".join(why)


def _headline_cell(pe: dict[str, Any], limit: float) -> str:
    """Score with CI and, where admissible, (rank among the plant's admissible policies)
    and travel ratio; where not, the mark and the reason."""
    est = pe.get("normalized_score", {}).get("iqm")
    if not est or "rank" not in pe:
        return "-"
    why = inadmissible_reason(pe, limit)
    if why:
        travel = "" if "travel" in why else f", travel {travel_cell(pe, limit)}"
        return f"{_ci(est)} {INADMISSIBLE} {why}{travel}"
    return f"{_ci(est)} ({pe['rank']}), travel {travel_cell(pe, limit)}"


def admissibility_note(summary: dict[str, Any]) -> str:
    """What the travel column and the mark mean, with the run's budget."""
    return (
        f"travel: mean valve travel over {ZERO}'s on the same episodes; {INADMISSIBLE}: not "
        f"admissible on that plant (travel above {budget(summary):g}x {ZERO}'s, a trip or "
        "a failed episode), listed after every admissible policy."
    )


def order_note() -> str:
    """The sentence that states the headline table's order."""
    return f"Rows are {ORDER_RULE}."


def headline_rows(summary: dict[str, Any]) -> tuple[list[str], list[list[str]]]:
    """Header and rows of the headline table (policy x plant), in the ranking's order
    (:data:`ORDER_RULE`), the last column the ranking's score."""
    plants = list(summary["plants"])
    header = ["#", "policy", *[p.split("/")[-1] for p in plants], "score over plants"]
    limit = budget(summary)
    rows = []
    for e in summary["ranking"]:
        cells = []
        for env_id in plants:
            cells.append(
                _headline_cell(summary["plants"][env_id]["policies"].get(e["policy"], {}), limit)
            )
        score = num(e["score"])
        if e["plants"] < len(plants):
            score += f" ({e['plants']} of {len(plants)} plants)"
        if e["admissible_plants"] < e["plants"]:
            score += f", {INADMISSIBLE} on {e['plants'] - e['admissible_plants']}"
        rows.append([str(e["position"]), e["policy"], *cells, score])
    for ref in REFERENCES:  # listed below the ranking, never ranked
        ests = [
            summary["plants"][p]["policies"].get(ref, {}).get("normalized_score", {}).get("iqm")
            for p in plants
        ]
        if any(ests):
            rows.append(["ref.", ref, *[_ci(est) if est else "-" for est in ests], "-"])
    return header, rows


def table_lines(header: list[str], rows: list[list[str]]) -> list[str]:
    return [
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
        *["| " + " | ".join(r) + " |" for r in rows],
    ]


def one_label(summary: dict[str, Any]) -> str:
    """What the score's 1 is in the run of ``summary`` (agents/oracle.py: ONE_LABELS)."""
    return ONE_LABELS[summary["run"].get("oracle", "cem")]


def headline_markdown(summary: dict[str, Any], margins: bool = True) -> str:
    """The headline table with its label (also in the README), and below it the score's
    ends per plant (:func:`margin_markdown`) unless ``margins`` is False."""
    n = len(summary["run"]["seeds"])
    lines = [
        f"{order_note()} Score: {stat_label(n)}: the share of the achievable improvement "
        f"over the industrial reference that a policy realizes (0 = {ZERO}, the cascade a "
        f"commissioned unit runs; 1 = {ONE}, {one_label(summary)}; per "
        f"scenario); (k) = rank among the policies admissible on that plant; "
        f"{admissibility_note(summary)}" + (f" {RUNS_NOTE}" if _multi_run(summary) else ""),
        "",
    ]
    lines += table_lines(*headline_rows(summary))
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
        body.append(
            [
                env_id.split("/")[-1],
                num(zero, 1),
                num(one, 1),
                f"{one - zero:+.1f}",
                f"{floored} of {len(refs)}",
            ]
        )
    if not body:
        return [f"Not normalized: the run has no {ZERO} or no {ONE} episodes."]
    return [
        f"Mean return over scenario × seed of the score's ends (the oracle's margin is "
        f"the achievable improvement; where it is below {stats.MIN_SPAN:.0%} of "
        f"{ZERO}'s cost the scale is held there: floored):",
        "",
        *table_lines(header, body),
    ]


def _iqm_score(entry: dict[str, Any]) -> float:
    return entry.get("normalized_score", {}).get("iqm", {}).get("value", -np.inf)


def _kind(name: str) -> str:
    """What a row of the agents' table is: a baseline, or a trained agent's kind
    (``agents.kind``: model-free, residual over X, imitation of X)."""
    import agents

    return agents.kind(name[len("sb3:") :]) if name.startswith("sb3:") else "baseline"


def agents_markdown(summary: dict[str, Any]) -> str:
    """Per plant, each trained agent (``sb3:*``, with its kind) against ``cascade_pi`` and
    the best other baseline (by the IQM of the normalized score): IQM normalized score with
    its CI, mean return and mean IAE over scenario × seed, trips and the episodes a plant
    engineer would reject (:func:`rejected_cell`). The zoo table of docs/agents/zoo.md."""
    n = len(summary["run"]["seeds"])
    multi = _multi_run(summary)
    lines = [
        f"{stat_label(n)}; return and IAE: means over scenario × seed. **Bold**: the "
        f"best of the plant's rows; {admissibility_note(summary)} {rejected_note()}"
        + (f" {RUNS_NOTE}" if multi else ""),
        "",
    ]
    header = [
        "plant",
        "policy",
        "kind",
        "IQM norm. score",
        *(["runs"] if multi else []),
        "mean return",
        COLUMNS["iae_K_s"][0],
        f"travel / {ZERO}'s",
        "trips",
        "rejected",
    ]
    body = []
    limit = budget(summary)
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
            ret, iae = cell("return", met.get("return")), cell("iae_K_s", met.get("iae_K_s"))
            spread = [_run_range(e.get("normalized_score", {}).get("iqm"))] if multi else []
            body.append(
                [
                    env_id.split("/")[-1],
                    f"{k} (best baseline)" if k == best_base else k,
                    _kind(k),
                    f"**{score}**" if k == top else score,
                    *spread,
                    f"**{ret}**" if met.get("return") == best_ret else ret,
                    f"**{iae}**" if met.get("iae_K_s") == best_iae else iae,
                    travel_cell(e, limit)
                    + (f" {INADMISSIBLE}" if e.get("admissible") is False else ""),
                    str(e["trips"]),
                    rejected_cell(e),
                ]
            )
    return "\n".join(lines + table_lines(header, body)) + "\n"


def rejected_note() -> str:
    """What the tables' ``rejected`` column counts."""
    return (
        f"rejected: the episodes a plant engineer would reject against cascade_pi_ff's "
        f"on the same scenario and seed (a trip, valve travel above "
        f"{num(stats.REALISM_TRAVEL_MAX, 0)}x, or a limit cycle in the quiet stretch "
        f"after the last scheduled change)."
    )


def rejected_cell(pe: dict[str, Any]) -> str:
    """``k/n``: a policy's rejected episodes of those compared (``-`` where none were)."""
    r = pe.get("realism")
    return f"{r['breaches']}/{r['episodes']}" if r else "-"


def markdown(summary: dict[str, Any], rows: list[dict]) -> str:
    """leaderboard.md."""
    run = summary["run"]
    n = len(run["seeds"])
    lines = [
        "# steamtemp_gym leaderboard",
        "",
        f"Seeds {run['seeds']}; scenarios: {', '.join(run['scenarios'])}. "
        "Return: the default reward summed over an episode (higher is better). "
        f"Normalized score per scenario: (R - R0) / (R1 - R0) with R0 the mean return "
        f"over seeds of {ZERO} (the industrial reference: load-scheduled cascade PI "
        f"with load feed-forward) and R1 that of {ONE} ({one_label(summary)}; "
        f"no causal controller can exceed the optimum): the share of the "
        f"achievable improvement a policy realizes, negative when it is worse than "
        f"{ZERO}. {ONE} and {REFERENCE} (every actuator held at its reset opening) are "
        "references, listed and never ranked.",
        "",
        "## Headline",
        "",
        headline_markdown(summary),
        "## Trained agents against the baselines",
        "",
        agents_markdown(summary),
    ]
    robust = mismatch.markdown(summary, ZERO)
    if robust:
        lines += ["## Robustness to model mismatch", "", robust]
    multi = _multi_run(summary)
    limit = budget(summary)
    for env_id, p in summary["plants"].items():
        lines += _plant_markdown(env_id, p, n, multi, limit)
    failed = [r for r in rows if r.get("error")]
    if failed:
        lines += ["## Failed episodes", "", *_failed_table(failed), ""]
    return "\n".join(lines)


def _plant_markdown(env_id: str, p: dict[str, Any], n: int, multi: bool, limit: float) -> list[str]:
    """A plant's section of leaderboard.md: the ranking over ``n`` seeds (with the training
    runs' range where ``multi``), then the per-scenario tables folded away."""
    pols = p["policies"]
    order = sorted(pols, key=lambda k: (pols[k].get("rank", 10**6), k))
    lines = [
        f"## {env_id}",
        "",
        f"Ranking: statistics over scenario × seed ({n} seeds), "
        f"95 % stratified-bootstrap CIs; P(> {VERSUS}): probability that an "
        f"episode of the policy has a higher return than one of {VERSUS} on the "
        "same scenario, averaged over scenarios. IAE, max\\|dev\\| and time outside "
        "±5 K: mean over scenario × seed where they apply. The admissible policies "
        f"by score, then those not admissible ({INADMISSIBLE}), with the reason."
        + (f" {RUNS_NOTE}" if multi else ""),
        "",
    ]
    header = [
        "rank",
        "policy",
        "IQM norm. score",
        *(["runs"] if multi else []),
        "mean norm. score",
        "IQM return",
        f"P(> {VERSUS})",
        *(COLUMNS[k][0] for k in RANK_METRICS),
        f"travel / {ZERO}'s",
        COLUMNS["valve_reversals"][0],
        "admissible",
        "trips",
        "failed",
    ]
    body = [_ranking_row(k, pols[k], multi, limit) for k in order]
    lines += table_lines(header, body) + [""]
    lines += ["<details><summary>per scenario (mean over seeds)</summary>", ""]
    for sc, cells in p["scenarios"].items():
        lines += _scenario_table(env_id, sc, cells, p["reference"][sc])
    return lines + ["</details>", ""]


def _ranking_row(k: str, e: dict[str, Any], multi: bool, limit: float) -> list[str]:
    """Policy ``k``'s row of a plant's ranking (``e``: its entry in the summary)."""
    ns = e.get("normalized_score", {})
    met = e["metrics"]
    travel = ratio(e["travel_ratio"], limit, 2)[:-1] if "travel_ratio" in e else "-"
    verdict = {
        True: "yes",
        False: f"no {INADMISSIBLE}: {inadmissible_reason(e, limit)}",
    }.get(e.get("admissible"), "-")
    rank = INADMISSIBLE if e.get("admissible") is False else e.get("rank")
    return [
        str(rank or ("ref." if k in REFERENCES else "-")),
        k,
        _ci(ns.get("iqm")),
        *([_run_range(ns.get("iqm"))] if multi else []),
        _ci(ns.get("mean")),
        _ci(e["return"]["iqm"], 0),
        _ci(e.get(f"p_improvement_over_{VERSUS}")),
        *(cell(k, met.get(k)) for k in RANK_METRICS),
        travel,
        cell("valve_reversals", met.get("valve_reversals")),
        verdict,
        str(e["trips"]),
        str(e["failed"]),
    ]


def _scenario_table(env_id: str, sc: str, cells: dict[str, Any], ref: dict[str, Any]) -> list[str]:
    """The table of scenario ``sc`` on a plant: per policy the mean over seeds of the
    normalized score and of the metrics any policy has there (``ref``: the score's ends)."""
    note = (
        f"0 = {ZERO} (return {num(ref['zero_return'], 1)}), 1 = {ONE} (return "
        f"{num(ref['one_return'], 1)}), scale {num(ref['span'], 1)}"
        if ref["normalized"]
        else f"not normalized ({ZERO} or {ONE} not run)"
    )
    cols = [m for m in TABLE_METRICS if any(m in c for c in cells.values())]
    header = ["policy", "seeds", "norm. score", *(COLUMNS[m][0] for m in cols), "trips"]
    body = []
    for k, c in cells.items():
        metrics = [cell(m, c.get(m)) for m in cols]
        body.append([k, str(c["seeds"]), num(c.get("normalized_score")), *metrics, str(c["trips"])])
    return [
        f"### {env_id.split('/')[-1]} - {sc}",
        "",
        f"Normalized score: {note}.",
        "",
        *table_lines(header, body),
        "",
    ]


def _failed_table(failed: list[dict]) -> list[str]:
    """The failed episodes: env, scenario, policy, seed and the start of the error."""
    body = []
    for r in failed:
        error = head(str(r["error"]), 160).replace("|", "\\|").replace("\n", " ")
        body.append([r["env"], r["scenario"], r["policy"], str(r["seed"]), error])
    return table_lines(["env", "scenario", "policy", "seed", "error"], body)


def console(summary: dict[str, Any]) -> str:
    """The headline table as plain text for the terminal (same statistic and label)."""
    header, rows = headline_rows(summary)
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    n = len(summary["run"]["seeds"])
    return "\n".join(
        [
            f"{stat_label(n)} (k: rank among the plant's admissible policies). {order_note()}",
            fmt.format(*header),
            *[fmt.format(*r) for r in rows],
        ]
    )
