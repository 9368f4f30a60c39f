"""The leaderboard's model-mismatch rows and robustness column
(agents/leaderboard/mismatch.py): each policy commissioned on the nominal plant and run on
the variants, kept out of the scores, summarized against its nominal return."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import pytest

from agents import leaderboard as lb
from agents import specs
from agents.evaluation import run_episode
from agents.leaderboard import cli, mismatch
from agents.leaderboard.plan import DEFAULT_SCENARIOS, Plan, build_plan
from agents.leaderboard.summary import ZERO
from steamtemp_gym.plants import perturb

SCHEMA = Path(__file__).parents[1] / "docs" / "leaderboard_schema.json"
ENV = "steamtemp/Cascade300MW-v0"  # the cheapest plant to build
FSH = "steamtemp/SupercriticalFSH-v0"


def _run(out: Path, *extra: str) -> dict:
    lb.main(
        [
            "--envs",
            ENV,
            "--policies",
            "cascade_pi",
            "--scenarios",
            f"{mismatch.SCENARIO},setpoint_step",
            "--seeds",
            "0",
            "--no-oracle",
            "--jobs",
            "1",
            "--out",
            str(out),
            *extra,
        ]
    )
    return json.loads((out / "leaderboard.json").read_text())


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> tuple[dict, dict]:
    tmp = tmp_path_factory.mktemp("mismatch")
    return _run(tmp / "with"), _run(tmp / "without", "--no-mismatch")


def test_a_mismatch_row_is_the_model_commissioned_policy_on_the_variant(runs):
    """The row of cascade_pi_ff on a variant is the policy commissioned on the nominal
    plant and run on the variant, bit for bit, not a controller retuned on the variant."""
    doc, _ = runs
    variant = "high_gain_slow"
    row = next(
        r
        for r in doc["episodes"]
        if r["policy"] == ZERO and r["scenario"] == mismatch.PREFIX + variant
    )
    params = perturb.mismatch(ENV)[variant]
    unit = gym.make(ENV, scenario=mismatch.SCENARIO, params=params)
    model = gym.make(ENV, scenario=mismatch.SCENARIO)
    want = run_episode(unit, specs.parse(ZERO, references=True).make(ENV, model), 0)["metrics"][
        "return"
    ]
    assert row["metrics"]["return"] == want
    retuned = run_episode(unit, specs.parse(ZERO, references=True).make(ENV, unit), 0)["metrics"][
        "return"
    ]
    assert retuned != want


def test_rows_policies_and_scores(runs):
    """Every policy but the references runs on every variant; the nominal rows, their
    fingerprints and every score are those of a run without the mismatch rows."""
    doc, plain = runs
    jsonschema = pytest.importorskip("jsonschema")
    jsonschema.validate(doc, json.loads(SCHEMA.read_text()))
    jsonschema.validate(plain, json.loads(SCHEMA.read_text()))
    mis = [r for r in doc["episodes"] if mismatch.is_label(r["scenario"])]
    variants = list(perturb.mismatch(ENV))
    assert sorted({(r["policy"], r["scenario"]) for r in mis}) == sorted(
        (p, mismatch.PREFIX + v) for p in ("cascade_pi", ZERO) for v in variants
    )
    nominal = [r for r in doc["episodes"] if not mismatch.is_label(r["scenario"])]
    assert nominal == plain["episodes"]
    assert doc["run"]["mismatch"] == {ENV: variants} and plain["run"]["mismatch"] == {}
    rob = doc["plants"][ENV]["robustness"]
    plants = {
        e: {k: v for k, v in p.items() if k != "robustness"} for e, p in doc["plants"].items()
    }
    assert plants == plain["plants"] and doc["ranking"] == plain["ranking"]
    for p in ("cascade_pi", ZERO):  # the ratio over the same policy's nominal episode
        nom = next(
            r["metrics"]["return"]
            for r in nominal
            if r["policy"] == p and r["scenario"] == mismatch.SCENARIO
        )
        e = rob["policies"][p]
        assert e["nominal_return"] == nom and e["episodes"] == len(variants)
        for v in variants:
            ret = next(
                r["metrics"]["return"]
                for r in mis
                if r["policy"] == p and r["scenario"] == mismatch.PREFIX + v
            )
            assert e["variants"][v]["return"] == ret
            assert e["variants"][v]["relative"] == pytest.approx(ret / nom, rel=1e-15)
        worst = max(variants, key=lambda v: e["variants"][v]["relative"])
        assert e["worst"] == {"variant": worst, "relative": e["variants"][worst]["relative"]}
    assert all(c["policy"] is None for c in rob["versus"].values())  # only baselines ran


def test_markdown_has_the_robustness_section(runs):
    doc, plain = runs
    text = mismatch.markdown(doc, ZERO)
    assert "#### Cascade300MW-v0" in text and "| cascade_pi_ff |" in text
    assert "(0 of 4 at least as good)" in text
    assert mismatch.markdown(plain, ZERO) == "" and mismatch.worst_markdown(plain) == ""
    worst = mismatch.worst_markdown(doc).splitlines()
    assert worst[0] == "| policy | Cascade300MW-v0 |" and len(worst) == 4


def _row(policy: str, scenario: str, seed: int, ret: float, tripped: float = 0.0) -> dict:
    return {
        "env": FSH,
        "scenario": scenario,
        "policy": policy,
        "seed": seed,
        "metrics": {"return": ret, "tripped": tripped},
    }


def test_summary_by_hand():
    """Two training runs and two seeds: the ratio pairs each variant episode with the same
    run's and seed's nominal one; the best admissible non-baseline policy per variant is
    set against the industrial reference; a policy without nominal episodes gets no ratio."""
    v1, v2 = list(perturb.mismatch(FSH))[:2]
    ramp, m1, m2 = mismatch.SCENARIO, mismatch.PREFIX + v1, mismatch.PREFIX + v2
    rows = [
        _row(ZERO, ramp, 0, -100),
        _row(ZERO, ramp, 1, -120),
        _row(ZERO, m1, 0, -110),
        _row(ZERO, m1, 1, -150),
        _row(ZERO, m2, 0, -40),
        _row(ZERO, m2, 1, -60),
        _row("sb3:x@run0", ramp, 0, -50),
        _row("sb3:x@run0", ramp, 1, -60),
        _row("sb3:x@run1", ramp, 0, -70),
        _row("sb3:x@run1", ramp, 1, -80),
        _row("sb3:x@run0", m1, 0, -55),
        _row("sb3:x@run0", m1, 1, -66),
        _row("sb3:x@run1", m1, 0, -77),
        _row("sb3:x@run1", m1, 1, -88, tripped=1.0),
        _row("sb3:x@run0", m2, 0, -500),
        _row("sb3:x@run1", m2, 0, -300),
        _row("mine", m1, 0, -10),  # never run on the nominal plant
        {**_row("sb3:x@run1", m2, 1, 0.0), "metrics": None, "error": "boom"},
    ]
    pols = {"sb3:x": {"admissible": True}, "mine": {"admissible": False}, ZERO: {}}
    s = mismatch.summarize(rows, FSH, pols, ZERO, ("oracle", "frozen_valve"))
    z = s["policies"][ZERO]
    assert z["variants"][v1] == {"return": -130.0, "relative": -130 / -110, "trips": 0}
    assert z["nominal_return"] == -110.0
    a = s["policies"]["sb3:x"]
    assert a["variants"][v1]["return"] == pytest.approx(-71.5)
    assert a["variants"][v1]["relative"] == pytest.approx(-71.5 / -65)
    assert a["variants"][v2]["relative"] == pytest.approx(-400 / -60)  # seeds 0 of both runs
    assert a["trips"] == 1 and a["failed"] == 1 and a["episodes"] == 6
    assert a["worst"]["variant"] == v2
    assert "relative" not in s["policies"]["mine"]["variants"][v1]
    assert "worst" not in s["policies"]["mine"] and "nominal_return" not in s["policies"]["mine"]
    assert s["versus"][v1] == {"zero_return": -130.0, "policy": None}  # sb3:x failed an episode
    assert mismatch.summarize(rows[:2], FSH, pols, ZERO, ()) is None
    ok = [r for r in rows if not r.get("error")]
    s = mismatch.summarize(ok, FSH, pols, ZERO, ())
    assert s["versus"][v1] == {
        "zero_return": -130.0,
        "policy": "sb3:x",
        "return": -71.5,
        "at_least_zero": True,
    }
    assert s["versus"][v2]["at_least_zero"] is False


def test_flags_decide_the_mismatch_rows(tmp_path):
    """Mismatch rows only with load_ramp_100_50 among the scenarios and without
    --no-mismatch; never for the references."""
    ap = cli.make_parser()

    def plan(*argv: str) -> Plan:
        return build_plan(
            ap,
            ap.parse_args(
                ["--envs", ENV, "--policies", "cascade_pi", "--out", str(tmp_path / "o"), *argv]
            ),
        )

    p = plan("--scenarios", "load_ramp_100_50")
    labels = [mismatch.PREFIX + v for v in perturb.mismatch(ENV)]
    assert p.scenarios_of(ENV) == ["load_ramp_100_50", *labels]
    assert p.policies_of(ENV, labels[0]) == ["cascade_pi", ZERO]
    assert "oracle" in p.policies_of(ENV, "load_ramp_100_50")
    assert plan("--scenarios", "setpoint_step").scenarios_of(ENV) == ["setpoint_step"]
    assert plan("--no-mismatch").scenarios_of(ENV) == list(DEFAULT_SCENARIOS)
    with pytest.raises(SystemExit):  # a label is not a scenario one can ask for
        plan("--scenarios", labels[0])
