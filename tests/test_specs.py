"""The Spec of a policy carries what the leaderboard asks of it (agents/specs.py): reference
or ranked, which end of the score, whether it runs in a process of its own, and what its
digest covers; the leaderboard parses each name once and decides a batch's process once."""

from __future__ import annotations

import pytest

from agents import specs
from agents.leaderboard import episodes
from agents.leaderboard.plan import Plan, policy_digest

ENV = "steamtemp/Cascade300MW-v0"


def test_references_parse_only_where_asked():
    for name in specs.REFERENCES:
        with pytest.raises(ValueError, match="unknown policy"):
            specs.parse(name)  # steamtemp-check --policy, datasets: no reference
        assert specs.parse(name, references=True).reference


@pytest.mark.parametrize(
    ("name", "kind", "reference", "end", "own"),
    [
        ("oracle", specs.ORACLE, True, 1, False),
        ("frozen_valve", specs.FROZEN, True, None, False),
        ("cascade_pi_ff", specs.BASELINE, False, 0, False),
        ("cascade_pi", specs.BASELINE, False, None, False),
        ("tests.toy_plant:ToyLags", specs.FACTORY, False, None, True),
    ],
)
def test_a_spec_carries_its_properties(name, kind, reference, end, own):
    spec = specs.parse(name, references=True)
    assert (spec.kind, spec.reference, spec.score_end, spec.own_process) == (
        kind,
        reference,
        end,
        own,
    )
    assert spec.available(ENV)


def test_what_a_digest_covers():
    oracle = specs.parse(specs.ONE, references=True)
    assert oracle.modules("cem") == ("agents.oracle",)
    assert oracle.modules("optimum") == ("agents.oracle", specs.OPTIMUM_MODULE)
    assert specs.parse(specs.FROZEN_VALVE, references=True).modules() == ("agents.difficulty",)
    assert specs.parse("cascade_pi").modules() == ("baselines.cascade_pi",)
    assert specs.parse("tests.toy_plant:ToyLags").modules() == ()
    # the oracle's digest follows its engine, and names its incumbents
    assert oracle.digest(ENV, "cem") != oracle.digest(ENV, "optimum")
    assert all(f"+{i}:" in oracle.digest(ENV) for i in ("mpc_linear", specs.ZERO))
    assert policy_digest(ENV, specs.ONE, "cem") == oracle.digest(ENV, "cem")


def test_a_plan_parses_each_name_once(monkeypatch):
    plan = Plan(envs=[ENV], scenarios=[], seeds=[0], policies={ENV: ["cascade_pi"]})
    first = plan.spec("cascade_pi")
    monkeypatch.setattr(specs, "parse", lambda *a, **k: pytest.fail("parsed again"))
    assert plan.spec("cascade_pi") is first


def test_a_batch_decides_its_process_once(monkeypatch):
    """run_units asks the batch's Spec once; both run paths (side by side, then seed by seed
    when that raises) take that answer."""
    asked = []
    real = specs.Spec.own_process

    def own(spec):
        asked.append(spec.name)
        return real.fget(spec)

    monkeypatch.setattr(specs.Spec, "own_process", property(own))
    unit = episodes.Unit(ENV, "nonsense", "nonsense", "cascade_pi", [0, 1], "fp", None)
    with pytest.raises(ValueError):  # no such scenario: both paths fail to make the env
        episodes.run_units([unit])
    assert asked == ["cascade_pi"]
