"""The leaderboard's model-mismatch rows and its robustness column.

A controller is commissioned on a model and then runs a unit that differs from it. The
leaderboard therefore also runs every policy but the references, commissioned on the
NOMINAL plant (a baseline's step tests and feed-forward fit see the model; a trained
agent is the file it is), unchanged on each variant of
:func:`steamtemp_gym.plants.perturb.mismatch` under :data:`SCENARIO`, on the run's seeds.
Such a row's scenario is labelled ``mismatch:<variant>``; these rows are kept out of the
normalized score, the ranking and the realism count.

A policy's robustness on a variant is its mean return there over its mean return on the
nominal plant under the same scenario, training runs and seeds. Returns are costs (<= 0):
1.00 is as good as on the model, 1.30 is 30 % more cost, below 1 the variant is easier
for that policy. Per variant the summary also names the best admissible policy that is
not a baseline or a reference (a trained agent, your own) and sets its return against
the industrial reference's on the same variant.
"""

from __future__ import annotations

from collections import defaultdict
from typing import Any

import numpy as np

import baselines
from agents import specs
from steamtemp_gym import catalog
from steamtemp_gym.plants import perturb

#: Row label prefix of a mismatch episode: ``mismatch:<variant>``.
PREFIX = "mismatch:"
#: The scenario every variant runs (its nominal rows are the run's own).
SCENARIO = "load_ramp_100_50"


def labels(env_id: str) -> dict[str, dict[str, Any]]:
    """``mismatch:<variant>`` -> the variant's ``params`` for ``env_id`` (empty for a plant
    without variants and for a registered variant id: its parameters are not the plant's
    defaults that the mismatch set scales)."""
    if env_id not in catalog.PLANTS:
        return {}
    return {PREFIX + v: p for v, p in perturb.mismatch(env_id).items()}


def is_label(scenario: str) -> bool:
    """Whether a row's scenario label is a mismatch variant."""
    return scenario.startswith(PREFIX)


def summarize(
    rows: list[dict], env_id: str, policies: dict[str, Any], zero: str, references: tuple[str, ...]
) -> dict[str, Any] | None:
    """A plant's ``robustness`` entry from the run's rows (``policies``: the plant's
    ranked entries, for admissibility); None if the run has no mismatch rows there."""
    nominal: dict[tuple[str, int], float] = {}
    by: dict[str, dict[str, list[dict]]] = defaultdict(lambda: defaultdict(list))
    failed: dict[str, int] = defaultdict(int)
    for r in rows:
        if r["env"] != env_id:
            continue
        if r["scenario"] == SCENARIO and not r.get("error"):
            nominal[r["policy"], r["seed"]] = r["metrics"]["return"]
        elif is_label(r["scenario"]):
            name = specs.split_run(r["policy"])[0]
            if r.get("error"):
                failed[name] += 1
            else:
                by[name][r["scenario"][len(PREFIX) :]].append(r)
    if not by and not failed:
        return None
    declared = [v[len(PREFIX) :] for v in labels(env_id)]
    variants = declared or sorted({v for d in by.values() for v in d})
    out: dict[str, Any] = {}
    for name in dict.fromkeys([*by, *failed]):
        entry: dict[str, Any] = {"episodes": 0, "trips": 0, "failed": failed[name], "variants": {}}
        paired_nominal: list[float] = []
        for v in variants:
            got = by[name].get(v, [])
            if not got:
                continue
            pairs = [
                (r["metrics"]["return"], nominal[r["policy"], r["seed"]])
                for r in got
                if (r["policy"], r["seed"]) in nominal
            ]
            var_mean = float(np.mean([r["metrics"]["return"] for r in got]))
            cell: dict[str, Any] = {
                "return": var_mean,
                "trips": int(sum(r["metrics"]["tripped"] > 0 for r in got)),
            }
            if pairs:
                num, den = (float(np.mean(x)) for x in zip(*pairs, strict=True))
                if den != 0.0:
                    cell["relative"] = num / den
                paired_nominal += [d for _, d in pairs]
            entry["variants"][v] = cell
            entry["episodes"] += len(got)
            entry["trips"] += cell["trips"]
        if paired_nominal:
            entry["nominal_return"] = float(np.mean(paired_nominal))
        rel = {v: c["relative"] for v, c in entry["variants"].items() if "relative" in c}
        if rel:
            worst = max(rel, key=rel.get)
            entry["worst"] = {"variant": worst, "relative": rel[worst]}
        out[name] = entry
    challengers = [
        p
        for p in out
        if p not in baselines.NAMES
        and p not in references
        and policies.get(p, {}).get("admissible")
    ]
    versus: dict[str, Any] = {}
    for v in variants:
        z = out.get(zero, {}).get("variants", {}).get(v)
        if z is None:
            continue
        ok = [p for p in challengers if v in out[p]["variants"] and out[p]["failed"] == 0]
        best = max(ok, key=lambda p: out[p]["variants"][v]["return"]) if ok else None
        cell = {"zero_return": z["return"], "policy": best}
        if best is not None:
            cell["return"] = out[best]["variants"][v]["return"]
            cell["at_least_zero"] = bool(cell["return"] >= z["return"])
        versus[v] = cell
    return {"scenario": SCENARIO, "variants": variants, "policies": out, "versus": versus}


