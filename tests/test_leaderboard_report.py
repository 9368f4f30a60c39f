"""The leaderboard's summary on hand-made episode rows: admissibility (the valve-travel budget),
the per-plant ranking that lists admissible policies first, the cross-plant order
(summary.ORDER_RULE) and how the tables state it, the reason for a † and travel ratios
near the budget."""

from __future__ import annotations

from pathlib import Path

import pytest

from agents import stats
from agents.leaderboard import pages, report
from agents.leaderboard.summary import ONE, ORDER_RULE, ZERO, summarize

ENV = "steamtemp/SupercriticalFSH-v0"
SCENARIOS = ("a", "b")


def _rows(policies: dict[str, tuple[float, float, bool]], env: str = ENV) -> list[dict]:
    """Two scenarios x three seeds per policy: (return, valve travel, trips in scenario b)."""
    rows = []
    for p, (ret, travel, trip) in policies.items():
        for sc in SCENARIOS:
            for seed in range(3):
                m = {
                    "return": ret + 0.1 * seed,
                    "valve_travel": travel,
                    "valve_reversals": 4.0,
                    "iae_K_s": -ret,
                    "tripped": float(trip and sc == "b" and seed == 0),
                }
                rows.append({"env": env, "scenario": sc, "policy": p, "seed": seed, "metrics": m})
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
    run = {
        "envs": [ENV],
        "scenarios": list(SCENARIOS),
        "policies": {ENV: list(POLICIES)},
        "seeds": [0, 1, 2],
    }
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
    ranks = {p: pols[p]["rank"] for p in ("fine", ZERO, "cascade_pi", "chatter", "tripper")}
    # chatter has the best score and tripper the second best: both after every admissible one
    assert ranks == {"fine": 1, ZERO: 2, "cascade_pi": 3, "chatter": 4, "tripper": 5}


def test_the_budget_is_the_run_s_and_the_tables_show_ratio_and_mark():
    s = _summary(budget=3.5)
    assert s["plants"][ENV]["policies"]["chatter"]["admissible"] is True
    assert s["plants"][ENV]["policies"]["chatter"]["rank"] == 1
    md = report.markdown(_summary(), [])
    assert f"{report.INADMISSIBLE} travel 3.0x > 2x" in md  # the headline's cell: the reason
    assert f"{report.INADMISSIBLE} 1 trip, travel 0.5x" in md
    assert f"above {stats.TRAVEL_BUDGET:g}x {ZERO}'s" in md
    assert "| no †: travel 3.0x > 2x |" in md and "| no †: 1 trip |" in md and "| yes |" in md


def test_the_comparison_table_puts_the_policies_side_by_side_per_scenario():
    md = pages.comparison_markdown(_summary(), ["fine", "cascade_pi", "absent"])
    assert "#### SupercriticalFSH-v0" in md and "each cell is fine / cascade_pi / absent" in md
    rows = {ln.split(" | ")[0].lstrip("| "): ln for ln in md.splitlines() if ln.startswith("| a")}
    # scenario a: returns -59.9 and -109.9 (seed means), IAE 60 and 110, travel 3.80 and 1.50;
    # the absent policy and the quiet p2p (not in these rows) read "-"
    assert rows["a"] == "| a | -59.9 / -109.9 / - | 60 / 110 / - | 3.80 / 1.50 / - | - / - / - |"


# --------------------------------------------------------------------------- cross-plant order
OTHER = "steamtemp/Cascade300MW-v0"
#: Per plant, (return, travel): the score is (return + 100) / 80 (0 = -100, 1 = -20), the
#: reference's travel 2, so a travel of 6 is 3x, over the budget.
PLANT_A = {
    ZERO: (-100.0, 2.0),
    ONE: (-20.0, 2.0),
    "cascade_pi": (-110.0, 1.5),
    "mpc": (-36.0, 6.0),  # 0.8, not admissible: counts as 0
    "tuned": (-76.0, 2.0),  # 0.3
    "chatter": (-140.0, 6.0),  # -0.5, not admissible: counts as -0.5
}
PLANT_B = {
    ZERO: (-100.0, 2.0),
    ONE: (-20.0, 2.0),
    "cascade_pi": (-110.0, 1.5),
    "mpc": (-36.0, 2.0),
    "tuned": (-76.0, 2.0),
    "chatter": (-100.0, 2.0),
    "agent": (-28.0, 2.0),  # 0.9, but on plant B only
}


