"""The per-env reference pages (docs/envs/, steamtemp_gym/docs.py): up to date with the code
(regenerated in memory and compared), and what they list is what an env has."""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass

import gymnasium as gym

import steamtemp_gym
from steamtemp_gym import catalog, docs, scenarios

ENV = "steamtemp/Cascade300MW-v0"


def test_pages_are_up_to_date():
    """Run ``python -m steamtemp_gym.docs`` after adding or changing a plant, a signal, a
    scenario or a parameter's note: a plant's page is part of adding it."""
    generated = docs.pages()
    on_disk = {p.name: p.read_text(encoding="utf-8") for p in docs.DOCS_DIR.glob("*.md")}
    missing = sorted(set(generated) - set(on_disk))
    extra = sorted(set(on_disk) - set(generated))
    assert not missing and not extra, (
        f"missing pages {missing}, pages of no env id {extra}; run python -m steamtemp_gym.docs"
    )
    stale = [n for n in generated if on_disk[n] != generated[n]]
    assert not stale, f"out of date: {stale}; run python -m steamtemp_gym.docs"
    assert docs.main(["--check"]) == 0


def _column(text: str, section: str, col: int = 0) -> list[str]:
    """Column ``col`` of the first table under ``## section``, backticks removed."""
    part = text.split(f"## {section}\n", 1)[1].split("\n## ", 1)[0]
    table = part[part.index("\n| ") :].strip().split("\n\n")[0]  # up to the next blank line
    rows = [r for r in table.splitlines()[2:] if not r.startswith("| **")]
    return [r.split(" | ")[col].strip("| `") for r in rows]


def test_a_page_lists_what_the_env_has():
    text = docs.page(ENV)
    env = gym.make(ENV, scenario="setpoint_step")
    _, info = env.reset(seed=0)
    sig = env.unwrapped.signals
    assert _column(text, "Observation", 1) == [s.name for s in sig.observation]
    assert _column(text, "Action", 1) == [s.name for s in sig.action]
    assert _column(text, "Info") == list(info)
    params = type(env.unwrapped.plant.params)
    assert _column(text, "Parameters") == [f.name for f in dataclasses.fields(params)]
    named = [n for n in scenarios.names(ENV) if n != scenarios.RANDOM]
    assert _column(text, "Scenarios") == named
    assert "`setpoint_step_535_545`" in text  # the plant's own scenario too
    assert re.search(r"\| `dt_s` \| float \| 1\.0 \| s \| sampling period T_s \(paper", text)
    assert docs.page_name(ENV) == "Cascade300MW-v0.md"
    own = [i for i in steamtemp_gym.ENV_IDS if catalog.packaged(i)]  # not the toy plant's
    assert set(docs.pages()) == {"README.md", *(docs.page_name(i) for i in own)}


@dataclass(frozen=True)
class _Documented:
    # --- rating (the paper
    #     unless noted)
    flow_kg_s: float = 1.0  # rated flow (paper)
    #: a note above
    #: on two lines
    time_s: float = 2.0
    count: int = 3
    # --- a second section
    share_fraction: float = 0.5  # of the flow (unverified)


def test_field_notes_read_the_comments_of_the_source():
    notes, sections = docs.field_notes(_Documented)
    assert notes == {
        "flow_kg_s": "rated flow (paper)",
        "time_s": "a note above on two lines",
        "count": "",
        "share_fraction": "of the flow (unverified)",
    }
    assert sections == {
        "flow_kg_s": "rating (the paper unless noted)",
        "time_s": "rating (the paper unless noted)",
        "count": "rating (the paper unless noted)",
        "share_fraction": "a second section",
    }
    assert [
        docs.unit_of(n)
        for n in ("flow_kg_s", "time_s", "count", "share_fraction", "lead_gain_K_s_kg", "T_out_C")
    ] == ["kg/s", "s", "", "fraction", "K s/kg", "C"]
