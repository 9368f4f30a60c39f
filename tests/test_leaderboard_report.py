"""The leaderboard's summary on hand-made episode rows: admissibility (the valve-travel budget)
and the ranking that lists admissible policies first."""

from __future__ import annotations

import pytest

from agents import stats
from agents.leaderboard import report
from agents.leaderboard.summary import ONE, ZERO, summarize

ENV = "steamtemp/SupercriticalFSH-v0"
SCENARIOS = ("a", "b")


def _rows(policies: dict[str, tuple[float, float, bool]]) -> list[dict]:
    """Two scenarios x three seeds per policy: (return, valve travel, trips in scenario b)."""
    rows = []
    for p, (ret, travel, trip) in policies.items():
        for sc in SCENARIOS:
            for seed in range(3):
                m = {"return": ret + 0.1 * seed, "valve_travel": travel, "valve_reversals": 4.0,
                     "iae_K_s": -ret, "tripped": float(trip and sc == "b" and seed == 0)}
                rows.append({"env": ENV, "scenario": sc, "policy": p, "seed": seed, "metrics": m})
    return rows


POLICIES = {
    ZERO: (-100.0, 2.0, False),
    ONE: (-20.0, 3.0, False),
    "cascade_pi": (-110.0, 1.5, False),
    "chatter": (-40.0, 6.0, False),  # best score, travel 3x the reference's
    "fine": (-60.0, 3.8, False),  # within 2x
    "tripper": (-50.0, 1.0, True),
}


def _summary(budget: float | None = None) -> dict:
    run = {"envs": [ENV], "scenarios": list(SCENARIOS), "policies": {ENV: list(POLICIES)},
           "seeds": [0, 1, 2]}  # fmt: skip
    if budget is not None:
        run["travel_budget"] = budget
    return summarize(_rows(POLICIES), run)[0]


def test_admissible_policies_rank_first_and_the_others_are_marked():
    pols = _summary()["plants"][ENV]["policies"]
    assert pols["chatter"]["travel_ratio"] == pytest.approx(3.0)
    assert pols["fine"]["admissible"] and pols["cascade_pi"]["admissible"]
    assert pols["chatter"]["admissible"] is False  # travel over 2x
    assert pols["tripper"]["admissible"] is False  # a trip
    assert "admissible" not in pols[ONE] and "rank" not in pols[ONE]
    ranks = {p: pols[p]["rank"] for p in ("fine", ZERO, "cascade_pi", "chatter",
                                          "tripper")}  # fmt: skip
    # chatter has the best score and tripper the second best: both after every admissible one
    assert ranks == {"fine": 1, ZERO: 2, "cascade_pi": 3, "chatter": 4, "tripper": 5}


def test_the_budget_is_the_run_s_and_the_tables_show_ratio_and_mark():
    s = _summary(budget=3.5)
    assert s["plants"][ENV]["policies"]["chatter"]["admissible"] is True
    assert s["plants"][ENV]["policies"]["chatter"]["rank"] == 1
    md = report.markdown(_summary(), [])
    assert f"travel 3.0x {report.INADMISSIBLE}" in md
    assert f"above {stats.TRAVEL_BUDGET:g}x {ZERO}'s" in md
    assert "| no †" in md and "| yes |" in md


def test_the_comparison_table_puts_the_policies_side_by_side_per_scenario():
    md = report.comparison_markdown(_summary(), ["fine", "cascade_pi", "absent"])
    assert "#### SupercriticalFSH-v0" in md and "each cell is fine / cascade_pi / absent" in md
    rows = {ln.split(" | ")[0].lstrip("| "): ln for ln in md.splitlines() if ln.startswith("| a")}
    # scenario a: returns -59.9 and -109.9 (seed means), IAE 60 and 110, travel 3.80 and 1.50;
    # the absent policy and the quiet p2p (not in these rows) read "-"
    assert rows["a"] == "| a | -59.9 / -109.9 / - | 60 / 110 / - | 3.80 / 1.50 / - | - / - / - |"