def _cell(c: dict[str, Any] | None) -> str:
    if c is None:
        return "-"
    rel = f" ({c['relative']:.2f})" if "relative" in c else ""
    trip = f", {c['trips']} trips" if c["trips"] else ""
    return f"{c['return']:.1f}{rel}{trip}"


def _order(plant: dict[str, Any]) -> list[str]:
    """The plant's policies with robustness entries, in the plant's ranking order."""
    pols, rob = plant["policies"], plant["robustness"]["policies"]
    return sorted(rob, key=lambda k: (pols.get(k, {}).get("rank", 10**6), k))


def markdown(summary: dict[str, Any], zero: str) -> str:
    """Per plant: each policy's mean return on every variant with its robustness (the
    return over its nominal return), the worst variant, and per variant the best admissible
    non-baseline policy against ``zero``. Empty if the run has no mismatch rows."""
    plants = {e: p for e, p in summary["plants"].items() if "robustness" in p}
    if not plants:
        return ""
    n = len(summary["run"]["seeds"])
    lines = [
        f"Every policy but the references commissioned on the nominal plant and run "
        f"unchanged on the model-mismatch variants (docs/robustness.md) under "
        f"`{SCENARIO}` ({n} seeds; a trained agent over its training runs). Cells: mean "
        "return on the variant (its ratio to the same policy's mean return on the "
        "nominal plant, same runs and seeds: 1.00 as good as on the model, 1.30 = 30 % "
        "more cost); worst: the variant with the highest ratio.",
        "",
    ]
    for env_id, p in plants.items():
        rob = p["robustness"]
        header = ["policy", "nominal return", *rob["variants"], "worst", "failed"]
        body = []
        for k in _order(p):
            e = rob["policies"][k]
            worst = e.get("worst")
            body.append(
                [
                    k,
                    f"{e['nominal_return']:.1f}" if "nominal_return" in e else "-",
                    *(_cell(e["variants"].get(v)) for v in rob["variants"]),
                    f"{worst['relative']:.2f} ({worst['variant']})" if worst else "-",
                    str(e["failed"]),
                ]
            )
        lines += [
            f"#### {env_id.split('/')[-1]}",
            "",
            "| " + " | ".join(header) + " |",
            "|" + "---|" * len(header),
            *["| " + " | ".join(r) + " |" for r in body],
            "",
            _versus(rob, zero),
            "",
        ]
    return "\n".join(lines)


def _versus(rob: dict[str, Any], zero: str) -> str:
    parts = []
    for v, c in rob["versus"].items():
        if c["policy"] is None:
            parts.append(f"{v}: no admissible non-baseline policy")
        else:
            sign = ">=" if c["at_least_zero"] else "<"
            parts.append(f"{v}: {c['policy']} {c['return']:.1f} {sign} {c['zero_return']:.1f}")
    won = sum(bool(c.get("at_least_zero")) for c in rob["versus"].values())
    return (
        f"Best admissible non-baseline policy against `{zero}` on each variant "
        f"({won} of {len(rob['versus'])} at least as good): " + "; ".join(parts) + "."
    )


def worst_markdown(summary: dict[str, Any]) -> str:
    """The robustness column: policy x plant, the worst variant's ratio (README)."""
    plants = [e for e, p in summary["plants"].items() if "robustness" in p]
    if not plants:
        return ""
    names = list(dict.fromkeys(k for e in plants for k in _order(summary["plants"][e])))
    header = ["policy", *[e.split("/")[-1] for e in plants]]
    body = []
    for k in names:
        cells = []
        for e in plants:
            w = summary["plants"][e]["robustness"]["policies"].get(k, {}).get("worst")
            cells.append(f"{w['relative']:.2f} ({w['variant']})" if w else "-")
        body.append([k, *cells])
    return (
        "\n".join(
            [
                "| " + " | ".join(header) + " |",
                "|" + "---|" * len(header),
                *["| " + " | ".join(r) + " |" for r in body],
            ]
        )
        + "\n"
    )
