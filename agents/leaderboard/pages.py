"""The tables scripts/update_readme_leaderboard.py writes into the documentation pages,
from leaderboard.json's summary and the zoo's files: the training budget of docs/agents/zoo.md,
the baselines' table and the rejected episodes of docs/baselines.md and the comparison of
docs/baselines/mpc_linear.md; built from the cells of agents/leaderboard/report.py.
"""

from __future__ import annotations

from typing import Any

import baselines
from agents import stats
from agents.leaderboard.report import (
    COLUMNS,
    INADMISSIBLE,
    admissibility_note,
    budget,
    cell,
    num,
    rejected_cell,
    rejected_note,
    table_lines,
    travel_cell,
)


def training_markdown(directory: Any) -> str:
    """What each trained agent in ``directory`` (steamtemp-train's files: the zoo) cost and
    reached, over its runs: decisions trained, those of the chosen checkpoint, wall time,
    that checkpoint's validation return and travel (the reference's return on the same
    episodes alongside) and how many runs' chosen checkpoints passed the commissioning
    checks (agents/validation.py; "-" for runs trained before checkpoints ran them); an
    offline clone (agents/behaviour_cloning.py) its transitions, epochs and fit time. The
    zoo's training-budget table of docs/agents/zoo.md."""
    import json

    import agents
    from agents.files import steamtemp_files, zoo_runs

    def span(xs: list[float], fmt: str) -> str:
        lo, hi = fmt.format(min(xs)), fmt.format(max(xs))
        return lo if lo == hi else f"{lo} to {hi}"

    header = [
        "plant",
        "agent",
        "kind",
        "runs",
        "decisions trained",
        "decisions at the chosen checkpoint",
        "wall time per run [min]",
        "validation return (reference's)",
        "validation travel / reference's",
        "commissioning checks passed",
    ]
    body = []
    for (env_id, algo), runs in sorted(zoo_runs(directory).items()):
        metas = [
            json.loads(steamtemp_files(directory, env_id, algo, k).meta[0].read_text())
            for k in runs
        ]
        plant, kind = env_id.split("/")[-1], agents.kind(algo)
        if "timesteps_trained" not in metas[0]:  # an offline clone
            t = [m["training"] for m in metas]
            body.append(
                [
                    plant,
                    f"sb3:{algo}",
                    kind,
                    str(len(runs)),
                    f"offline: {span([x['transitions'] / 1e3 for x in t], '{:.0f}')}k "
                    f"transitions x {span([x['epochs'] for x in t], '{:d}')} epochs",
                    "-",
                    span([x["seconds"] / 60 for x in t], "{:.1f}"),
                    "-",
                    "-",
                    "-",
                ]
            )
            continue
        v = [m["validation"] for m in metas]
        checked = [x["best"]["check"] for x in v if "check" in x["best"]]
        body.append(
            [
                plant,
                f"sb3:{algo}",
                kind,
                str(len(runs)),
                span([m["timesteps_trained"] / 1e6 for m in metas], "{:.2f}") + "M",
                span([m["timesteps_of_best"] / 1e6 for m in metas], "{:.2f}") + "M",
                span([m["wall_time_s"] / 60 for m in metas], "{:.1f}"),
                span([x["best"]["return"] for x in v], "{:.1f}")
                + f" ({span([x['reference']['return'] for x in v], '{:.1f}')})",
                span([x["best"]["travel_ratio"] for x in v], "{:.2f}") + "x",
                f"{sum(not c for c in checked)} of {len(v)} runs" if checked else "-",
            ]
        )
    return "\n".join(table_lines(header, body)) + "\n"


def baselines_markdown(summary: dict[str, Any]) -> str:
    """Every baseline on every plant: mean IAE of the main steam, valve travel relative to
    the reference's and valve reversals, over scenario x seed (the actuator columns of
    docs/baselines.md's valve-activity table); † = not admissible."""
    plants = list(summary["plants"])
    header = [
        "baseline",
        *[f"{p.split('/')[-1]}: IAE [K s] / travel / reversals / rejected" for p in plants],
    ]
    body = []
    limit = budget(summary)
    for name in baselines.NAMES:
        cells = []
        for env_id in plants:
            pe = summary["plants"][env_id]["policies"].get(name)
            if pe is None:
                cells.append("-")
                continue
            met = pe["metrics"]
            mark = f" {INADMISSIBLE}" if pe.get("admissible") is False else ""
            cells.append(
                f"{num(met.get('iae_K_s'), 0)} / {travel_cell(pe, limit)} / "
                f"{num(met.get('valve_reversals'), 0)} / "
                f"{rejected_cell(pe)}{mark}"
            )
        if any(c != "-" for c in cells):
            body.append([f"`{name}`", *cells])
    n = len(summary["run"]["seeds"])
    lines = [
        f"Means over scenario × seed ({n} seeds); {admissibility_note(summary)[:-1]}; "
        f"{rejected_note()}",
        "",
    ]
    return "\n".join(lines + table_lines(header, body)) + "\n"


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
            rows.append(
                [
                    f"`{name}`",
                    env_id.split("/")[-1],
                    f"{r['breaches']}/{r['episodes']}",
                    listed + more,
                ]
            )
    n = len(summary["run"]["seeds"])
    head = (
        f"Over every scenario and seed ({n} seeds) of the run, {clean} of "
        f"{clean + len(rows)} baseline-plant pairs have no episode a plant engineer would "
        f"reject against `cascade_pi_ff`'s on the same scenario and seed (a trip, valve "
        f"travel above {num(stats.REALISM_TRAVEL_MAX, 0)}x, or a limit cycle in the quiet "
        f"stretch: the quiet peak-to-peak above max(2x the reference's, 1.5 K))."
    )
    if not rows:
        return head + "\n"
    return (
        "\n".join(
            [
                head + " The others:",
                "",
                *table_lines(["baseline", "plant", "rejected", "first episodes"], rows),
            ]
        )
        + "\n"
    )


#: The columns of :func:`comparison_markdown`, in order.
COMPARISON_METRICS = ("return", "iae_K_s", "valve_travel", "quiet_p2p_K")


def comparison_markdown(summary: dict[str, Any], policies: list[str]) -> str:
    """Per plant and scenario, the mean over seeds of the return, IAE, valve travel and
    quiet peak-to-peak of each of ``policies``, side by side (``a / b / c`` per cell; "-"
    where a policy was not run or a metric does not apply)."""
    n = len(summary["run"]["seeds"])
    lines = [
        f"Means over seeds ({n} seeds); each cell is {' / '.join(policies)}; quiet "
        "p2p: the main-steam error's peak-to-peak over the quiet stretch after the "
        "scenario's last scheduled change (- where it does not apply).",
        "",
    ]
    header = ["scenario", *(COLUMNS[m][0] for m in COMPARISON_METRICS)]
    for env_id, plant in summary["plants"].items():
        body = []
        for sc, cells in plant["scenarios"].items():
            body.append(
                [
                    sc,
                    *(
                        " / ".join(cell(m, cells.get(p, {}).get(m)) for p in policies)
                        for m in COMPARISON_METRICS
                    ),
                ]
            )
        lines += [f"#### {env_id.split('/')[-1]}", "", *table_lines(header, body), ""]
    return "\n".join(lines)
