"""A trained agent over several training runs on the leaderboard: the two-level bootstrap
of agents/stats.py (training runs, then episodes within each) on hand-computable cases,
and the report's one row per agent over run x scenario x seed (agents/leaderboard/summary.py)
on hand-made records; with one run the summary is the one-run report's, number for number
(tests/data/one_run_summary.json: the summary the report wrote before it knew training
runs, on the record of tests/run_records.py, and its markdown as the version-9 report
writes it: the same numbers under the headline's new order, captions and last column, the
1 named by the oracle's engine)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from run_records import ENV, FIXED, rows, run_info

from agents import stats
from agents.leaderboard import pages, report
from agents.leaderboard.records import strict
from agents.leaderboard.summary import summarize

GOLDEN = Path(__file__).with_name("data") / "one_run_summary.json"
AGENT = "sb3:ppo"


# --------------------------------------------------------------------------- stats
def test_two_constant_runs_by_hand():
    """Runs scoring 0, 0 and 1, 1: a replicate draws (0, 0), (0, 1), (1, 0) or (1, 1); the
    IQM of {0, 0, 1, 1} is 0.5; a quarter of the replicates are 0 and a quarter 1."""
    point, lo, hi = stats.training_run_bootstrap_ci([[np.zeros(2)], [np.ones(2)]])
    assert (point, lo, hi) == (0.5, 0.0, 1.0)
    assert stats.per_run([[np.zeros(2)], [np.ones(2)]]) == [0.0, 1.0]


def test_three_runs_by_hand_the_ci_covers_the_runs():
    """Runs of 0, 1 and 2 (two tasks of two episodes each): the IQM of the pooled twelve is
    the mean of the middle six, 1; a replicate of one run three times has probability
    1/27 > 2.5 %, so the interval reaches from the worst run to the best."""
    runs = [[np.full(2, v), np.full(2, v)] for v in (0.0, 1.0, 2.0)]
    point, lo, hi = stats.training_run_bootstrap_ci(runs)
    assert point == 1.0 and (lo, hi) == (0.0, 2.0)
    pooled = stats.stratified_bootstrap_ci([np.concatenate([r[t] for r in runs]) for t in (0, 1)])
    assert pooled[0] == point and 0.0 < pooled[1] and pooled[2] < 2.0  # episodes alone: narrower


def _definition(runs, statistic, n_boot, seed):
    """The replicates as the docstring defines them, one replicate at a time."""
    rng = np.random.default_rng(seed)
    n = len(runs)
    pick = rng.integers(0, n, (n_boot, n))
    drawn = [
        [r[t][rng.integers(0, r[t].size, (n_boot, n, r[t].size))] for r in runs]
        for t in range(len(runs[0]))
    ]
    return np.array(
        [
            statistic(np.concatenate([d[pick[b, j]][b, j] for d in drawn for j in range(n)]))
            for b in range(n_boot)
        ]
    )


@pytest.mark.parametrize("sizes", [(5, 5, 5), (5, 3, 4)])  # equal sizes: the batched path
def test_the_replicates_follow_the_definition(sizes):
    rng = np.random.default_rng(7)
    runs = [[rng.normal(k, 1.0, n) for n in (sizes[k], 4)] for k in range(3)]
    for statistic in (stats.iqm, stats.mean):
        reps = _definition(runs, statistic, 300, 3)
        want = np.percentile(reps, [2.5, 97.5])
        point, lo, hi = stats.training_run_bootstrap_ci(runs, statistic, n_boot=300, seed=3)
        np.testing.assert_allclose([lo, hi], want, rtol=0, atol=1e-12)
        assert point == pytest.approx(statistic(np.concatenate([t for r in runs for t in r])))


def test_one_run_is_the_stratified_bootstrap_and_the_same_seed_the_same_interval():
    rng = np.random.default_rng(1)
    tasks = [rng.normal(0, 1, 5) for _ in range(4)]
    assert stats.training_run_bootstrap_ci([tasks]) == stats.stratified_bootstrap_ci(tasks)
    runs = [tasks, [t + 1 for t in tasks]]
    assert stats.training_run_bootstrap_ci(runs) == stats.training_run_bootstrap_ci(runs)
    assert stats.training_run_bootstrap_ci(runs, seed=1) != stats.training_run_bootstrap_ci(runs)


@pytest.mark.parametrize(
    ("runs", "match"),
    [
        ([], "no training runs"),
        ([[np.ones(2)], [np.ones(2), np.ones(2)]], "different task counts"),
        ([[np.ones(2)], [np.array([])]], "training run 1: no scores"),
        ([[np.ones(2)], [np.array([np.nan])]], "training run 1: scores must be finite"),
    ],
)
def test_bad_runs_are_refused(runs, match):
    with pytest.raises(ValueError, match=match):
        stats.training_run_bootstrap_ci(runs)


# --------------------------------------------------------------------------- report
def _summary(offsets: dict, spread: bool = True) -> tuple[dict, list[dict]]:
    names = [AGENT if k is None else f"{AGENT}@run{k}" for k in offsets]
    r = rows(AGENT, offsets, spread)
    s, _ = summarize(r, run_info([*FIXED, *names]))
    return json.loads(json.dumps(strict(s))), r


@pytest.mark.parametrize("run", [None, 0, 2])  # sb3:ppo, or its only run named
def test_one_run_gives_the_one_run_summary(run):
    gold = json.loads(GOLDEN.read_text())
    s, r = _summary({run: 0.0})
    assert s["schema_version"] == gold["summary"]["schema_version"] + 4 == 9
    for pe in s["plants"][ENV]["policies"].values():  # the record predates this entry
        pe.pop("realism", None)
    assert s["plants"] == gold["summary"]["plants"]
    old = gold["summary"]["ranking"]  # version 5's fields; version 8 adds score and more
    assert [{k: e[k] for k in old[0]} for e in s["ranking"]] == old
    if run is None:
        assert s["run"] == gold["summary"]["run"]
        assert report.markdown(s, r) == gold["markdown"]


def test_three_runs_are_one_row_with_the_hand_computed_iqm_and_ci():
    """Returns -60 + (0, 8, -10) for runs 0, 1, 2 on every episode; 0 = -100, 1 = -20: the
    runs score 0.5, 0.6 and 0.375. Pooled (12 episodes each), the IQM drops 9 from each
    end: (3 x 0.375 + 12 x 0.5 + 3 x 0.6) / 18; the CI spans the worst run to the best."""
    s, r = _summary({0: 0.0, 1: 8.0, 2: -10.0}, spread=False)
    pols = s["plants"][ENV]["policies"]
    assert set(pols) == {*FIXED, AGENT}
    e = pols[AGENT]
    assert e["training_runs"] == [0, 1, 2] and e["episodes"] == 36
    iqm = e["normalized_score"]["iqm"]
    assert iqm["value"] == pytest.approx((3 * 0.375 + 12 * 0.5 + 3 * 0.6) / 18, abs=1e-15)
    assert iqm["per_run"] == pytest.approx([0.5, 0.6, 0.375], abs=1e-15)
    assert iqm["run_range"] == pytest.approx([0.375, 0.6], abs=1e-15)
    assert iqm["ci95"] == pytest.approx([0.375, 0.6], abs=1e-15)
    assert e["return"]["iqm"]["per_run"] == pytest.approx([-60.0, -52.0, -70.0])
    cell = s["plants"][ENV]["scenarios"]["a"][AGENT]
    assert cell["seeds"] == 12 and cell["training_runs"] == 3
    assert (
        "training_runs" not in pols["cascade_pi"]
        and "per_run" not in pols["cascade_pi"]["normalized_score"]["iqm"]
    )
    md = report.markdown(s, r)
    spread = f"{report.num(0.375)} to {report.num(0.6)} (3 runs)"
    assert md.count(spread) == 2  # the plant's ranking table and the agents' table
    assert report.RUNS_NOTE in md and f"{AGENT}@run" not in md.split("## Failed")[0]


def test_three_runs_with_spread_the_ci_resamples_the_runs():
    """With episodes that vary, the agent's CI is wider than the pooled episodes' stratified
    CI, contains every run's IQM but for their own episodes' noise, and the runs' IQMs
    are those of each run scored alone."""
    s, _ = _summary({0: 0.0, 1: 8.0, 2: -10.0})
    est = s["plants"][ENV]["policies"][AGENT]["normalized_score"]["iqm"]
    alone = [
        _summary({k: off})[0]["plants"][ENV]["policies"][AGENT]["normalized_score"]["iqm"]
        for k, off in ((0, 0.0), (1, 8.0), (2, -10.0))
    ]
    assert est["per_run"] == pytest.approx([a["value"] for a in alone], abs=1e-15)
    lo, hi = est["ci95"]
    assert lo < min(est["per_run"]) + 0.02 and hi > max(est["per_run"]) - 0.02
    pooled = summarize(rows("pooled", {None: 0.0}), run_info([*FIXED, "pooled"]))
    pooled_ci = pooled[0]["plants"][ENV]["policies"]["pooled"]["normalized_score"]["iqm"]["ci95"]
    assert hi - lo > 3 * np.diff(pooled_ci)[0]


def test_failed_episodes_of_a_run_count_for_the_agent():
    r = rows(AGENT, {0: 0.0, 1: 8.0})
    bad = next(x for x in r if x["policy"] == f"{AGENT}@run1")
    bad.update(metrics=None, error="RuntimeError: x")
    s, _ = summarize(r, run_info([*FIXED, f"{AGENT}@run0", f"{AGENT}@run1"]))
    e = s["plants"][ENV]["policies"][AGENT]
    assert e["failed"] == 1 and e["episodes"] == 23 and e["admissible"] is False
    assert e["normalized_score"]["runs"] == 23 and len(e["normalized_score"]["iqm"]["per_run"]) == 2


def test_a_run_without_scored_episodes_is_left_out_of_the_score_s_runs():
    """Run 2 ran only scenario c, where cascade_pi_ff did not run (not normalized): the
    return counts three runs, the normalized score two."""

    def ran(x: dict) -> bool:
        if x["policy"] == f"{AGENT}@run2":
            return x["scenario"] == "c"
        return not (x["policy"] == "cascade_pi_ff" and x["scenario"] == "c")

    r = [x for x in rows(AGENT, {0: 0.0, 1: 8.0, 2: -10.0}) if ran(x)]
    names = [f"{AGENT}@run{k}" for k in range(3)]
    s, _ = summarize(r, run_info([*FIXED, *names]))
    e = s["plants"][ENV]["policies"][AGENT]
    assert e["training_runs"] == [0, 1, 2] and len(e["return"]["iqm"]["per_run"]) == 3
    assert len(e["normalized_score"]["iqm"]["per_run"]) == 2 and e["normalized_score"]["tasks"] == 2


def test_realism_counts_the_episodes_a_plant_engineer_would_reject():
    """Against cascade_pi_ff's travel 2.0 on the same scenario and seed: cascade_pi (1.5) is
    never rejected; the agent's travel 3.0 + 0.1 seed passes at 3x (6.0) until a seed or a
    scenario pushes it over; a trip and a limit cycle are rejected whatever the travel."""
    r = rows(AGENT, {None: 0.0})
    for row in r:
        if row["policy"] == AGENT and row["scenario"] == "b":
            row["metrics"]["valve_travel"] = 6.5 if row["seed"] == 1 else 1.0
        if row["policy"] == AGENT and row["scenario"] == "c" and row["seed"] == 3:
            row["metrics"]["tripped"] = 1.0
        row["metrics"]["quiet_p2p_K"] = 1.0
        if row["policy"] == "cascade_pi" and row["scenario"] == "a" and row["seed"] == 2:
            row["metrics"]["quiet_p2p_K"] = 2.5
    s, _ = summarize(r, run_info([*FIXED, AGENT]))
    pol = s["plants"][ENV]["policies"]
    assert pol["cascade_pi"]["realism"] == {
        "episodes": 12,
        "breaches": 1,
        "listed": ["cascade_pi a seed 2: quiet p2p 2.50 K against the reference's 1.00 K"],
    }
    assert pol[AGENT]["realism"]["episodes"] == 12 and pol[AGENT]["realism"]["breaches"] == 2
    assert pol[AGENT]["realism"]["listed"] == [
        f"{AGENT} b seed 1: travel 6.50 = 3.25x the reference's 2.00",
        f"{AGENT} c seed 3: tripped",
    ]
    assert all("realism" not in pol[p] for p in ("cascade_pi_ff", "oracle"))
    assert "1/12" in pages.baselines_markdown(s)
    md = pages.realism_markdown(s)  # baselines only: the agent is not listed
    assert "0 of 1 baseline-plant pairs have no episode" in md
    row = (
        "| `cascade_pi` | SupercriticalFSH-v0 | 1/12 | a seed 2: quiet p2p 2.50 K against "
        "the reference's 1.00 K |"
    )
    assert row in md and AGENT not in md


def test_training_table_gives_each_agent_s_budget_over_its_runs(tmp_path):
    """The zoo's training-budget table: one row per agent over its runs, the ranges of the
    runs' own metadata (hand-made runs: 1.2M and 2.5M decisions, 10 and 12.5 minutes; the
    first run's checkpoint passed its commissioning checks, the second's limit-cycled)."""
    best = {"return": -50.0, "iae_K_s": 1.0, "valve_travel": 1.0, "travel_ratio": 1.0}
    for run, (steps, minutes, ret, check) in enumerate(
        [(1_200_000, 10.0, -50.0, ""), (2_500_000, 12.5, -40.0, "quiet p2p 3 K")]
    ):
        meta = {
            "timesteps_trained": steps,
            "timesteps_of_best": steps // 2,
            "wall_time_s": 60 * minutes,
            "validation": {
                "best": {**best, "return": ret, "check": check},
                "reference": {"return": -90.0},
            },
        }
        stem = f"steamtemp__{ENV.split('/')[-1]}__trpo" + (f"__run{run}" if run else "")
        (tmp_path / f"{stem}.json").write_text(json.dumps(meta))
        (tmp_path / f"{stem}.zip").write_bytes(b"")
    lines = pages.training_markdown(tmp_path).splitlines()
    assert len(lines) == 3
    assert lines[2] == (
        f"| {ENV.split('/')[-1]} | sb3:trpo | model-free | 2 | 1.20 to 2.50M | "
        "0.60 to 1.25M | 10.0 to 12.5 | -50.0 to -40.0 (-90.0) | 1.00x | "
        "1 of 2 runs |"
    )