def _two_plants() -> dict:
    rows = [
        *_rows({p: (*v, False) for p, v in PLANT_A.items()}),
        *_rows({p: (*v, False) for p, v in PLANT_B.items()}, OTHER),
    ]
    run = {
        "envs": [ENV, OTHER],
        "scenarios": list(SCENARIOS),
        "seeds": [0, 1, 2],
        "policies": {ENV: list(PLANT_A), OTHER: list(PLANT_B)},
        "travel_budget": 2.0,
    }
    return summarize(rows, run)[0]


def test_the_order_is_the_mean_score_an_inadmissible_plant_counting_at_most_0():
    """mpc scores 0.8 on both plants but is over the budget on A: (0 + 0.8) / 2 = 0.4 puts it
    above tuned (0.3 on both), though its mean per-plant rank (4 on A, 2 on B: 3) is worse
    than tuned's (1 and 3: 2). chatter, over the budget on A at -0.5, keeps the -0.5: being
    inadmissible never helps, so it stays below cascade_pi (-0.125 on both). agent, best
    on B but scored on one plant only, comes after every policy scored on both."""
    s = _two_plants()
    order = [e["policy"] for e in s["ranking"]]
    assert order == ["mpc", "tuned", ZERO, "cascade_pi", "chatter", "agent"]
    by = {e["policy"]: e for e in s["ranking"]}
    assert by["mpc"]["score"] == pytest.approx(0.4) and by["mpc"]["mean_rank"] == 3.0
    assert by["tuned"]["score"] == pytest.approx(0.3) and by["tuned"]["mean_rank"] == 2.0
    assert by["chatter"]["score"] == pytest.approx(-0.25)
    assert by["cascade_pi"]["score"] == pytest.approx(-0.125)
    assert (by["mpc"]["plants"], by["mpc"]["admissible_plants"]) == (2, 1)
    assert (by["agent"]["plants"], by["agent"]["admissible_plants"]) == (1, 1)
    assert [e["position"] for e in s["ranking"]] == [1, 2, 3, 4, 5, 6]
    pols = s["plants"][ENV]["policies"]
    assert pols["mpc"]["rank"] == 4 and pols["tuned"]["rank"] == 1  # per plant: unchanged


def test_the_headline_states_its_order_and_the_reasons():
    s = _two_plants()
    text = report.headline_markdown(s, margins=False)
    assert f"Rows are {ORDER_RULE}." in text
    rows = {r.split(" | ")[1]: r for r in text.splitlines() if r.startswith("| ")}
    assert rows["mpc"] == (
        "| 1 | mpc | 0.80 [0.80, 0.80] † travel 3.0x > 2x | "
        "0.80 [0.80, 0.80] (2), travel 1.0x | 0.40, † on 1 |"
    )
    assert rows["agent"].endswith("| 0.90 (1 of 2 plants) |")
    assert rows["tuned"].endswith("| 0.30 |")
    assert "score over plants" in text and "mean rank" not in text
    assert ORDER_RULE in report.console(s)


def test_the_docs_and_the_readme_state_the_order():
    """docs/leaderboard.md states the rule word for word (code spans aside); the README's
    leaderboard section says it in short."""
    root = Path(__file__).parents[1]
    doc = " ".join((root / "docs" / "leaderboard.md").read_text().replace("`", "").split())
    assert ORDER_RULE in doc
    readme = " ".join((root / "README.md").read_text().split())
    rule = (
        "ordered by the mean over plants of each policy's score, a positive score on a "
        "plant where it is not admissible counting as 0"
    )
    assert rule in readme


@pytest.mark.parametrize(
    ("r", "text"),
    [
        (1.7, "1.7x"),
        (2.04, "2.04x"),
        (1.96, "1.96x"),
        (2.05, "2.05x"),
        (2.06, "2.1x"),
        (1.94, "1.9x"),
        (2.0, "2.0x"),
        (2.004, "2.004x"),
        (1.9999, "1.9999x"),
        (9.5, "9.5x"),
    ],
)
def test_a_travel_ratio_shows_on_which_side_of_the_budget_it_is(r, text):
    assert report.ratio(r, 2.0) == text
    assert report.ratio(r) == f"{r:.1f}x"  # no budget: one decimal


def test_the_reason_names_every_cause():
    pe = {"admissible": False, "travel_ratio": 2.04, "trips": 1, "failed": 2}
    assert report.inadmissible_reason(pe, 2.0) == "travel 2.04x > 2x, 1 trip, 2 failed episodes"
    pe = {"admissible": False, "travel_ratio": 1.2, "trips": 3, "failed": 0}
    assert report.inadmissible_reason(pe, 2.0) == "3 trips"
    assert report.inadmissible_reason({"admissible": True, "travel_ratio": 1.2}, 2.0) == ""
