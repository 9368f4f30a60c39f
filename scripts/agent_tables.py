"""The table per plant of the trained agents of a leaderboard run, with the baselines they
are measured against: score IQM [95 % CI] over every run's episodes, each run's IQM, the
IQM on the named and on the held-out scenarios, valve travel against ``cascade_pi_ff``'s,
the episodes rejected for realism, and what each run trained on (decisions, CPU minutes).

    python scripts/agent_tables.py --run leaderboard_out [--baselines mpc_linear,...]
        [--write docs/agents/plant_scale.md]

``--run``: a steamtemp-leaderboard output directory (leaderboard.json, episodes.jsonl).
Agents: every policy with training runs there (``sb3:<algo>``, or a trained agent's files
named by path); their metadata (the ``.json`` beside each model, or the shipped zoo's)
gives the decisions and CPU time of each run. Named and held-out IQMs use the run's own
score ends per scenario (the means over seeds of ``cascade_pi_ff`` and the oracle), as the
leaderboard does. With ``--write`` the tables replace what stands between the page's
``<!-- agent-tables:start -->`` and ``<!-- agent-tables:end -->`` markers.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

import agents
from agents import specs, stats
from agents.files import parse_stem, steamtemp_files
from agents.leaderboard.records import EPISODES, read_record
from steamtemp_gym.scenarios import heldout

START, END = "<!-- agent-tables:start -->", "<!-- agent-tables:end -->"
ZERO, ONE = "cascade_pi_ff", "oracle"


def episode_scores(run: Path) -> dict[tuple[str, str], list[tuple[str, float]]]:
    """Per (plant, policy as scored), every episode's (scenario, normalized score)."""
    rows = [r for r in read_record(run / EPISODES) if not r.get("error") and "variant" not in r]
    ends: dict[tuple[str, str, str], list[float]] = defaultdict(list)
    for r in rows:
        if r["policy"] in (ZERO, ONE):
            ends[r["env"], r["scenario"], r["policy"]].append(r["metrics"]["return"])
    out: dict[tuple[str, str], list[tuple[str, float]]] = defaultdict(list)
    for r in rows:
        zero = ends.get((r["env"], r["scenario"], ZERO))
        one = ends.get((r["env"], r["scenario"], ONE))
        if zero and one:
            s = stats.normalize([r["metrics"]["return"]], np.mean(zero), np.mean(one))[0]
            out[r["env"], r["policy"]].append((r["scenario"], float(s)))
    return out


def _iqm(scores: list[float]) -> str:
    return f"{stats.iqm(np.array(scores)):.2f}" if scores else "-"


def run_records(env_id: str, policy: str, runs: list[int]) -> list[dict]:
    """The metadata of each training run of ``policy`` on ``env_id``."""
    out = []
    for k in runs:
        if policy.startswith(specs.SB3_PREFIX):
            f = steamtemp_files(agents.ZOO, env_id, policy[len(specs.SB3_PREFIX) :], k).meta[0]
        else:
            f = Path(policy).with_suffix(".json")
        out.append(json.loads(f.read_text(encoding="utf-8")) if f.is_file() else {})
    return out


def plant_table(env_id: str, plant: dict, scores: dict, baselines: list[str]) -> list[str]:
    """The markdown table of one plant."""
    lines = [
        f"**{env_id.split('/')[-1]}**",
        "",
        "| policy | score IQM [95 % CI] | per run | named / held-out | travel | rejected "
        "| decisions per run | CPU min per run |",
        "|---|---|---|---|---|---|---|---|",
    ]
    pols = plant["policies"]
    trained = [p for p in pols if "training_runs" in pols[p] or p.endswith(".zip")]
    for p in [b for b in baselines if b in pols] + trained:
        e = pols[p]
        iqm = e.get("normalized_score", {}).get("iqm", {})
        if not iqm:
            continue
        lo, hi = iqm["ci95"]
        names = (
            [p] if "training_runs" not in e else [specs.run_name(p, k) for k in e["training_runs"]]
        )
        if len(names) > 1 or names[0] != p:
            pooled = [x for n in names for x in scores.get((env_id, n), [])]
        else:
            pooled = scores.get((env_id, p), [])
        named = [s for sc, s in pooled if not sc.startswith(heldout.PREFIX)]
        held = [s for sc, s in pooled if sc.startswith(heldout.PREFIX)]
        per_run = " / ".join(f"{v:.2f}" for v in iqm.get("per_run", [])) or "-"
        breaches = e.get("realism", {}).get("breaches", 0)
        trips = e.get("trips", 0)
        rejected = f"{breaches + trips} of {e['episodes']}"
        decisions = cpu = "-"
        if p in trained:
            meta = run_records(env_id, p, e.get("training_runs", [0]))
            steps = [m["timesteps_trained"] for m in meta if "timesteps_trained" in m]
            mins = [
                m.get("cpu_time_s", m.get("wall_time_s", 0.0)) / 60
                for m in meta
                if "timesteps_trained" in m
            ]
            decisions = " / ".join(f"{s / 1e6:.1f}M" for s in steps) or "-"
            cpu = " / ".join(f"{m:.0f}" for m in mins) or "-"
        shown = p
        if p.endswith(".zip"):  # a run's files: its algo, run and directory
            _, algo, k = parse_stem(Path(p).stem)
            shown = f"{algo} run{k or 0} ({Path(p).parent.name})"
        lines.append(
            f"| `{shown}` | {iqm['value']:.2f} [{lo:.2f}, {hi:.2f}] | {per_run} | "
            f"{_iqm(named)} / {_iqm(held)} | {e.get('travel_ratio', float('nan')):.2f}x | "
            f"{rejected} | {decisions} | {cpu} |"
        )
    return lines


def tables(run: Path, baselines: list[str]) -> str:
    doc = json.loads((run / "leaderboard.json").read_text(encoding="utf-8"))
    scores = episode_scores(run)
    out: list[str] = []
    for env_id, plant in doc["plants"].items():
        out += plant_table(env_id, plant, scores, baselines) + [""]
    return "\n".join(out).rstrip("\n") + "\n"


def write(page: Path, text: str) -> None:
    """Replace the page's text between the markers by ``text``."""
    body = page.read_text(encoding="utf-8")
    if START not in body or END not in body:
        raise ValueError(f"{page}: no {START} ... {END} markers")
    head, rest = body.split(START, 1)
    tail = rest.split(END, 1)[1]
    page.write_text(f"{head}{START}\n{text}{END}{tail}", encoding="utf-8")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--run", type=Path, required=True, help="a leaderboard output directory")
    ap.add_argument("--baselines", default="mpc_linear,cascade_pi_ff_tuned")
    ap.add_argument("--write", type=Path, default=None, help="a page with the markers")
    args = ap.parse_args(argv)
    if not (args.run / "leaderboard.json").is_file():
        ap.error(f"--run {args.run}: no leaderboard.json there")
    text = tables(args.run, [b for b in args.baselines.split(",") if b])
    if args.write is None:
        sys.stdout.write(text)
        return 0
    try:
        write(args.write, text)
    except ValueError as exc:
        ap.error(str(exc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
